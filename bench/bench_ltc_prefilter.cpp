// LTC normal-map prefilter benchmarks (ltc-filtering.md §5.2 "cost at the thesis configuration"): fitting a 128² map
// at MIPs 1..7 with 8×16 specular + 2×4 diffuse views (thesis: ~4 h on a GPU, 26.7 MB), and the runtime lookup.
#include "core/ltc/ltc_prefilter.h"
#include "core/ltc/ltc_tables.h"
#include "core/texture/normal_map_gen.h"

#include <benchmark/benchmark.h>

#include <tbb/info.h>

#include <chrono>

using namespace specula;
using namespace specula::ltc;

namespace {

std::vector<Vec3> stone(int size) { return NormalMapLtcPrefilter::normalsOf(generateNormalMap(NormalMapKind::Stone, size, 1)); }

// One full prefilter per iteration (no cache). Counters: storage (bytes of the fitted tables), fits, µs per fit of
// wall time, and the threads TBB may use.
void BM_LtcPrefilter(benchmark::State& st) {
    const int size = int(st.range(0));
    const std::vector<Vec3> n = stone(size);
    PrefilterSettings s;  // thesis configuration: α = 0.1, 8×16 + 2×4 views, 256 samples, 30 t-EM iterations
    builtinTables();      // built once, outside the timing
    size_t bytes = 0;
    double seconds = 0;
    for (auto _ : st) {
        const auto t0 = std::chrono::steady_clock::now();
        NormalMapLtcPrefilter p = NormalMapLtcPrefilter::build(n, size, s);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        bytes = p.storageBytes();
        benchmark::DoNotOptimize(p.specRecords().data());
    }
    const double texels = double(size * size - 1) / 3.0;  // levels 1..log2(size)
    const double fits = texels * (s.specTheta * s.specPhi + s.diffTheta * s.diffPhi);
    st.counters["storage_bytes"] = double(bytes);
    st.counters["fits"] = fits;
    st.counters["us_per_fit"] = seconds * 1e6 / (fits * double(st.iterations()));  // wall time, all threads
    st.counters["threads"] = double(tbb::info::default_concurrency());
}
BENCHMARK(BM_LtcPrefilter)->Arg(32)->Arg(128)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// The runtime lookup (both lobes) at a footprint between levels 2 and 3 (trilinear: 2 levels × 4 texels × 4 views).
void BM_LtcPrefilterLookup(benchmark::State& st) {
    static const NormalMapLtcPrefilter p = NormalMapLtcPrefilter::build(stone(32), 32, PrefilterSettings{});
    const LtcTables& t = builtinTables();
    const float d = float(st.range(0)) / 32.f;
    int i = 0;
    float acc = 0;
    for (auto _ : st) {
        const Vec2 uv(float((i * 7919) % 10007) / 10007.f, float((i * 104729) % 10009) / 10009.f);
        const float th = 0.1f + 1.3f * float(i % 97) / 97.f, ph = 6.28f * float(i % 89) / 89.f;
        ++i;
        LtcPair l = p.lookup(uv, Vec2(d, 0), Vec2(0, d), Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)), t);
        acc += l.spec.magnitude + l.diffuse.invM[0][0];
    }
    benchmark::DoNotOptimize(acc);
}
BENCHMARK(BM_LtcPrefilterLookup)->Arg(0)->Arg(1)->Arg(6);

}  // namespace

BENCHMARK_MAIN();
