// LTC quad lights (issue 10 item 9): ns per analytic quad-light evaluation of a lobe (table lookup + exact clipping or
// clip-free integral, and the polygon sample the shadow ratio draws) against one sampled NEE sample of the same light.
#include "core/ltc/ltc_ggx.h"
#include "core/render/lights.h"
#include "core/render/lobes/ggx.h"
#include "core/render/lobes/lambert.h"
#include "core/render/sampler.h"
#include "ratio_reporter.h"

#include <benchmark/benchmark.h>

#include <vector>

using namespace specula;

namespace {

// 64 shading configurations: view directions and a quad light above a shading point at the origin (lobe frame = world).
struct Case {
    Vec3 wo;
    Vec3 poly[4];
};
const std::vector<Case>& cases() {
    static const std::vector<Case> c = [] {
        std::vector<Case> v;
        QuadLight light(Vec3(-0.6f, -0.4f, 1.2f), Vec3(1.1f, 0.f, 0.f), Vec3(0.f, 0.8f, 0.f), Color3(1.f), true);
        for (int i = 0; i < 64; ++i) {
            float th = 0.02f + 1.45f * float(i) / 63.f, ph = 0.37f * float(i);
            Case k;
            k.wo = Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
            Vec3 p(0.3f * std::cos(float(i)), 0.3f * std::sin(float(i)), 0.f);
            Color3 L;
            light.polygon(p, k.poly, L);
            for (auto& q : k.poly) q -= p;
            v.push_back(k);
        }
        return v;
    }();
    return c;
}

const GgxLobe& ggx() {
    static GgxLobe l(0.2f, 0.2f, Fresnel::schlick(Color3(0.95f, 0.64f, 0.54f)));
    return l;
}
const GgxLobe& ggxAniso() {
    static GgxLobe l(0.35f, 0.1f, Fresnel::schlick(Color3(0.95f, 0.64f, 0.54f)));
    return l;
}

void BM_LtcQuad(benchmark::State& state) {
    const BsdfLobe& lobe = state.range(0) == 0 ? static_cast<const BsdfLobe&>(ggx()) : ggxAniso();
    const uint8_t horizon = uint8_t(state.range(1));
    auto& c = cases();
    size_t k = 0;
    for (auto _ : state) {
        const Case& x = c[k++ & 63];
        Color3 r;
        lobe.integratePolygon(LobeQuery{x.wo, x.wo, std::numeric_limits<float>::infinity(), horizon}, x.poly, 4, r);
        benchmark::DoNotOptimize(r);
    }
    state.SetLabel(std::string(state.range(0) == 0 ? "ggx iso" : "ggx aniso") + (horizon ? " clipless" : " clip"));
}

void BM_LtcQuadPlusShadowSample(benchmark::State& state) {
    // What "ltc" costs per light and lobe before the shadow ray: the integral and the polygon sample.
    auto& c = cases();
    size_t k = 0;
    for (auto _ : state) {
        const Case& x = c[k & 63];
        LobeQuery q{x.wo, x.wo};
        Color3 r;
        ggx().integratePolygon(q, x.poly, 4, r);
        Vec3 wi;
        ggx().samplePolygon(q, x.poly, 4, Vec2(float(k % 61) / 61.f, float(k % 53) / 53.f), mix64(k), wi);
        benchmark::DoNotOptimize(r);
        benchmark::DoNotOptimize(wi);
        ++k;
    }
    state.SetLabel("ggx iso clip + samplePolygon");
}

void BM_SampledNee(benchmark::State& state) {
    // One sampled next-event sample of the same light (area sample + f·cos and pdf for MIS), no shadow ray.
    QuadLight light(Vec3(-0.6f, -0.4f, 1.2f), Vec3(1.1f, 0.f, 0.f), Vec3(0.f, 0.8f, 0.f), Color3(1.f), true);
    auto& c = cases();
    size_t k = 0;
    for (auto _ : state) {
        const Case& x = c[k & 63];
        LightSample ls;
        Vec3 p(0.3f * std::cos(float(k & 63)), 0.3f * std::sin(float(k & 63)), 0.f);
        light.sample(p, Vec2(float(k % 61) / 61.f, float(k % 53) / 53.f), ls);
        LobeValue v = ggx().evalPdf(LobeQuery{x.wo, ls.wi});
        Color3 contrib = v.f * ls.L / (ls.pdf + v.pdf);
        benchmark::DoNotOptimize(contrib);
        ++k;
    }
    state.SetLabel("ggx sampled NEE");
}

BENCHMARK(BM_LtcQuad)->ArgsProduct({{0, 1}, {0, 1}})->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_LtcQuadPlusShadowSample)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_SampledNee)->Repetitions(5)->ReportAggregatesOnly(true);

}  // namespace

int main(int argc, char** argv) {
    return specula::bench::runWithRatios(argc, argv, [](specula::bench::RatioReporter& rep) {
        double nee = 0;
        for (auto& [k, v] : rep.medianNs)
            if (k.rfind("BM_SampledNee", 0) == 0) nee = v;
        if (nee > 0) {
            std::printf("\nmedian ns per quad-light evaluation; ratio vs one sampled NEE sample (%.1f ns)\n", nee);
            for (auto& [k, v] : rep.medianNs)
                std::printf("RATIO %-36s %7.1f ns  x%.2f\n", rep.label[k].c_str(), v, v / nee);
        }
    });
}
