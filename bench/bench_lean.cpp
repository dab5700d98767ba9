// LEAN mapping micro-benchmarks: cost of a footprint-filtered LEAN moment lookup (+ statistics) against a plain
// normal-map lookup through TextureStore/OIIO and a plain bilinear fetch, and the memory of a map's moment pyramid.
#include "core/color/color_config.h"
#include "core/texture/lean_moments.h"
#include "core/texture/normal_map_gen.h"
#include "core/texture/texture_store.h"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

using namespace specula;

namespace {

struct Fixture {
    std::unique_ptr<TextureStore> store;
    TextureHandle tex;
    LeanPyramid pyramid;
    NormalMap map;
};

Fixture& fixture() {
    static Fixture f = [] {
        Fixture x;
        x.map = generateNormalMap(NormalMapKind::Brushed, 1024, 1);
        std::string dir = (std::filesystem::temp_directory_path() / "specula-bench-lean").string();
        std::filesystem::create_directories(dir);
        writeNormalMap(x.map, dir + "/brushed1024.exr");
        x.store = std::make_unique<TextureStore>(ColorConfig::load("builtin"));
        x.tex = x.store->load(dir + "/brushed1024.exr", "raw");
        const auto& px = x.store->pixels(x.tex);
        x.pyramid = LeanPyramid::fromEncodedPixels(px.data(), 1024, 1024, 3, false);
        return x;
    }();
    return f;
}

// Footprints: range(0) = texels per pixel along u (minor axis 1/4 of it for the anisotropic case).
Vec2 uvAt(int i) { return Vec2(float((i * 7919) % 10007) / 10007.f, float((i * 104729) % 10009) / 10009.f); }

void BM_NormalMapTextureStore(benchmark::State& st) {
    Fixture& f = fixture();
    float t = float(st.range(0)) / 1024.f;
    int i = 0;
    float acc = 0;
    for (auto _ : st) {
        float c[3];
        f.store->sample(f.tex, uvAt(i++), Vec2(t, 0), Vec2(0, t * 0.25f), c, 3);
        acc += c[0];
    }
    benchmark::DoNotOptimize(acc);
}
BENCHMARK(BM_NormalMapTextureStore)->Arg(1)->Arg(8)->Arg(64);

void BM_LeanLookup(benchmark::State& st, LeanFilter filter) {
    Fixture& f = fixture();
    float t = float(st.range(0)) / 1024.f;
    int i = 0;
    float acc = 0;
    for (auto _ : st) {
        LeanStats s = leanStats(f.pyramid.lookup(uvAt(i++), Vec2(t, 0), Vec2(0, t * 0.25f), filter));
        acc += s.rho + s.varX;
    }
    benchmark::DoNotOptimize(acc);
}
BENCHMARK_CAPTURE(BM_LeanLookup, none, LeanFilter::None)->Arg(1);
BENCHMARK_CAPTURE(BM_LeanLookup, trilinear, LeanFilter::Trilinear)->Arg(1)->Arg(8)->Arg(64);
BENCHMARK_CAPTURE(BM_LeanLookup, anisotropic, LeanFilter::Anisotropic)->Arg(1)->Arg(8)->Arg(64);

void BM_LeanBuildPyramid(benchmark::State& st) {
    Fixture& f = fixture();
    const auto& px = f.store->pixels(f.tex);
    for (auto _ : st) benchmark::DoNotOptimize(LeanPyramid::fromEncodedPixels(px.data(), 1024, 1024, 3, false));
    LeanPyramid P = LeanPyramid::fromEncodedPixels(px.data(), 1024, 1024, 3, false);
    st.counters["lean_bytes"] = double(P.memoryBytes());
    st.counters["lean_base_bytes"] = double(P.baseBytes());
    size_t gl = 0;
    for (int l = 0; l < P.glslLevels(); ++l) gl += P.glslPackedLevel(l).size() * sizeof(float);
    st.counters["lean_glsl_bytes"] = double(gl);
    // A float RGB normal map with its MIP chain (what TextureStore keeps as a .tx): 12 B/texel * 4/3.
    st.counters["normalmap_float_mip_bytes"] = double(1024 * 1024 * 12) * 4.0 / 3.0;
}
BENCHMARK(BM_LeanBuildPyramid)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
