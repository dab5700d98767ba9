// Graph-evaluator overhead: a GGX material built from a node graph (shade + eval through the compiled
// program) against a direct C++ GgxLobe with the same parameters, in one run; prints the ratio.
#include "core/graph/graph_material.h"
#include "core/render/lobes/ggx.h"

#include "bench/ratio_reporter.h"

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <map>
#include <vector>

using namespace specula;

namespace {

struct Setup {
    std::shared_ptr<Material> mat;
    std::vector<Vec3> dirs;
    Setup() {
        nlohmann::json m = {{"nodes",
                             {{"spec",
                               {{"type", "bsdf.ggx"},
                                {"inputs", {{"roughness", 0.3}, {"anisotropy", 0.4}, {"f0", {0.95, 0.64, 0.54}}}}}}}},
                            {"output", "@spec.bsdf"}};
        mat = loadGraphMaterial(m, "/materials/bench", GraphLoadContext{});
        for (int i = 0; i < 64; ++i) {
            float a = 0.1f * i, b = 0.37f * i;
            dirs.push_back(glm::normalize(Vec3(0.6f * std::cos(a), 0.6f * std::sin(b), 1.f)));
        }
    }
};
Setup& setup() {
    static Setup s;
    return s;
}

ShadingPoint point() {
    ShadingPoint sp;
    sp.n = sp.ng = glm::normalize(Vec3(0.1f, 0.2f, 1.f));
    sp.tangent = Vec4(1, 0, 0, 1);
    return sp;
}

void BM_GgxGraph(benchmark::State& state) {
    Setup& s = setup();
    ScratchArena arena;
    Closure cl;
    ShadingPoint sp = point();
    size_t k = 0;
    for (auto _ : state) {
        s.mat->shade(sp, arena, cl);
        BsdfEval e = cl.evalPdf({s.dirs[k & 63], s.dirs[(k * 7 + 3) & 63]}).f;
        benchmark::DoNotOptimize(e);
        arena.reset();
        ++k;
    }
}

// A hand-written material stores roughness/anisotropy/F0 and maps them per shading point, as the node does.
struct HandWritten {
    float roughness = 0.3f, anisotropy = 0.4f;
    Color3 f0{0.95f, 0.64f, 0.54f};
    void build(const ShadingPoint& sp, ScratchArena& arena, Closure& cl) {
        benchmark::DoNotOptimize(roughness);
        benchmark::DoNotOptimize(anisotropy);
        float alpha = roughness * roughness, aspect = std::sqrt(std::max(1.f - 0.9f * anisotropy, 0.f));
        Vec3 n = glm::normalize(sp.n);
        Frame frame = Frame::fromNormalTangent(n, Vec3(sp.tangent));
        cl.clear();
        cl.add(Color3(1.f), arena.make<GgxLobe>(alpha / aspect, alpha * aspect, Fresnel::schlick(f0)), frame);
    }
};

void BM_GgxDirect(benchmark::State& state) {
    Setup& s = setup();
    ScratchArena arena;
    Closure cl;
    ShadingPoint sp = point();
    HandWritten m;
    size_t k = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(sp);
        m.build(sp, arena, cl);
        BsdfEval e = cl.evalPdf({s.dirs[k & 63], s.dirs[(k * 7 + 3) & 63]}).f;
        benchmark::DoNotOptimize(e);
        arena.reset();
        ++k;
    }
}

