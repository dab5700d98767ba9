// Scene loading time of a material with a long chain of nodes (issue 35): the structure check of the scene JSON
// (duplicate keys, depth; scene_loader.cpp's SAX pass) is linear in an object's member count (the callback parser it
// replaced took 2.4 s for 20,000 nodes and minutes for 100,000). 100,000 nodes are refused for the node limit after
// the parse, as SceneParsing.ChainedGraphOfHundredThousandNodesIsReadInLinearTime asserts.
//
// Run: bench_scene_load (a few seconds). Measured 2026-12-07 (2-core shared VM): 20,000 nodes loaded and built
// 221 ms; 100,000 nodes parsed, checked and refused 375 ms.
#include "core/scene/scene_loader.h"
#include "core/util/error.h"

#include <benchmark/benchmark.h>

#include <string>

using namespace specula;

namespace {

// A scene whose one material is a chain of `links` math.mul.float nodes feeding a GGX roughness.
std::string chainScene(int links) {
    std::string nodes = R"("c0": {"type": "math.mul.float", "inputs": {"a": 0.3, "b": 1.0}})";
    for (int i = 1; i < links; ++i)
        nodes += ", \"c" + std::to_string(i) + R"(": {"type": "math.mul.float", "inputs": {"a": "@c)" +
                 std::to_string(i - 1) + R"(.out", "b": 1.0}})";
    nodes += R"(, "s": {"type": "bsdf.ggx", "inputs": {"roughness": "@c)" + std::to_string(links - 1) + R"(.out"}})";
    return R"({"version": 1, "camera": {"position": [0, -5, 1], "look_at": [0, 0, 1]}, "materials": {"m": {"nodes": {)" + nodes +
           R"(}, "output": "@s.bsdf"}}, "shapes": [{"type": "sphere", "material": "m"}]})";
}

void BM_LoadChainedGraph(benchmark::State& state) {
    const int links = int(state.range(0));
    const std::string text = chainScene(links);
    int refused = 0;
    for (auto _ : state) {
        try {
            Scene s = loadSceneFromString(text, ".");
            benchmark::DoNotOptimize(&s);
        } catch (const InputError&) {
            ++refused;  // over the node limit (65,536): refused after the whole text was parsed and checked
        }
    }
    state.counters["refused"] = double(refused) / double(state.iterations());
    state.SetItemsProcessed(int64_t(state.iterations()) * links);
}
BENCHMARK(BM_LoadChainedGraph)->Arg(20000)->Arg(100000)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
