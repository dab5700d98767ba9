// P-NDF query throughput (issue 12 item 8): brute force vs min-max hierarchy vs hierarchy with clusters, by footprint
// size, on the procedural maps of core/texture/normal_map_gen.h; manifold build time and memory at 256² and 1024².
#include "core/texture/normal_map_gen.h"
#include "nodes/bsdf/glint_pndf/pndf_eval.h"
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"
#include "tests/unit/pndf_test_maps.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

using namespace specula;
using namespace specula::pndf;

namespace {

const PndfManifold& manifoldFor(NormalMapKind kind, int n) {
    static std::map<std::pair<int, int>, std::unique_ptr<PndfManifold>> cache;
    auto& slot = cache[{int(kind), n}];
    if (!slot) {
        NormalMap map = generateNormalMap(kind, n, 1);
        slot = std::make_unique<PndfManifold>(map.normals, n, n);
    }
    return *slot;
}

struct Query {
    Footprint fp;
    Vec2d s;
};

// Queries where D is non-zero, like BSDF sampling's (spec §2.4 step 1 and §5 cost note): the footprint centre uniform
// on the tile, x drawn from the truncated Gaussian kernel (std σ/3 inside the σ box), s = the manifold normal at x.
// So s is distributed as D_P itself.
std::vector<Query> makeQueries(const PndfManifold& m, double sigma, int count, unsigned seed = 99) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1);
    std::normal_distribution<double> g(0, sigma / 3);
    std::vector<Query> qs;
    for (int i = 0; i < count; ++i) {
        Footprint fp{u01(rng) * m.width(), u01(rng) * m.height(), sigma, sigma, FootprintKernel::Gaussian};
        double dx, dy;
        do {
            dx = g(rng);
            dy = g(rng);
        } while (std::abs(dx) > sigma || std::abs(dy) > sigma);
        qs.push_back({fp, testing::manifoldNormalAt(m, fp.centreX + dx, fp.centreY + dy)});
    }
    return qs;
}

// D smoothed over a disk of radius rho in s (the spread of h over a small light or a pixel), by a fixed 8-point
// pattern: a distribution-level error that, unlike the pointwise one, does not hinge on where exactly each fold
// caustic lies.
std::vector<double> smoothedD(const PndfManifold& m, const std::vector<Query>& qs, double eps, double rho) {
    static const double pat[8][2] = {{0.31, 0.12}, {-0.55, 0.40}, {0.72, -0.51}, {-0.18, -0.83},
                                     {0.05, 0.62}, {-0.81, -0.22}, {0.47, 0.77}, {0.88, 0.21}};
    std::vector<double> out(qs.size());
    for (size_t i = 0; i < qs.size(); ++i) {
        double acc = 0;
        for (const auto& p : pat)
            acc += evalPndfHierarchy(m, qs[i].fp, {qs[i].s.x + rho * p[0], qs[i].s.y + rho * p[1]}, nullptr, eps);
        out[i] = acc / 8;
    }
    return out;
}

struct RunResult {
    std::vector<double> d;
    double nodes = 0, cells = 0, clusters = 0, seconds = 0;
};

