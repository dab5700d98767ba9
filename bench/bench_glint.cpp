// Glint BRDF CPU cost (nodes/bsdf/glint): eval with GGAA off and on against GGX on identical inputs in one run, the
// GGAA overhead (C21 Table 1 reports 0.6-4.2 % on a GPU; spec §4.11 budget ~10 %), and dictionary/pyramid memory.
#include "core/render/lobes/ggx.h"
#include "nodes/bsdf/glint/glint_bsdf.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

using namespace specula;
using namespace specula::glint;

namespace {

struct Case {
    Vec3 wo, wi;
    GlintEvalInputs in;
};

// Pixel-like configurations: a 1080p camera over a unit-UV plane (footprint ~1e-3 UV), curvature-like frame
// rotation per pixel, directions around the mirror configuration so the glint cells are exercised.
const std::vector<Case>& cases() {
    static std::vector<Case> c = [] {
        std::vector<Case> v;
        std::mt19937 rng(17);
        std::uniform_real_distribution<float> u(0.f, 1.f);
        for (int n = 0; n < 4096; ++n) {
            Case k;
            k.wo = glm::normalize(Vec3(u(rng) - 0.5f, u(rng) - 0.5f, 1.f));
            Vec3 m = glm::normalize(Vec3(0.4f * (u(rng) - 0.5f), 0.4f * (u(rng) - 0.5f), 1.f));
            k.wi = 2.f * glm::dot(k.wo, m) * m - k.wo;
            if (k.wi.z <= 0.f) k.wi = Vec3(-k.wo.x, -k.wo.y, k.wo.z);
            k.in.uv = Vec2(u(rng), u(rng));
            float s = 1e-3f * (0.5f + u(rng));
            k.in.duvdx = Vec2(s, 0.2f * s * (u(rng) - 0.5f));
            k.in.duvdy = Vec2(0.3f * s * (u(rng) - 0.5f), s * (0.5f + u(rng)));
            k.in.diff.dnx = Vec2(0.02f * u(rng), 0.01f * (u(rng) - 0.5f));
            k.in.diff.dny = Vec2(0.01f * (u(rng) - 0.5f), 0.02f * u(rng));
            v.push_back(k);
        }
        return v;
    }();
    return c;
}

GlintParams params(bool ggaa) {
    GlintParams p;
    p.logDensity = 15.f;   // C21 demo
    p.sigmaX = p.sigmaY = 0.16f;
    p.relArea = 1.f;
    p.maxAniso = 8.f;
    p.ggaa = ggaa;
    return p;
}

float runGlint(bool ggaa, size_t& i) {
    static const Dictionary& d = Dictionary::instance();
    const GlintParams p = params(ggaa);
    const GlintShape shape = GlintShape::make(p.sigmaX, p.sigmaY, p.rho);
    const Case& k = cases()[i++ & 4095];
    return glintFCosScalar(d, p, shape, k.in, k.wo, k.wi);
}

float runGgx(size_t& i) {
    static const GgxLobe lobe(0.2263f, 0.2263f, Fresnel::one());  // alpha = sqrt(2) sigma
    const Case& k = cases()[i++ & 4095];
    return lobe.eval(k.wo, k.wi).x;
}

void BM_Ggx(benchmark::State& st) {
    size_t i = 0;
    for (auto _ : st) benchmark::DoNotOptimize(runGgx(i));
}
void BM_GlintNoGgaa(benchmark::State& st) {
    size_t i = 0;
    for (auto _ : st) benchmark::DoNotOptimize(runGlint(false, i));
}
void BM_GlintGgaa(benchmark::State& st) {
    size_t i = 0;
    for (auto _ : st) benchmark::DoNotOptimize(runGlint(true, i));
}
BENCHMARK(BM_Ggx);
BENCHMARK(BM_GlintNoGgaa);
BENCHMARK(BM_GlintGgaa);

// Interleaved min-of-rounds timing (robust on a shared 2-core machine): ns per eval of each variant.
void summary() {
    Dictionary::instance();
    auto time = [](auto&& fn) {
        const int n = 4096 * 8;
        auto t0 = std::chrono::steady_clock::now();
        float acc = 0;
        size_t i = 0;
        for (int j = 0; j < n; ++j) acc += fn(i);
        benchmark::DoNotOptimize(acc);
        return std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() / n;
    };
    double best[3] = {1e30, 1e30, 1e30};
    for (int r = 0; r < 15; ++r) {
        best[0] = std::min(best[0], time([](size_t& i) { return runGgx(i); }));
        best[1] = std::min(best[1], time([](size_t& i) { return runGlint(false, i); }));
        best[2] = std::min(best[2], time([](size_t& i) { return runGlint(true, i); }));
    }
    const Dictionary& d = Dictionary::instance();
    std::printf("glint summary (ns/eval, min of 15 interleaved rounds): GGX %.1f, glint no GGAA %.1f, glint GGAA %.1f\n",
                best[0], best[1], best[2]);
    std::printf("GGAA overhead: %+.1f %% (target <= 5 %%); glint/GGX = %.1fx\n", 100.0 * (best[2] / best[1] - 1.0),
                best[1] / best[0]);
    std::printf("dictionary: %s in %.2f s; CPU float32 with MIP chain %zu B; GPU RGB16F base %zu B (384 KiB), "
                "RGB16F with chain %zu B, RGBA32F with chain (our GL upload) %zu B; cell-cap hits %llu\n",
                d.fromCache() ? "loaded from cache" : "generated", d.generationSeconds(), d.bytesCpu(),
                Dictionary::bytesBaseRgb16f(), Dictionary::bytesChainRgb16f(), Dictionary::bytesChainRgba32f(),
                (unsigned long long)cellCapHits().load());
}

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    summary();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
