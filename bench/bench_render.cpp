// End-to-end render timings of the anchor scene (examples/anchor-sphere.json) at 1 and 64 spp, path
// tracing on all cores: scene load + BVH build + rendering, without process start-up or image writing,
// i.e. what shared/anchors times for Cycles as "blender_cycles_*_render".
#include "core/api/specula.h"

#include <benchmark/benchmark.h>

using namespace specula;

static void BM_AnchorSphere(benchmark::State& state) {
    const int spp = int(state.range(0));
    const std::string path = std::string(SPECULA_SOURCE_DIR) + "/examples/anchor-sphere.json";
    uint64_t samples = 0;
    for (auto _ : state) {
        SceneOverrides ov;
        ov.spp = spp;
        Scene scene = loadScene(path, ov);
        RenderOutput out = renderScene(scene);
        samples += out.stats.samples;
        benchmark::DoNotOptimize(out.images.aovs[0].pixels.data());
    }
    state.counters["samples_per_second"] = benchmark::Counter(double(samples), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_AnchorSphere)->Arg(1)->Arg(64)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1)->Repetitions(3)
    ->ReportAggregatesOnly(false);

BENCHMARK_MAIN();
