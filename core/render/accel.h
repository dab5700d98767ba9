// Ray intersection through Embree 3 (one BVH over all world-space triangles) and reconstruction of
// the full shading point (exact analytic attributes, ray differentials) at a hit.
#pragma once

#include "core/render/ray.h"
#include "core/render/shading.h"

#include <cstdint>
#include <memory>

namespace specula {

struct Scene;

struct Hit {
    float t = 0.f;
    uint32_t shape = 0, prim = 0;
    float b1 = 0.f, b2 = 0.f;  // barycentrics of vertices 1 and 2
};

// Sees every ray the renderer traces through an Accel (bench_embree_limit records them to replay through Embree
// alone). Called from the render threads concurrently; null (the default) costs one load and branch per ray.
class RayObserver {
public:
    virtual ~RayObserver() = default;
    virtual void onRay(const Ray& ray, bool shadow) = 0;
    // The rays of one Accel::intersectStream call (coherent camera rays), in order; by default one onRay each.
    virtual void onStream(const Ray* rays, size_t n) {
        for (size_t k = 0; k < n; ++k) onRay(rays[k], false);
    }
};

class Accel {
public:
    // embreeConfig: Embree's device configuration string (tests pin its ISA with "max_isa=sse4.2" and the like).
    explicit Accel(const Scene& scene, const char* embreeConfig = "threads=0");
    ~Accel();
    Accel(const Accel&) = delete;
    Accel& operator=(const Accel&) = delete;

    bool intersect(const Ray& ray, Hit& hit) const;
    // n rays traced as one coherent stream (Embree's rtcIntersect1M; camera rays of neighbouring pixels, issue 37):
    // found[k] = 1 and hits[k] set where rays[k] hits, each hit refined as intersect() refines it, so a ray gets the
    // same bits here as through intersect() whenever Embree picks the same triangle (the stream and single-ray
    // kernels agree on the triangle; they may differ in t and u, v, which refineHit recomputes).
    void intersectStream(const Ray* rays, size_t n, Hit* hits, uint8_t* found) const;
    bool occluded(const Ray& ray) const;
    // Embree's answer alone: rtcIntersect1 / rtcOccluded1 on this BVH, without the exact recomputation of the hit
    // (refineHit) and unobserved. For bench_embree_limit, the renderer's lower bound (issue 15 item 2).
    bool embreeIntersect(const Ray& ray, Hit& hit) const;
    // intersectStream's Embree part alone: rtcIntersect1M on up to 64 rays at a time, unrefined and unobserved.
    void embreeIntersectStream(const Ray* rays, size_t n, Hit* hits, uint8_t* found) const;
    bool embreeOccluded(const Ray& ray) const;
    // Process-wide; set it before a render and clear it after (not while one runs).
    static void setRayObserver(RayObserver* observer);

    // Builds the shading point of a hit; if the ray carries differentials, computes dp/dx, dp/dy,
    // duv, dn and dwo (pbrt-v4 SurfaceInteraction::ComputeDifferentials). The geometric and shading
    // normals are flipped to face the ray's origin side.
    // derivatives = false (a material that reads none, Material::needsDerivatives) skips dn/du, dn/dv and the screen
    // differentials: hasDifferentials stays false; everything else, the position included, is the same.
    ShadingPoint shadingPoint(const RayDifferential& ray, const Hit& hit, bool derivatives = true) const;
    // The ray against the plane of triangle (on.shape, on.prim), with barycentrics extrapolated beyond the triangle:
    // what a GPU helper invocation of that triangle computes for a neighbouring pixel of its 2x2 quad. False when
    // the ray is parallel to the plane or meets it behind the origin.
    bool extrapolate(const Ray& ray, const Hit& on, Hit& out) const;

private:
    // t and barycentrics of Embree's hit recomputed from its triangle, the same bits on every CPU.
    void refineHit(const Ray& ray, Hit& hit) const;

    struct Impl;
    std::unique_ptr<Impl> impl_;
    const Scene& scene_;
};

// Offset a ray origin off a surface along the geometric normal, towards direction w (robust to
// self-intersection without an epsilon in t; scale-aware).
Vec3 offsetRayOrigin(const Vec3& p, const Vec3& ng, const Vec3& w);
// duv/dx, duv/dy (least squares on dpdu, dpdv) and dn/dx, dn/dy of a shading point whose dpdx, dpdy are set.
void surfaceDifferentials(ShadingPoint& sp);

}  // namespace specula