RunResult runQueries(const PndfManifold& m, const std::vector<Query>& qs, double eps, int repeats = 3) {
    RunResult rr;
    rr.d.resize(qs.size());
    EvalStats st;
    for (size_t i = 0; i < qs.size(); ++i) rr.d[i] = evalPndfHierarchy(m, qs[i].fp, qs[i].s, &st, eps);
    rr.nodes = double(st.nodesVisited) / qs.size();
    rr.cells = double(st.cellsTested) / qs.size();
    rr.clusters = double(st.clustersUsed) / qs.size();
    rr.seconds = 1e300;
    for (int r = 0; r < repeats; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        double acc = 0;
        for (const Query& q : qs) acc += evalPndfHierarchy(m, q.fp, q.s, nullptr, eps);
        benchmark::DoNotOptimize(acc);
        rr.seconds = std::min(rr.seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    return rr;
}

// Relative RMSE sqrt(Σ(d-ref)²/Σref²) and relative L1 Σ|d-ref|/Σref of D over the queries.
void errors(const std::vector<double>& d, const std::vector<double>& ref, double& rmse, double& l1) {
    double e2 = 0, r2 = 0, e1 = 0, r1 = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        e2 += (d[i] - ref[i]) * (d[i] - ref[i]);
        r2 += ref[i] * ref[i];
        e1 += std::abs(d[i] - ref[i]);
        r1 += ref[i];
    }
    rmse = std::sqrt(e2 / r2);
    l1 = e1 / r1;
}

// Calibration table (kDefaultClusterThreshold): per map and footprint, the exact D_P (no clusters) against clusters
// at ε_c on a half-decade grid; errors pointwise and with D smoothed over a disk of radius rho in s.
int calibrate(int argc, char** argv) {
    int queries = 300, size = 1024;
    double rho = 0.01, e0 = 1e-6, e1 = 3.1;
    std::vector<double> sigmas = {2, 4, 8, 16, 32, 64};
    for (int i = 0; i < argc; ++i) {
        const std::string a = argv[i];
        auto val = [&a](const char* key) { return a.rfind(key, 0) == 0 ? a.substr(std::strlen(key)) : std::string(); };
        if (!val("--q=").empty()) queries = std::stoi(val("--q="));
        if (!val("--n=").empty()) size = std::stoi(val("--n="));
        if (!val("--rho=").empty()) rho = std::stod(val("--rho="));
        if (!val("--e0=").empty()) e0 = std::stod(val("--e0="));
        if (!val("--e1=").empty()) e1 = std::stod(val("--e1="));
        if (!val("--sigmas=").empty()) {
            sigmas.clear();
            std::string v = val("--sigmas=");
            for (size_t p = 0; p < v.size();) {
                size_t q = v.find(',', p);
                if (q == std::string::npos) q = v.size();
                sigmas.push_back(std::stod(v.substr(p, q - p)));
                p = q + 1;
            }
        }
    }
    std::printf("map sigma eps_c | pointwise relRMSE relL1 | smoothed(rho=%g) relRMSE relL1 | nodes/query (speed-up) "
                "time speed-up | clusters/query\n", rho);
    for (NormalMapKind kind : {NormalMapKind::Bumps, NormalMapKind::Brushed, NormalMapKind::Scratches}) {
        const PndfManifold& m = manifoldFor(kind, size);
        for (double sigma : sigmas) {
            const std::vector<Query> qs = makeQueries(m, sigma, queries);
            const RunResult ref = runQueries(m, qs, 0.0);
            const std::vector<double> refSm = smoothedD(m, qs, 0.0, rho);
            std::printf("%s sigma=%g exact: nodes %.1f cells %.1f, %.2f us/query\n", normalMapKindName(kind), sigma,
                        ref.nodes, ref.cells, ref.seconds / qs.size() * 1e6);
            for (double e = e0; e < e1; e *= std::sqrt(10.0)) {
                const RunResult rr = runQueries(m, qs, e);
                if (rr.clusters == 0) continue;
                double rmse, l1, rmseS, l1S;
                errors(rr.d, ref.d, rmse, l1);
                errors(smoothedD(m, qs, e, rho), refSm, rmseS, l1S);
                std::printf("%s %g %.0e | %.4f %.4f | %.4f %.4f | %.1f (x%.2f) x%.2f | %.1f\n", normalMapKindName(kind),
                            sigma, e, rmse, l1, rmseS, l1S, rr.nodes, ref.nodes / rr.nodes, ref.seconds / rr.seconds,
                            rr.clusters);
                if (l1S > 0.5) break;
            }
        }
    }
    return 0;
}

// ---- Google Benchmark ----------------------------------------------------------------------------------------------

constexpr int kQueries = 256;

// Mode 0: brute force; 1: hierarchy, no clusters (exact); 2: clusters at kDefaultClusterThreshold; 3: clusters at
// ε_c = 0.3 (the ~10x setting on brushed, ~20% error of D).
void BM_PndfQuery(benchmark::State& state) {
    const NormalMapKind kind = NormalMapKind(state.range(0));
    const int size = int(state.range(1));
    const double sigma = double(state.range(2)) / 2;  // range = texels across = 2σ
    const int mode = int(state.range(3));
    const double eps = mode == 2 ? kDefaultClusterThreshold : mode == 3 ? 0.3 : 0.0;
    const PndfManifold& m = manifoldFor(kind, size);
    const std::vector<Query> qs = makeQueries(m, sigma, kQueries);
    double err = 0, ref = 0;
    if (mode >= 2)
        for (const Query& q : qs) {
            double exact = evalPndfHierarchy(m, q.fp, q.s);
            err += std::abs(evalPndfHierarchy(m, q.fp, q.s, nullptr, eps) - exact);
            ref += exact;
        }
    size_t i = 0;
    EvalStats stats;
    uint64_t n = 0;
    for (auto _ : state) {
        const Query& q = qs[i++ % kQueries];
        double d = mode == 0 ? evalPndfBruteForce(m, q.fp, q.s, &stats) : evalPndfHierarchy(m, q.fp, q.s, &stats, eps);
        benchmark::DoNotOptimize(d);
        ++n;
    }
    state.SetItemsProcessed(int64_t(n));
    state.SetLabel(std::string(normalMapKindName(kind)) + (mode == 0 ? " brute" : mode == 1 ? " exact" :
                                                           mode == 2 ? " eps_default" : " eps_0.3"));
    state.counters["nodes"] = double(stats.nodesVisited) / double(n);
    state.counters["cells"] = double(stats.cellsTested) / double(n);
    state.counters["clusters"] = double(stats.clustersUsed) / double(n);
    if (mode >= 2) state.counters["relL1"] = err / ref;
}

void queryArgs(benchmark::internal::Benchmark* b) {
    for (int kind : {int(NormalMapKind::Bumps), int(NormalMapKind::Brushed), int(NormalMapKind::Scratches)})
        for (int across : {4, 8, 16, 32, 64, 128})
            for (int mode = 0; mode < 4; ++mode) b->Args({kind, 1024, across, mode});
    for (int across : {4, 32}) b->Args({int(NormalMapKind::Bumps), 256, across, 1});
}
BENCHMARK(BM_PndfQuery)->Apply(queryArgs)->ArgNames({"map", "N", "across", "mode"})->Unit(benchmark::kMicrosecond);

// Build time and the memory breakdown (issue 12 item 2: <= 34 MB, <= 20 s on 2 cores at 1024²).
void BM_PndfBuild(benchmark::State& state) {
    const int n = int(state.range(0));
    const std::vector<Vec3> normals = generateNormalMap(NormalMapKind::Brushed, n, 1).normals;
    PndfManifold::MemoryBreakdown mb;
    size_t bytes = 0;
    for (auto _ : state) {
        PndfManifold m(normals, n, n);
        bytes = m.memoryBytes();
        mb = m.memoryBreakdown();
        benchmark::DoNotOptimize(bytes);
    }
    double bounds = 0, clusters = 0;
    for (size_t b : mb.bounds) bounds += double(b);
    for (size_t b : mb.clusters) clusters += double(b);
    state.counters["MB"] = double(bytes) / 1e6;
    state.counters["normals_MB"] = double(mb.normals) / 1e6;
    state.counters["bounds_MB"] = bounds / 1e6;
    state.counters["bounds1_MB"] = double(mb.bounds[1]) / 1e6;
    state.counters["clusters_MB"] = clusters / 1e6;
    state.counters["clusters1_MB"] = double(mb.clusters[1]) / 1e6;
    state.counters["clusters5_MB"] = double(mb.clusters[5]) / 1e6;
}
BENCHMARK(BM_PndfBuild)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

int main(int argc, char** argv) {
    for (int i = 1; i < argc; ++i)
        if (!std::strcmp(argv[i], "--calibrate")) return calibrate(argc, argv);
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    return 0;
}
