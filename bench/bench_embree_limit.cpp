// The renderer against its limit (issue 15 item 2): the anchor scene path-traced by renderScene, and the very same rays
// (camera, bounces, shadow rays, recorded through Accel's RayObserver) traced again through Embree alone on a BVH built
// the same way (Accel::embreeIntersect / embreeOccluded: no shading, no sampling, no exact hit recomputation). Prints
// render time / Embree-only time, both with the BVH build, both on every core (TBB), medians of interleaved runs.
// Since issue 37 the renderer traces each tile row's camera rays as one coherent stream (Accel::intersectStream); the
// Embree-only replay traces them the same way (rtcIntersect1M, the ratio's baseline), and once more one by one
// (rtcIntersect1, the baseline before issue 37) for comparison.
//   bench_embree_limit [SPP=8] [RESOLUTION=256] [RUNS=3]
#include "core/api/specula.h"
#include "core/render/accel.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

using namespace specula;

namespace {

struct RecordedRay {
    Ray ray;
    bool shadow;
    uint32_t stream;  // on the first ray of an intersectStream call: its number of rays; 0 otherwise
};
class Recorder final : public RayObserver {
public:
    void onRay(const Ray& ray, bool shadow) override { perThread.local().push_back({ray, shadow, 0}); }
    void onStream(const Ray* rays, size_t n) override {
        auto& v = perThread.local();
        for (size_t k = 0; k < n; ++k) v.push_back({rays[k], false, k == 0 ? uint32_t(n) : 0u});
    }
    tbb::enumerable_thread_specific<std::vector<RecordedRay>> perThread;
};

double seconds(std::chrono::steady_clock::time_point a) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    const int spp = argc > 1 ? std::atoi(argv[1]) : 8;
    const int res = argc > 2 ? std::atoi(argv[2]) : 256;
    const int runs = argc > 3 ? std::atoi(argv[3]) : 3;
    SceneOverrides ov;
    ov.spp = spp;
    ov.width = ov.height = res;
    const Scene scene = loadScene(std::string(SPECULA_SOURCE_DIR) + "/examples/anchor-sphere.json", ov);

    // Record the rays of one render.
    Recorder rec;
    Accel::setRayObserver(&rec);
    renderScene(scene);
    Accel::setRayObserver(nullptr);
    std::vector<RecordedRay> rays;
    for (auto& v : rec.perThread) rays.insert(rays.end(), v.begin(), v.end());
    const size_t shadowRays = size_t(std::count_if(rays.begin(), rays.end(), [](const RecordedRay& r) { return r.shadow; }));
    // Work items: a stream's rays stay together (rtcIntersect1M calls of up to 64 rays); any other ray is one item.
    std::vector<size_t> items;
    size_t streamed = 0;
    for (size_t i = 0; i < rays.size(); i += std::max<size_t>(rays[i].stream, 1)) {
        items.push_back(i);
        streamed += rays[i].stream;
    }
    std::vector<Ray> plain(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) plain[i] = rays[i].ray;
    // Traces the recorded rays on 'accel': streams as streams, or every ray through rtcIntersect1 / rtcOccluded1.
    auto replay = [&](const Accel& accel, bool asStreams) {
        tbb::enumerable_thread_specific<size_t> count(0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, items.size(), 2048), [&](const tbb::blocked_range<size_t>& b) {
            size_t& c = count.local();
            Hit h;
            Hit hs[64];
            uint8_t found[64];
            for (size_t it = b.begin(); it != b.end(); ++it) {
                const size_t i = items[it];
                const size_t n = std::max<size_t>(rays[i].stream, 1);
                if (asStreams && rays[i].stream > 0) {
                    for (size_t k = 0; k < n; k += 64) {
                        const size_t m = std::min<size_t>(64, n - k);
                        accel.embreeIntersectStream(plain.data() + i + k, m, hs, found);
                        for (size_t q = 0; q < m; ++q) c += found[q];
                    }
                    continue;
                }
                for (size_t k = i; k < i + n; ++k)
                    c += rays[k].shadow ? accel.embreeOccluded(rays[k].ray) : accel.embreeIntersect(rays[k].ray, h);
            }
        });
        return count.combine([](size_t a, size_t b) { return a + b; });
    };
    std::vector<double> render, embree, embreeSingle, build;
    size_t hits = 0, hitsSingle = 0;
    for (int r = 0; r < runs; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        RenderOutput out = renderScene(scene);
        render.push_back(seconds(t0));
        if (out.stats.samples == 0) return 1;
        // Both replays include a BVH build of their own, as the render does.
        t0 = std::chrono::steady_clock::now();
        {
            Accel accel(scene);
            build.push_back(seconds(t0));
            hits = replay(accel, true);
        }
        embree.push_back(seconds(t0));
        t0 = std::chrono::steady_clock::now();
        {
            Accel accel(scene);
            hitsSingle = replay(accel, false);
        }
        embreeSingle.push_back(seconds(t0));
    }
    const double tr = median(render), te = median(embree), ts = median(embreeSingle), tb = median(build);
    std::printf("anchor-sphere %dx%d at %d spp: %zu rays (%zu shadow, %zu camera rays in streams, %zu hit or occluded)\n",
                res, res, spp, rays.size(), shadowRays, streamed, hits);
    if (hits != hitsSingle) std::printf("note: the streams found %zu hits or occlusions, single rays %zu\n", hits, hitsSingle);
    std::printf("render (renderScene, BVH build included)                        %8.3f s\n", tr);
    std::printf("Embree alone: BVH build %.3f s + the same rays, streams as streams %8.3f s  (%.1f Mrays/s)\n", tb, te,
                double(rays.size()) / (te - tb) * 1e-6);
    std::printf("Embree alone: every ray through rtcIntersect1 / rtcOccluded1      %8.3f s  (%.1f Mrays/s)\n", ts,
                double(rays.size()) / (ts - tb) * 1e-6);
    std::printf("render / Embree-only with single rays (the baseline before issue 37) %.2f\n", tr / ts);
    std::printf("RATIO render / Embree-only %.2f (goal <= 2.0)\n", tr / te);
    return 0;
}
