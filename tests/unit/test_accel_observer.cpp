// Accel's RayObserver and its Embree-only queries (bench_embree_limit, issue 15 item 2): the observer sees every ray of
// a render (camera, bounces and shadow rays) without changing a bit of the image, and Embree alone finds the same
// triangle as Accel::intersect, whose exact recomputation moves t by rounding only.
#include "core/api/specula.h"
#include "core/render/accel.h"
#include "tests/unit/test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <mutex>
#include <vector>

using namespace specula;

namespace {

class Collect final : public RayObserver {
public:
    void onRay(const Ray& ray, bool shadow) override {
        std::lock_guard<std::mutex> lock(m);
        (shadow ? shadows : rays).push_back(ray);
    }
    std::mutex m;
    std::vector<Ray> rays, shadows;
};

}  // namespace

TEST(AccelObserver, SeesEveryRayAndChangesNoPixel) {
    SceneOverrides ov;
    ov.spp = 2;
    ov.width = ov.height = 32;
    const Scene scene = loadScene(test::sourcePath("examples/anchor-sphere.json"), ov);
    const RenderOutput plain = renderScene(scene);
    Collect c;
    Accel::setRayObserver(&c);
    const RenderOutput observed = renderScene(scene);
    Accel::setRayObserver(nullptr);
    ASSERT_EQ(plain.images.aovs.size(), observed.images.aovs.size());
    for (size_t a = 0; a < plain.images.aovs.size(); ++a) {
        const auto& p = plain.images.aovs[a].pixels;
        const auto& o = observed.images.aovs[a].pixels;
        ASSERT_EQ(p.size(), o.size());
        EXPECT_EQ(0, std::memcmp(p.data(), o.data(), p.size() * sizeof(p[0]))) << "AOV " << a;
    }
    // At least one camera ray per sample, and the path integrator's shadow rays.
    EXPECT_GE(c.rays.size(), size_t(32 * 32 * 2));
    EXPECT_GT(c.shadows.size(), size_t(0));

    Accel accel(scene);
    int hits = 0;
    for (size_t i = 0; i < c.rays.size(); i += 7) {
        Hit exact, raw;
        const bool a = accel.intersect(c.rays[i], exact), b = accel.embreeIntersect(c.rays[i], raw);
        ASSERT_EQ(a, b) << "ray " << i;
        if (!a) continue;
        ++hits;
        EXPECT_EQ(exact.shape, raw.shape);
        EXPECT_EQ(exact.prim, raw.prim);
        EXPECT_NEAR(exact.t, raw.t, 1e-4f * std::max(1.f, raw.t)) << "ray " << i;
    }
    EXPECT_GT(hits, 100);
    for (size_t i = 0; i < c.shadows.size(); i += 7)
        EXPECT_EQ(accel.occluded(c.shadows[i]), accel.embreeOccluded(c.shadows[i])) << "shadow ray " << i;
}

// Issue 37: the renderer's camera rays go through Accel::intersectStream (rtcIntersect1M). For every ray it must find
// the triangle Accel::intersect finds, with the same bits of t and barycentrics (refineHit recomputes them from the
// triangle), and the observer must see each ray once, in order, as one stream.
TEST(AccelObserver, StreamsFindWhatSingleRaysFindToTheBit) {
    class Streams final : public RayObserver {
    public:
        void onRay(const Ray&, bool) override { ++single; }
        void onStream(const Ray* rays, size_t n) override { streamed.insert(streamed.end(), rays, rays + n); }
        size_t single = 0;
        std::vector<Ray> streamed;
    };
    SceneOverrides ov;
    ov.spp = 1;
    ov.width = ov.height = 48;
    const Scene scene = loadScene(test::sourcePath("examples/demo.json"), ov);
    Accel accel(scene);
    // Every non-shadow ray of a demo render: camera rays (coherent) and bounce rays (incoherent), as one long stream.
    std::vector<Ray> rays;
    Collect c;
    Accel::setRayObserver(&c);
    renderScene(scene);
    Accel::setRayObserver(nullptr);
    rays.insert(rays.end(), c.rays.begin(), c.rays.end());
    ASSERT_GT(rays.size(), size_t(48 * 48));
    std::vector<Hit> hits(rays.size());
    std::vector<uint8_t> found(rays.size());
    Streams s;
    Accel::setRayObserver(&s);
    accel.intersectStream(rays.data(), rays.size(), hits.data(), found.data());
    Accel::setRayObserver(nullptr);
    EXPECT_EQ(s.single, 0u);
    ASSERT_EQ(s.streamed.size(), rays.size());
    EXPECT_EQ(0, std::memcmp(s.streamed.data(), rays.data(), rays.size() * sizeof(Ray)));
    size_t hitCount = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        Hit h;
        const bool a = accel.intersect(rays[i], h);
        ASSERT_EQ(a, bool(found[i])) << "ray " << i;
        if (!a) continue;
        ++hitCount;
        EXPECT_EQ(h.shape, hits[i].shape) << "ray " << i;
        EXPECT_EQ(h.prim, hits[i].prim) << "ray " << i;
        EXPECT_EQ(0, std::memcmp(&h.t, &hits[i].t, sizeof(float))) << "ray " << i;
        EXPECT_EQ(0, std::memcmp(&h.b1, &hits[i].b1, sizeof(float))) << "ray " << i;
        EXPECT_EQ(0, std::memcmp(&h.b2, &hits[i].b2, sizeof(float))) << "ray " << i;
    }
    EXPECT_GT(hitCount, rays.size() / 4);
}
