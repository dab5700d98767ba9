// Cost of one filtered-GGX evaluation (f·cos for a light sample, including the per-sample half-vector filtering) for
// every filter/kernel mode, against the unfiltered GgxLobe and FilteredGgxLobe(none) in the same run; prints ratios
// (issue 37 goal: projected_approx ≤ 1.5x GgxLobe, the float form FloatProjectedApprox; TK21 Tables 2–3 report
// whole-frame times).
#include "nodes/bsdf/ggx_filtered/filtered_ggx.h"

#include "bench/ratio_reporter.h"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

using namespace specula;
using namespace specula::fggx;

namespace {

std::vector<Vec3>& dirs() {
    static std::vector<Vec3> d = [] {
        std::vector<Vec3> v;
        for (int i = 0; i < 64; ++i) {
            float a = 0.1f * i, b = 0.37f * i;
            v.push_back(glm::normalize(Vec3(0.6f * std::cos(a), 0.6f * std::sin(b), 1.f)));
        }
        return v;
    }();
    return d;
}

const float kLightDistance = 4.f;

LobeSetup setupFor(Filter f, Kernel k) {
    LobeSetup s;
    s.A = Sym2::diag(0.05 * 0.05, 0.03 * 0.03);
    s.params.filter = f;
    s.params.kernel = k;
    s.diff.valid = true;
    s.diff.dwo[0] = D3(0.002, 0.0005, -0.0003), s.diff.dwo[1] = D3(-0.0004, 0.0021, 0.0001);
    s.diff.dn[0] = D3(0.01, 0.002, 0), s.diff.dn[1] = D3(-0.001, 0.012, 0);
    s.diff.dp[0] = D3(0.004, 0.0, 0.001), s.diff.dp[1] = D3(0.0, 0.004, -0.001);
    return s;
}

// The timed loop: evalPdf over pairs of the 64 fixed directions. Both outputs are kept: with only f kept, the
// compiler drops the inlined GgxLobe's pdf (its own Smith G1 and NDF) but not FilteredGgxLobe's (one division gives
// both), which made the unfiltered lobe look 4–5 ns cheaper per evaluation than the renderer, which uses both, sees.
template <class Lobe>
void evalLoop(benchmark::State& state, const Lobe& lobe) {
    auto& d = dirs();
    size_t k = 0;
    for (auto _ : state) {
        LobeValue e = lobe.evalPdf(LobeQuery{d[k & 63], d[(k * 7 + 3) & 63], kLightDistance});
        benchmark::DoNotOptimize(e);
        ++k;
    }
}

void BM_GgxLobe(benchmark::State& state) {
    evalLoop(state, GgxLobe(0.05f, 0.03f, Fresnel::schlick(Color3(0.95f, 0.64f, 0.54f))));
}

void BM_Filtered(benchmark::State& state) {
    Filter f = Filter(state.range(0));
    Kernel kn = Kernel(state.range(1));
    const Fresnel fresnel = Fresnel::schlick(Color3(0.95f, 0.64f, 0.54f));
    evalLoop(state, FilteredGgxLobe(setupFor(f, kn), fresnel));
    state.SetLabel(std::string(filterName(f)) + (kn == Kernel::Full ? "/full" : "/axis_aligned"));
}

BENCHMARK(BM_GgxLobe)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_Filtered)
    ->ArgsProduct({{int(Filter::None), int(Filter::Slope), int(Filter::Projected), int(Filter::ProjectedApprox)}, {0, 1}})
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_Filtered)
    ->ArgsProduct({{int(Filter::IsoMax), int(Filter::IsoSum), int(Filter::IsoMean), int(Filter::IsoRect)}, {0}})
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

}  // namespace

int main(int argc, char** argv) {
    return specula::bench::runWithRatios(argc, argv, [](specula::bench::RatioReporter& rep) {
        double ggx = 0, none = 0;
        for (auto& [k, v] : rep.medianNs) {
            if (k.rfind("BM_GgxLobe", 0) == 0) ggx = v;
            if (rep.label[k] == "none/full") none = v;
        }
        if (ggx > 0 && none > 0) {
            std::printf("\nmedian ns per eval; ratios vs GgxLobe (%.2f ns) and vs FilteredGgxLobe none/full (%.2f ns)\n", ggx, none);
            for (auto& [k, v] : rep.medianNs) {
                if (k.rfind("BM_Filtered", 0) != 0) continue;
                std::printf("RATIO %-28s %7.2f ns  x%.3f vs GgxLobe  x%.3f vs none\n", rep.label[k].c_str(), v, v / ggx, v / none);
            }
        }
    });
}
