// Cost of the glint quad-light integral (issue 11 item 2, nodes/bsdf/glint/glint_area.h) per query, for small,
// medium and large lights, beside one point evaluation of the same lobe (what one light sample costs).
#include "nodes/bsdf/glint/glint_area.h"

#include <benchmark/benchmark.h>

#include <cmath>

using namespace specula;
using namespace specula::glint;

namespace {

struct Setup {
    GlintParams p;
    GlintShape shape;
    GlintEvalInputs in;
    Vec3 wo, wi;
    Vec3 quad[4];
};

// A quad of the given angular size centred on the mirror direction of wo, 2 units away; footprint |duv| 2e-3.
Setup makeSetup(float angle) {
    Setup s;
    s.p.sigmaX = s.p.sigmaY = 0.2f;
    s.p.logDensity = 13.f;
    s.p.ggaa = false;
    s.shape = GlintShape::make(s.p.sigmaX, s.p.sigmaY, s.p.rho);
    s.in.uv = Vec2(0.31f, 0.62f);
    s.in.duvdx = Vec2(2e-3f, 0.f);
    s.in.duvdy = Vec2(0.f, 1e-3f);
    s.wo = glm::normalize(Vec3(0.4f, 0.1f, 0.9f));
    s.wi = Vec3(-s.wo.x, -s.wo.y, s.wo.z);
    const Vec3 c = s.wi * 2.f, n = -s.wi;
    const Vec3 t = glm::normalize(glm::cross(Vec3(0, 0, 1), n)), b = glm::cross(n, t);
    const float h = 2.f * std::tan(0.5f * angle);
    s.quad[0] = c - h * t - h * b, s.quad[1] = c - h * t + h * b, s.quad[2] = c + h * t + h * b, s.quad[3] = c + h * t - h * b;
    GlintAreaResult r;
    if (!glintPolygonIntegral(Dictionary::instance(), s.p, s.shape, s.in, s.wo, s.quad, 4, r))
        std::swap(s.quad[1], s.quad[3]);  // orient counter-clockwise as seen from the shading point
    return s;
}

void BM_GlintQuadIntegral(benchmark::State& state) {
    const Setup s = makeSetup(float(state.range(0)) / 1000.f);
    const Dictionary& dict = Dictionary::instance();
    int cells = 0;
    for (auto _ : state) {
        GlintAreaResult r;
        glintPolygonIntegral(dict, s.p, s.shape, s.in, s.wo, s.quad, 4, r);
        benchmark::DoNotOptimize(r.integral);
        cells = r.cells;
    }
    state.counters["cells"] = cells;
}
BENCHMARK(BM_GlintQuadIntegral)->Arg(30)->Arg(200)->Arg(800)->ArgName("angle_mrad");

// One shadow-ray direction after the integral of the same query (the integrator's order): the recorded cells are reused.
void BM_GlintQuadSampleAfterIntegral(benchmark::State& state) {
    const Setup s = makeSetup(float(state.range(0)) / 1000.f);
    const Dictionary& dict = Dictionary::instance();
    GlintAreaResult r;
    glintPolygonIntegral(dict, s.p, s.shape, s.in, s.wo, s.quad, 4, r);
    uint64_t seed = 1;
    for (auto _ : state) {
        Vec3 wi;
        const Vec2 u(float((seed * 0x9E3779B9u) & 0xffff) / 65536.f, float((seed * 0x85EBCA6Bu) & 0xffff) / 65536.f);
        benchmark::DoNotOptimize(glintSamplePolygonByCells(dict, s.p, s.shape, s.in, s.wo, s.quad, 4, u, seed++, wi));
        benchmark::DoNotOptimize(wi);
    }
}
BENCHMARK(BM_GlintQuadSampleAfterIntegral)->Arg(30)->Arg(200)->Arg(800)->ArgName("angle_mrad");

void BM_GlintPointEvaluation(benchmark::State& state) {
    const Setup s = makeSetup(0.2f);
    const Dictionary& dict = Dictionary::instance();
    for (auto _ : state) benchmark::DoNotOptimize(glintFCosScalar(dict, s.p, s.shape, s.in, s.wo, s.wi));
}
BENCHMARK(BM_GlintPointEvaluation);

}  // namespace

BENCHMARK_MAIN();
