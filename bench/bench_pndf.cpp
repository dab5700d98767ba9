// P-NDF query throughput (issue 12 item 8): brute force vs min-max hierarchy vs hierarchy with clusters, by footprint
// size, on the procedural maps of core/texture/normal_map_gen.h; manifold build time, memory and disk-cache load.
//
// Run: bench_pndf --benchmark_min_time=0.1 (~1 min), or bench_pndf --calibrate [--q=300 --sigmas=2,4,8,16,32,64]
// for the ε_c table (~3 min). Queries: footprint centre uniform on the tile, Gaussian kernel, s = the manifold normal
// at a kernel-distributed point (so s ~ D_P: BSDF-sampling-like queries, where D > 0, spec §5 cost note).
// Errors are against the exact sum (no clusters): relative L1 Σ|d-ref|/Σref (and RMSE sqrt(Σ(d-ref)²/Σref²)),
// pointwise, and with D smoothed over a disk of radius 0.01 in s (8 fixed points; a light/pixel-sized spread).
// The smoothed metric over-states errors on scratches: its flat regions are near-delta equilateral spikes
// (area ε_J/2) that the 8 points miss in the exact D but hit once a cluster spreads them into a real triangle.
//
// Measured 2026-12-02 (2-core shared VM, medians of 3; times are noisy, node counts are not).
// Calibration, bench_pndf --calibrate --q=300, 1024² maps, criterion of clusterAccepted (r < ε_c σ_u σ_v, for the
// Gaussian r·K_max(node)/K(0) < ε_c σ_u σ_v; r the true fit error): per cell "x<node speed-up vs the exact
// hierarchy> <pointwise relL1> <smoothed relL1>"; σ = half-width (2σ texels across).
//   bumps     eps_c |      σ = 2         |      σ = 8         |      σ = 32        |      σ = 64
//             3e-06 |    (no clusters)   | x 1.01 0.000 0.000 | x 1.10 0.002 0.002 | x 1.22 0.015 0.011
//             1e-05 | x 1.00 0.000 0.000 | x 1.03 0.000 0.000 | x 1.17 0.007 0.007 | x 1.33 0.047 0.034
//             1e-04 | x 1.01 0.000 0.000 | x 1.10 0.002 0.002 | x 1.40 0.079 0.067 | x 1.61 0.324 0.160
//             1e-03 | x 1.03 0.000 0.001 | x 1.31 0.067 0.043 | x 1.71 0.569 0.306 | x 2.03 0.547 0.212
//             1e-02 | x 1.21 0.016 0.030 | x 1.68 0.480 0.266 | x 2.25 0.767 0.368 | x 2.71 0.574 0.270
//             3e-02 | x 1.45 0.082 0.104 | x 1.88 0.733 0.341 | x 2.57 0.727 0.375 | x 3.20 0.579 0.276
//             1e-01 | x 1.78 0.325 0.236 | x 2.28 0.745 0.381 | x 2.96 0.735 0.383 | x 4.05 0.598 0.347
//             3e-01 | x 2.10 0.786 0.382 | x 2.76 0.744 0.466 | x 3.73 0.754 0.446 | x 4.99 0.694 0.425
//             1e+00 | x 2.54 0.948 0.459 | x 3.11 0.705 0.519 | x 4.63 0.826 0.521 | x 5.98 0.723 0.445
//   brushed   eps_c |      σ = 2         |      σ = 8         |      σ = 32        |      σ = 64
//             3e-06 |    (no clusters)   | x 1.00 0.000 0.000 | x 1.01 0.000 0.000 | x 1.05 0.000 0.000
//             1e-05 |    (no clusters)   | x 1.00 0.000 0.000 | x 1.03 0.000 0.000 | x 1.12 0.002 0.001
//             1e-04 |    (no clusters)   | x 1.01 0.000 0.000 | x 1.20 0.004 0.002 | x 1.50 0.019 0.008
//             1e-03 | x 1.00 0.000 0.000 | x 1.09 0.001 0.001 | x 1.77 0.057 0.029 | x 2.69 0.106 0.058
//             1e-02 | x 1.02 0.001 0.000 | x 1.39 0.019 0.022 | x 3.48 0.244 0.128 | x 5.57 0.209 0.099
//             3e-02 | x 1.06 0.001 0.002 | x 1.76 0.078 0.079 | x 4.91 0.372 0.156 | x 8.68 0.237 0.121
//             1e-01 | x 1.13 0.003 0.022 | x 2.40 0.222 0.180 | x 7.25 0.442 0.204 | x14.63 0.285 0.162
//             3e-01 | x 1.28 0.018 0.054 | x 3.22 0.512 0.278 | x11.88 0.505 0.275 | x23.59 0.324 0.211
//             1e+00 | x 1.68 0.068 0.207 | x 4.26 0.827 0.351 | x18.42 0.516 0.301 | x41.92 0.446 0.355
//   scratches eps_c |      σ = 2         |      σ = 8         |      σ = 32        |      σ = 64
//             3e-06 | x 1.00 0.000 0.000 | x 1.00 0.001 0.001 | x 1.01 0.003 0.032 | x 1.01 0.012 0.097
//             1e-05 | x 1.00 0.000 0.000 | x 1.00 0.001 0.005 | x 1.01 0.012 0.110 | x 1.01 0.024 0.148
//             1e-04 | x 1.00 0.000 0.000 | x 1.01 0.012 0.097 | x 1.02 0.034 0.229 | x 1.04 0.027 0.170
//             1e-03 | x 1.03 0.013 0.014 | x 1.04 0.074 0.364 | x 1.07 0.034 0.260 | x 1.12 0.030 0.182
//             1e-02 | x 1.11 0.161 0.513 | x 1.07 0.070 0.437 | x 1.15 0.035 0.252 | x 1.24 0.035 0.210
//             3e-02 |    (err > 0.5)     | x 1.10 0.072 0.417 | x 1.21 0.038 0.247 | x 1.34 0.037 0.210
//             1e-01 |    (err > 0.5)     | x 1.14 0.076 0.404 | x 1.30 0.041 0.295 | x 1.49 0.041 0.209
//             3e-01 |    (err > 0.5)     | x 1.19 0.078 0.411 | x 1.42 0.044 0.319 | x 1.75 0.049 0.218
//             1e+00 |    (err > 0.5)     | x 1.26 0.090 0.473 | x 1.63 0.055 0.348 | x 2.21 0.090 0.217
// Re-check with another query set (--q=1000 --seed=7, uniform test), pointwise relative L1 at ε_c = 1e-5 / 3e-5,
// σ = 64: bumps 0.021 / 0.074, brushed 0.0002 / 0.001, scratches 0.022 / 0.029: the table is stable to ~20%.
// The uniform test (spec §3.2 as written) at equal error needs 1.5-2x more nodes on brushed (σ = 64: x1.27 at 0.072,
// x2.63 at 0.198, x9.30 at 0.289 pointwise relL1, against x1.92 at 0.052, x5.57 at 0.209, x14.6 at 0.285 above).
// => kDefaultClusterThreshold = 3e-6: the largest half-decade with pointwise error <= ~0.02 at every footprint on
//    all maps (bumps bind: 1e-5 gives 0.047 at σ = 64). It buys 1.0-1.2x only. The ≥10x goal is reached only on
//    brushed at ε_c ≈ 0.1 (14.6x fewer nodes, ~10x time) with ~0.28 pointwise / 0.16 smoothed relative L1 of D;
//    bumps and scratches never get there (bumps' exact hierarchy already visits only 841 nodes at 128 texels
//    across; scratches' grooves have huge 1/|J| weights, so few blocks pass). Cluster level 5: no change (nodes
//    within 2% at σ = 64 on all maps, both tests).
//
// Query time by footprint (texels across), µs/query, nodes visited per query in brackets, pointwise relL1 last;
// google benchmark, medians of 3 on a loaded machine (load ~3.7 on 2 cores: compare within a row, not across runs):
//   map        across | brute  | exact hierarchy | ε_c = 3e-6 (default)  | ε_c = 0.1
//   bumps         4   | 0.85   | 0.41 (20)       | 0.47 (20, 0)          | 0.30 (11, 0.30)
//   bumps        16   | 10.8   | 2.2 (75)        | 2.2 (75, 0.00001)     | 0.68 (33, 0.76)
//   bumps        64   | 219    | 20.5 (314)      | 18.3 (285, 0.001)     | 3.6 (106, 0.73)
//   bumps       128   | 682    | 71 (840)        | 44 (690, 0.013)       | 8.8 (208, 0.61)
//   brushed       4   | 1.26   | 1.36 (33)       | 1.55 (33, 0)          | 1.32 (29, 0.003)
//   brushed      16   | 12.9   | 17.1 (282)      | 16.0 (282, 0)         | 12.9 (118, 0.21)
//   brushed      64   | 258    | 384 (3774)      | 314 (3741, 0.00004)   | 116 (515, 0.45)
//   brushed     128   | 1110   | 981 (13900)     | 1098 (13269, 0.0004)  | 173 (942, 0.28)
//   scratches     4   | 2.0    | 1.8 (27)        | 1.9 (27, 0)           | 1.5 (24, 0.22)
//   scratches    16   | 17.4   | 21 (220)        | 13 (220, 0.0005)      | 20 (193, 0.07)
//   scratches    64   | 237    | 152 (2531)      | 192 (2514, 0.003)     | 152 (1941, 0.04)
//   scratches   128   | 866    | 812 (9881)      | 673 (9789, 0.012)     | 477 (6575, 0.04)
// On a quiet machine (earlier run, same code) brushed at 128 texels: brute 693, exact 628 µs. The exact hierarchy is
// ~10x faster than brute force on bumps at 128 texels, but only 1.1-1.4x on brushed and scratches, whose cells'
// normal bounds overlap most of the footprint's normals (28% / 19% of the cells get hit-tested).
// Build (brushed, quiet machine): 256² 29.5 ms, 1024² 477 ms. Memory at 1024²: 26.55 MB = normals 8.39 + bounds
// levels 1..8 5.59 (4.19 + 1.05 + 0.26 + 0.07 + ...) + clusters levels 1..5 12.57 (9.44 + 2.36 + 0.59 + 0.15 + 0.04).
// Disk cache at 1024²: build + write 512 ms, load (checksum + deserialize) 13.7 ms, 26.55 MB file.
#include "core/texture/normal_map_gen.h"
#include "nodes/bsdf/glint_pndf/pndf_cache.h"
#include "nodes/bsdf/glint_pndf/pndf_eval.h"
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"
#include "nodes/bsdf/glint_pndf/pndf_masking.h"
#include "tests/unit/pndf_test_maps.h"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
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
    unsigned seed = 99;
    std::vector<double> sigmas = {2, 4, 8, 16, 32, 64};
    for (int i = 0; i < argc; ++i) {
        const std::string a = argv[i];
        auto val = [&a](const char* key) { return a.rfind(key, 0) == 0 ? a.substr(std::strlen(key)) : std::string(); };
        if (!val("--q=").empty()) queries = std::stoi(val("--q="));
        if (!val("--n=").empty()) size = std::stoi(val("--n="));
        if (!val("--rho=").empty()) rho = std::stod(val("--rho="));
        if (!val("--e0=").empty()) e0 = std::stod(val("--e0="));
        if (!val("--e1=").empty()) e1 = std::stod(val("--e1="));
        if (!val("--seed=").empty()) seed = unsigned(std::stoul(val("--seed=")));
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
            const std::vector<Query> qs = makeQueries(m, sigma, queries, seed);
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
// ε_c = 0.1 (the ≥10x-fewer-nodes setting on brushed at 128 texels across, ~0.28 relative L1 error of D).
void BM_PndfQuery(benchmark::State& state) {
    const NormalMapKind kind = NormalMapKind(state.range(0));
    const int size = int(state.range(1));
    const double sigma = double(state.range(2)) / 2;  // range = texels across = 2σ
    const int mode = int(state.range(3));
    const double eps = mode == 2 ? kDefaultClusterThreshold : mode == 3 ? 0.1 : 0.0;
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
                                                           mode == 2 ? " eps_default" : " eps_0.1"));
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
    state.counters["clusters_MB"] = clusters / 1e6;
    for (int l = 0; l <= PndfManifold::kMaxLevel; ++l)  // level 0 is recomputed: 0
        state.counters["bounds" + std::to_string(l) + "_MB"] = double(mb.bounds[l]) / 1e6;
    for (int l = 1; l <= PndfManifold::kMaxClusterLevel; ++l)
        state.counters["clusters" + std::to_string(l) + "_MB"] = double(mb.clusters[l]) / 1e6;
}
BENCHMARK(BM_PndfBuild)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond)->Iterations(2);

