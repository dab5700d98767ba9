// The renderer against its limit (issue 15 item 2): the anchor scene path-traced by renderScene, and the very same rays
// (camera, bounces, shadow rays, recorded through Accel's RayObserver) traced again through Embree alone on a BVH built
// the same way (Accel::embreeIntersect / embreeOccluded: no shading, no sampling, no exact hit recomputation). Prints
// render time / Embree-only time, both with the BVH build, both on every core (TBB), medians of interleaved runs.
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
};

class Recorder final : public RayObserver {
public:
    void onRay(const Ray& ray, bool shadow) override { perThread.local().push_back({ray, shadow}); }
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

    std::vector<double> render, embree, build;
    size_t hits = 0;
    for (int r = 0; r < runs; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        RenderOutput out = renderScene(scene);
        render.push_back(seconds(t0));
        if (out.stats.samples == 0) return 1;

        t0 = std::chrono::steady_clock::now();
        Accel accel(scene);
        build.push_back(seconds(t0));
        tbb::enumerable_thread_specific<size_t> count(0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 4096), [&](const tbb::blocked_range<size_t>& b) {
            size_t& c = count.local();
            Hit h;
            for (size_t i = b.begin(); i != b.end(); ++i)
                c += rays[i].shadow ? accel.embreeOccluded(rays[i].ray) : accel.embreeIntersect(rays[i].ray, h);
        });
        embree.push_back(seconds(t0));
        hits = count.combine([](size_t a, size_t b) { return a + b; });
    }
    const double tr = median(render), te = median(embree), tb = median(build);
    std::printf("anchor-sphere %dx%d at %d spp: %zu rays (%zu shadow, %zu hit or occluded)\n", res, res, spp, rays.size(),
                shadowRays, hits);
    std::printf("render (renderScene, BVH build included)      %8.3f s\n", tr);
    std::printf("Embree alone (BVH build %.3f s + the same rays) %8.3f s  (%.1f Mrays/s)\n", tb, te,
                double(rays.size()) / (te - tb) * 1e-6);
    std::printf("RATIO render / Embree-only %.2f (goal <= 2.0)\n", tr / te);
    return 0;
}