// The two halves apart: building the closure (the graph's shade against the hand-written lobe set-up), without eval.
void BM_ShadeOnly(benchmark::State& state) {
    Setup& s = setup();
    ScratchArena arena;
    Closure cl;
    ShadingPoint sp = point();
    for (auto _ : state) {
        s.mat->shade(sp, arena, cl);
        benchmark::DoNotOptimize(cl);
        arena.reset();
    }
}
void BM_BuildOnly(benchmark::State& state) {
    ScratchArena arena;
    Closure cl;
    ShadingPoint sp = point();
    HandWritten m;
    for (auto _ : state) {
        benchmark::DoNotOptimize(sp);
        m.build(sp, arena, cl);
        benchmark::DoNotOptimize(cl);
        arena.reset();
    }
}
// Batches of 32 shading points (issue 37: the renderer's camera stage shades a tile row at once): the graph's
// Program::shadeBatch against the hand-written set-up in the same loop shape, then one evaluation per point.
constexpr size_t kBatch = 32;
struct Batch {
    std::vector<ShadingPoint> sps;
    std::vector<const ShadingPoint*> ptrs;
    std::vector<Closure> closures = std::vector<Closure>(kBatch);
    std::vector<Closure*> outs;
    Batch() {
        for (size_t k = 0; k < kBatch; ++k) {
            ShadingPoint sp = point();
            sp.n = sp.ng = glm::normalize(Vec3(0.1f + 0.01f * float(k), 0.2f - 0.005f * float(k), 1.f));
            sps.push_back(sp);
        }
        for (size_t k = 0; k < kBatch; ++k) {
            ptrs.push_back(&sps[k]);
            outs.push_back(&closures[k]);
        }
    }
};
void BM_GgxGraphBatch(benchmark::State& state) {
    Setup& s = setup();
    ScratchArena arena;
    Batch b;
    size_t k = 0;
    for (auto _ : state) {
        s.mat->shadeBatch(b.ptrs.data(), kBatch, arena, b.outs.data());
        for (size_t i = 0; i < kBatch; ++i, ++k) {
            BsdfEval e = b.closures[i].evalPdf({s.dirs[k & 63], s.dirs[(k * 7 + 3) & 63]}).f;
            benchmark::DoNotOptimize(e);
        }
        arena.reset();
    }
}
void BM_GgxDirectBatch(benchmark::State& state) {
    Setup& s = setup();
    ScratchArena arena;
    Batch b;
    HandWritten m;
    size_t k = 0;
    for (auto _ : state) {
        for (size_t i = 0; i < kBatch; ++i) {
            benchmark::DoNotOptimize(b.sps[i]);
            m.build(b.sps[i], arena, b.closures[i]);
        }
        for (size_t i = 0; i < kBatch; ++i, ++k) {
            BsdfEval e = b.closures[i].evalPdf({s.dirs[k & 63], s.dirs[(k * 7 + 3) & 63]}).f;
            benchmark::DoNotOptimize(e);
        }
        arena.reset();
    }
}
BENCHMARK(BM_GgxDirectBatch)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_GgxGraphBatch)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_ShadeOnly)->Repetitions(3)->ReportAggregatesOnly(true);
BENCHMARK(BM_BuildOnly)->Repetitions(3)->ReportAggregatesOnly(true);
BENCHMARK(BM_GgxDirect)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_GgxGraph)->Repetitions(5)->ReportAggregatesOnly(true);


}  // namespace

int main(int argc, char** argv) {
    return specula::bench::runWithRatios(argc, argv, [](specula::bench::RatioReporter& rep) {
        if (rep.medianNs.count("BM_ShadeOnly") && rep.medianNs.count("BM_BuildOnly"))
            std::printf("closure building alone: graph shade %.2f ns / hand-written %.2f ns = ratio %.3f\n",
                        rep.medianNs["BM_ShadeOnly"], rep.medianNs["BM_BuildOnly"],
                        rep.medianNs["BM_ShadeOnly"] / rep.medianNs["BM_BuildOnly"]);
        if (rep.medianNs.count("BM_GgxGraph") && rep.medianNs.count("BM_GgxDirect")) {
            double g = rep.medianNs["BM_GgxGraph"], d = rep.medianNs["BM_GgxDirect"];
            std::printf("graph/direct GGX (shade+eval) median: %.2f ns / %.2f ns = ratio %.3f (overhead %+.1f%%, "
                        "target <= +10%%)\n", g, d, g / d, (g / d - 1.0) * 100.0);
        }
        if (rep.medianNs.count("BM_GgxGraphBatch") && rep.medianNs.count("BM_GgxDirectBatch")) {
            double g = rep.medianNs["BM_GgxGraphBatch"] / kBatch, d = rep.medianNs["BM_GgxDirectBatch"] / kBatch;
            std::printf("batched graph/direct GGX (shade+eval, %zu points per batch) median per point: %.2f ns / %.2f ns "
                        "= ratio %.3f (overhead %+.1f%%, target <= +10%%)\n", kBatch, g, d, g / d, (g / d - 1.0) * 100.0);
        }
    });
}