// Disk cache (pndf_cache.h) at 1024²: arg 0 = build and write the file, 1 = load it (checksum + deserialize).
void BM_PndfCache(benchmark::State& state) {
    const int n = 1024;
    const std::vector<Vec3> normals = generateNormalMap(NormalMapKind::Brushed, n, 1).normals;
    const std::string dir = (std::filesystem::temp_directory_path() / "specula-bench-pndf-cache").string();
    const std::string file = pndfCachePath(dir, pndfCacheKey(normals, n, n, kDefaultJacobianClamp));
    if (state.range(0) == 1) loadOrBuildManifold(normals, n, n, kDefaultJacobianClamp, dir);  // make sure it exists
    resetPndfCacheStats();
    for (auto _ : state) {
        if (state.range(0) == 0) {
            state.PauseTiming();
            std::filesystem::remove(file);
            state.ResumeTiming();
        }
        auto m = loadOrBuildManifold(normals, n, n, kDefaultJacobianClamp, dir);
        benchmark::DoNotOptimize(m.get());
    }
    const PndfCacheStats st = pndfCacheStats();
    state.counters["builds"] = double(st.builds);
    state.counters["diskHits"] = double(st.diskHits);
    state.counters["file_MB"] = double(std::filesystem::file_size(file)) / 1e6;
    state.SetLabel(state.range(0) == 0 ? "build+write" : "load");
}
BENCHMARK(BM_PndfCache)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);

// The GGX-fit masking build (pndf_masking.h, spec §4.2: target <= 5 s on one core at 1024², 32 azimuths) on one core
// (a one-thread TBB arena), on the map of the PndfMasking.GgxFitBudgetAt1024 test, which asserts its node count and
// memory exactly.
void BM_PndfGgxFit(benchmark::State& state) {
    const int n = int(state.range(0));
    const PndfManifold m(testing::sinusoidMap(n, 2, 24, 0.5), n, n, kDefaultJacobianClamp, false);
    tbb::task_arena one(1);
    size_t bytes = 0;
    for (auto _ : state) {
        one.execute([&] {
            const PndfGgxFit fit(m, 32);
            bytes = fit.memoryBytes();
        });
        benchmark::DoNotOptimize(bytes);
    }
    state.counters["MiB"] = double(bytes) / 1048576.0;
}
BENCHMARK(BM_PndfGgxFit)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

int main(int argc, char** argv) {
    for (int i = 1; i < argc; ++i)
        if (!std::strcmp(argv[i], "--calibrate")) return calibrate(argc, argv);
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    return 0;
}
