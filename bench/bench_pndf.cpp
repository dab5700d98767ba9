// P-NDF query throughput (issue 12 item 8, first slice): brute force vs min-max hierarchy at footprints 4, 16 and 64
// texels across on a 256² synthetic bump map, and the manifold build time and memory at 256² and 1024².
// With clusters at ε_c = 1e-4 / 1e-3 (true-residual units, not the paper's; not yet calibrated against image RMSE),
// reporting the relative L1 error of D against the exact sum over the same queries.
#include "nodes/bsdf/glint_pndf/pndf_eval.h"
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

using namespace specula;
using namespace specula::pndf;

namespace {

// Periodic bump map: 12 sinusoids of integer frequency up to 24 cycles per tile, peak slopes around 0.3.
std::vector<Vec3> bumpMap(int n) {
    std::mt19937 rng(1234);
    std::uniform_int_distribution<int> freq(-24, 24);
    std::uniform_real_distribution<double> phase(0, 6.283185307179586);
    struct Wave {
        double fx, fy, ph, amp;
    };
    std::vector<Wave> waves;
    while (waves.size() < 12) {
        int fx = freq(rng), fy = freq(rng);
        if (fx == 0 && fy == 0) continue;
        double w = 6.283185307179586 * std::sqrt(double(fx * fx + fy * fy)) / 256.0;
        waves.push_back({double(fx), double(fy), phase(rng), 0.3 / (w * 12)});
    }
    std::vector<Vec3> normals(size_t(n) * n);
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) {
            double hx = 0, hy = 0;
            for (const Wave& wv : waves) {
                // Frequencies are per 256 texels, so a 1024² map repeats the 256² pattern 4x4 (same statistics).
                double arg = 6.283185307179586 * (wv.fx * c + wv.fy * r) / 256.0 + wv.ph;
                double k = wv.amp * std::cos(arg) * 6.283185307179586 / 256.0;
                hx += k * wv.fx;
                hy += k * wv.fy;
            }
            normals[size_t(r) * n + c] = glm::normalize(Vec3(float(-hx), float(-hy), 1.f));
        }
    return normals;
}

const PndfManifold& manifold256() {
    static PndfManifold m(bumpMap(256), 256, 256);
    return m;
}

struct Query {
    Footprint fp;
    Vec2d s;
};

// Queries like BSDF sampling's (s = the manifold normal at a kernel-distributed point: high-density regions, many
// hits, spec §5 cost note) alternated with queries uniform in the footprint's normal bounds (like light sampling).
std::vector<Query> makeQueries(const PndfManifold& m, double sigma, int count) {
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> u01(0, 1);
    std::vector<Query> qs;
    for (int i = 0; i < count; ++i) {
        Footprint fp{u01(rng) * m.width(), u01(rng) * m.height(), sigma, sigma, FootprintKernel::Gaussian};
        Vec2d s;
        if (i % 2 == 0) {
            double x = fp.centreX + (u01(rng) * 2 - 1) * sigma, y = fp.centreY + (u01(rng) * 2 - 1) * sigma;
            int c = int(std::floor(x)), r = int(std::floor(y));
            double xi = x - c, eta = y - r;
            ManifoldTriangle t[2];
            m.cellTriangles(r, c, t);
            bool up = xi + eta < 1;
            const ManifoldTriangle& tr = t[up ? 0 : 1];
            double t1 = up ? xi : 1 - xi, t2 = up ? eta : 1 - eta;
            s = {tr.sOrigin.x + t1 * tr.sEdge1.x + t2 * tr.sEdge2.x, tr.sOrigin.y + t1 * tr.sEdge1.y + t2 * tr.sEdge2.y};
        } else {
            NormalBounds b = footprintNormalBounds(m, fp);
            s = {b.minX + u01(rng) * (b.maxX - b.minX), b.minY + u01(rng) * (b.maxY - b.minY)};
        }
        qs.push_back({fp, s});
    }
    return qs;
}

template <bool kHierarchy>
void BM_PndfQuery(benchmark::State& state) {
    const PndfManifold& m = manifold256();
    const double sigma = double(state.range(0)) / 2;  // range = texels across = 2σ
    const std::vector<Query> qs = makeQueries(m, sigma, 512);
    size_t i = 0;
    EvalStats stats;
    uint64_t n = 0;
    for (auto _ : state) {
        const Query& q = qs[i++ & 511];
        double d = kHierarchy ? evalPndfHierarchy(m, q.fp, q.s, &stats) : evalPndfBruteForce(m, q.fp, q.s, &stats);
        benchmark::DoNotOptimize(d);
        ++n;
    }
    state.SetItemsProcessed(int64_t(n));
    state.counters["cells/query"] = double(stats.cellsTested) / double(n);
    state.counters["hits/query"] = double(stats.trianglesHit) / double(n);
}
void BM_PndfQueryClusters(benchmark::State& state) {
    const PndfManifold& m = manifold256();
    const double sigma = double(state.range(0)) / 2;
    const double eps = state.range(1) == 0 ? 1e-4 : 1e-3;
    const std::vector<Query> qs = makeQueries(m, sigma, 512);
    double err = 0, ref = 0;
    for (const Query& q : qs) {
        err += std::abs(evalPndfHierarchy(m, q.fp, q.s, nullptr, eps) - evalPndfBruteForce(m, q.fp, q.s));
        ref += evalPndfBruteForce(m, q.fp, q.s);
    }
    size_t i = 0;
    EvalStats stats;
    uint64_t n = 0;
    for (auto _ : state) {
        const Query& q = qs[i++ & 511];
        double d = evalPndfHierarchy(m, q.fp, q.s, &stats, eps);
        benchmark::DoNotOptimize(d);
        ++n;
    }
    state.SetItemsProcessed(int64_t(n));
    state.counters["eps_c"] = eps;
    state.counters["relL1"] = err / ref;
    state.counters["clusters/query"] = double(stats.clustersUsed) / double(n);
    state.counters["cells/query"] = double(stats.cellsTested) / double(n);
}
BENCHMARK(BM_PndfQueryClusters)->Args({4, 0})->Args({16, 0})->Args({64, 0})->Args({4, 1})->Args({16, 1})->Args({64, 1});

BENCHMARK(BM_PndfQuery<false>)->Name("BM_PndfQuery/brute")->Arg(4)->Arg(16)->Arg(64);
BENCHMARK(BM_PndfQuery<true>)->Name("BM_PndfQuery/hierarchy")->Arg(4)->Arg(16)->Arg(64);

void BM_PndfBuild(benchmark::State& state) {
    const int n = int(state.range(0));
    const std::vector<Vec3> normals = bumpMap(n);
    size_t bytes = 0;
    for (auto _ : state) {
        PndfManifold m(normals, n, n);
        bytes = m.memoryBytes();
        benchmark::DoNotOptimize(bytes);
    }
    state.counters["MB"] = double(bytes) / 1e6;
    state.counters["input MB (float3)"] = double(normals.size() * sizeof(Vec3)) / 1e6;
}
BENCHMARK(BM_PndfBuild)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
