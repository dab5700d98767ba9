// Embree 3 BVH over world-space triangles; hit reconstruction with exact analytic attributes and
// ray differentials (pbrt-v4 §10.1.1: dp/dx from the tangent-plane intersection of offset rays).
#include "core/render/accel.h"

#include "core/scene/scene.h"
#include "core/util/error.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace specula {

struct Accel::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
};

static void embreeError(void*, RTCError code, const char* str) {
    // Errors are surfaced by checking the scene after commit; keep the message for diagnostics.
    (void)code;
    (void)str;
}

Accel::Accel(const Scene& scene, const char* embreeConfig) : impl_(std::make_unique<Impl>()), scene_(scene) {
    impl_->device = rtcNewDevice(embreeConfig);
    if (!impl_->device) throw std::runtime_error("Embree: cannot create device");
    rtcSetDeviceErrorFunction(impl_->device, embreeError, nullptr);
    impl_->scene = rtcNewScene(impl_->device);
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);  // watertight: no cracks between triangles
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
    for (size_t s = 0; s < scene.shapes.size(); ++s) {
        const TriangleMesh& m = scene.shapes[s].mesh;
        RTCGeometry g = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), m.positions.size()));
        for (size_t i = 0; i < m.positions.size(); ++i) {
            v[3 * i + 0] = m.positions[i].x;
            v[3 * i + 1] = m.positions[i].y;
            v[3 * i + 2] = m.positions[i].z;
        }
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(unsigned), m.indices.size()));
        for (size_t i = 0; i < m.indices.size(); ++i) {
            idx[3 * i + 0] = m.indices[i].x;
            idx[3 * i + 1] = m.indices[i].y;
            idx[3 * i + 2] = m.indices[i].z;
        }
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(impl_->scene, g, unsigned(s));
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(impl_->scene);
}

Accel::~Accel() {
    if (impl_->scene) rtcReleaseScene(impl_->scene);
    if (impl_->device) rtcReleaseDevice(impl_->device);
}

namespace {
RayObserver* gRayObserver = nullptr;
}  // namespace

void Accel::setRayObserver(RayObserver* observer) { gRayObserver = observer; }

bool Accel::intersect(const Ray& ray, Hit& hit) const {
    if (gRayObserver) gRayObserver->onRay(ray, false);
    if (!embreeIntersect(ray, hit)) return false;
    refineHit(ray, hit);
    return true;
}

namespace {
// A ray as Embree takes it (no motion blur, every geometry visible), with no hit yet.
RTCRayHit toRtcRayHit(const Ray& ray, unsigned id) {
    RTCRayHit r;
    r.ray.org_x = ray.o.x;
    r.ray.org_y = ray.o.y;
    r.ray.org_z = ray.o.z;
    r.ray.dir_x = ray.d.x;
    r.ray.dir_y = ray.d.y;
    r.ray.dir_z = ray.d.z;
    r.ray.tnear = ray.tMin;
    r.ray.tfar = ray.tMax;
    r.ray.time = 0.f;
    r.ray.mask = 0xFFFFFFFF;
    r.ray.id = id;
    r.ray.flags = 0;
    r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return r;
}
// Embree's answer as a Hit (unrefined); false on a miss.
bool fromRtcRayHit(const RTCRayHit& r, Hit& hit) {
    if (r.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit.t = r.ray.tfar;
    hit.shape = r.hit.geomID;
    hit.prim = r.hit.primID;
    hit.b1 = r.hit.u;
    hit.b2 = r.hit.v;
    return true;
}
}  // namespace

void Accel::intersectStream(const Ray* rays, size_t n, Hit* hits, uint8_t* found) const {
    if (gRayObserver) gRayObserver->onStream(rays, n);
    embreeIntersectStream(rays, n, hits, found);
    for (size_t k = 0; k < n; ++k)
        if (found[k]) refineHit(rays[k], hits[k]);
}

void Accel::embreeIntersectStream(const Ray* rays, size_t n, Hit* hits, uint8_t* found) const {
    constexpr size_t kChunk = 64;
    RTCRayHit rh[kChunk];
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (size_t begin = 0; begin < n; begin += kChunk) {
        const size_t m = std::min(kChunk, n - begin);
        for (size_t k = 0; k < m; ++k) rh[k] = toRtcRayHit(rays[begin + k], unsigned(k));
        rtcIntersect1M(impl_->scene, &ctx, rh, unsigned(m), sizeof(RTCRayHit));
        for (size_t k = 0; k < m; ++k) found[begin + k] = fromRtcRayHit(rh[k], hits[begin + k]);
    }
}

bool Accel::embreeIntersect(const Ray& ray, Hit& hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh = toRtcRayHit(ray, 0);
    rtcIntersect1(impl_->scene, &ctx, &rh);
    return fromRtcRayHit(rh, hit);
}

// Embree picks its kernels by the CPU's ISA at run time, and their t, u, v differ in the last bits between SSE,
// AVX2 and AVX-512 (approximate reciprocals such as rcp14 vs rcp + Newton; other association orders), so the same
// scene rendered on two machines differed slightly everywhere. Embree still decides *which* triangle is hit; the
// hit's t and barycentrics are recomputed here from that triangle alone, in double precision with IEEE-rounded
// scalar operations only (Möller & Trumbore 1997), so they are the same bits on every x86-64 machine.
void Accel::refineHit(const Ray& ray, Hit& hit) const {
    const TriangleMesh& m = scene_.shapes[hit.shape].mesh;
    const glm::uvec3 idx = m.indices[hit.prim];
    using D3 = glm::dvec3;
    const D3 p0(m.positions[idx.x]), o(ray.o), d(ray.d);
    const D3 e1 = D3(m.positions[idx.y]) - p0, e2 = D3(m.positions[idx.z]) - p0;
    const D3 pv = glm::cross(d, e2);
    const double det = glm::dot(e1, pv);
    // Embree found a hit, so det is non-zero unless the ray grazes the plane; keep Embree's values then.
    if (!(std::abs(det) > 1e-300)) return;
    const double inv = 1.0 / det;
    const D3 tv = o - p0, qv = glm::cross(tv, e1);
    double u = glm::dot(tv, pv) * inv, v = glm::dot(d, qv) * inv;
    const double t = glm::dot(e2, qv) * inv;
    if (!std::isfinite(t) || !std::isfinite(u) || !std::isfinite(v)) return;
    // Embree's watertight test accepted the hit; the recomputation can land a rounding step outside the triangle
    // or the ray's interval, so clamp to both.
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0 - u);
    hit.t = std::clamp(float(t), ray.tMin, ray.tMax);
    hit.b1 = float(u);
    hit.b2 = float(v);
}

bool Accel::occluded(const Ray& ray) const {
    if (gRayObserver) gRayObserver->onRay(ray, true);
    return embreeOccluded(ray);
}

bool Accel::embreeOccluded(const Ray& ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    r.org_x = ray.o.x;
    r.org_y = ray.o.y;
    r.org_z = ray.o.z;
    r.dir_x = ray.d.x;
    r.dir_y = ray.d.y;
    r.dir_z = ray.d.z;
    r.tnear = ray.tMin;
    r.tfar = ray.tMax;
    r.time = 0.f;
    r.mask = 0xFFFFFFFF;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(impl_->scene, &ctx, &r);
    return r.tfar < 0.f;  // Embree sets tfar = -inf on a hit
}

// Partial derivatives of an attribute over a triangle with respect to (u, v) (pbrt-v4 Triangle::InteractionFromIntersection).
template <typename T>
static bool triangleUvPartials(const Vec2 uv[3], const T& a0, const T& a1, const T& a2, T& dadu, T& dadv) {
    Vec2 duv02 = uv[0] - uv[2], duv12 = uv[1] - uv[2];
    T da02 = a0 - a2, da12 = a1 - a2;
    float det = duv02.x * duv12.y - duv02.y * duv12.x;
    if (std::abs(det) < 1e-12f) return false;
    float inv = 1.f / det;
    dadu = (duv12.y * da02 - duv02.y * da12) * inv;
    dadv = (duv02.x * da12 - duv12.x * da02) * inv;
    return true;
}

// d/du of normalize(M n) given dn/du: (I - n'n'ᵀ) M dn / |M n|.
static Vec3 transformNormalDerivative(const Mat3& m, const Vec3& n, const Vec3& dn) {
    Vec3 mn = m * n;
    float len = glm::length(mn);
    Vec3 nw = mn / len;
    Vec3 mdn = m * dn;
    return (mdn - nw * glm::dot(nw, mdn)) / len;
}

bool Accel::extrapolate(const Ray& ray, const Hit& on, Hit& out) const {
    const TriangleMesh& m = scene_.shapes[on.shape].mesh;
    const glm::uvec3 idx = m.indices[on.prim];
    const Vec3 p0 = m.positions[idx.x], e1 = m.positions[idx.y] - p0, e2 = m.positions[idx.z] - p0;
    const Vec3 n = glm::cross(e1, e2);
    const float den = glm::dot(ray.d, n);
    if (std::abs(den) <= 1e-20f) return false;
    const float t = glm::dot(p0 - ray.o, n) / den;
    if (!(t > 0.f)) return false;
    // Barycentrics of the plane point in the triangle's own (possibly extrapolated) affine frame.
    const Vec3 d = ray.o + t * ray.d - p0;
    const float d00 = glm::dot(e1, e1), d01 = glm::dot(e1, e2), d11 = glm::dot(e2, e2);
    const float d20 = glm::dot(d, e1), d21 = glm::dot(d, e2);
    const float det = d00 * d11 - d01 * d01;
    if (!(std::abs(det) > 0.f)) return false;
    out = on;
    out.t = t;
    out.b1 = (d11 * d20 - d01 * d21) / det;
    out.b2 = (d00 * d21 - d01 * d20) / det;
    return true;
}

ShadingPoint Accel::shadingPoint(const RayDifferential& ray, const Hit& hit, bool derivatives) const {
    const ShapeInstance& sh = scene_.shapes[hit.shape];
    const TriangleMesh& m = sh.mesh;
    const glm::uvec3 idx = m.indices[hit.prim];
    const float b0 = 1.f - hit.b1 - hit.b2;
    const Vec3 p0 = m.positions[idx.x], p1 = m.positions[idx.y], p2 = m.positions[idx.z];

    ShadingPoint sp;
    sp.shapeId = hit.shape;
    sp.primId = hit.prim;
    sp.p = sp.pGeom = b0 * p0 + hit.b1 * p1 + hit.b2 * p2;
    Vec3 ngRaw = glm::cross(p1 - p0, p2 - p0);
    sp.ng = glm::normalize(ngRaw);
    sp.wo = -glm::normalize(ray.d);

    Vec2 uv[3] = {{0, 0}, {1, 0}, {1, 1}};
    if (!m.uvs.empty()) {
        uv[0] = m.uvs[idx.x];
        uv[1] = m.uvs[idx.y];
        uv[2] = m.uvs[idx.z];
    }
    sp.uv = b0 * uv[0] + hit.b1 * uv[1] + hit.b2 * uv[2];
    if (!triangleUvPartials(uv, p0, p1, p2, sp.dpdu, sp.dpdv)) {
        Frame f = Frame::fromNormal(sp.ng);
        sp.dpdu = f.t;
        sp.dpdv = f.b;
    }
    if (!m.normals.empty()) {
        const Vec3 n0 = m.normals[idx.x], n1 = m.normals[idx.y], n2 = m.normals[idx.z];
        Vec3 n = b0 * n0 + hit.b1 * n1 + hit.b2 * n2;
        float len = glm::length(n);
        sp.n = len > 0.f ? n / len : sp.ng;
        Vec3 dndu, dndv;
        if (derivatives && triangleUvPartials(uv, n0, n1, n2, dndu, dndv) && len > 0.f) {
            // derivative of the normalised interpolated normal
            sp.dndu = (dndu - sp.n * glm::dot(sp.n, dndu)) / len;
            sp.dndv = (dndv - sp.n * glm::dot(sp.n, dndv)) / len;
        }
    } else {
        sp.n = sp.ng;
    }
    Vec3 tangent = sp.dpdu;
    float handed = 1.f;
    if (!m.tangents.empty()) {
        Vec4 t = b0 * m.tangents[idx.x] + hit.b1 * m.tangents[idx.y] + hit.b2 * m.tangents[idx.z];
        if (glm::dot(Vec3(t), Vec3(t)) > 0.f) tangent = Vec3(t);
        handed = m.tangents[idx.x].w < 0.f ? -1.f : 1.f;
    }

    if (sh.surface) {
        // Exact attributes of the analytic surface at the hit (object space -> world).
        // The tessellation's hit differs from the exact surface by the facet sagitta, which would make
        // positions (and hence differentials) jump between facets. Refine t by Newton steps on the exact
        // surface: intersect the ray with the tangent plane at the projection of the current point.
        const Vec3 oObj = Vec3(sh.worldToObject * Vec4(ray.o, 1.f));
        const Vec3 dObj = Mat3(sh.worldToObject) * ray.d;
        float t = hit.t;
        // Only rays with differentials need positions continuous across facets; planar shapes are exact.
        const int iterations = (ray.hasDifferentials && !sh.surface->isPlanar()) ? 2 : 0;
        for (int it = 0; it < iterations; ++it) {
            Vec3 q, qn;
            sh.surface->closest(oObj + t * dObj, q, qn);
            float denom = glm::dot(qn, dObj);
            if (std::abs(denom) < 1e-6f) break;
            float dt = glm::dot(qn, q - (oObj + t * dObj)) / denom;
            if (!std::isfinite(dt) || std::abs(dt) > 0.05f * hit.t) break;  // stay near the facet hit
            t += dt;
        }
        SurfaceGeometry g = sh.surface->at(oObj + t * dObj);
        Mat3 lin(sh.objectToWorld);
        sp.p = Vec3(sh.objectToWorld * Vec4(g.p, 1.f));
        sp.uv = g.uv;
        sp.dpdu = lin * g.dpdu;
        sp.dpdv = lin * g.dpdv;
        sp.n = glm::normalize(sh.normalToWorld * g.n);
        if (derivatives) {
            sp.dndu = transformNormalDerivative(sh.normalToWorld, g.n, g.dndu);
            sp.dndv = transformNormalDerivative(sh.normalToWorld, g.n, g.dndv);
        }
        tangent = sp.dpdu;
        handed = glm::dot(glm::cross(sp.n, sp.dpdu), sp.dpdv) < 0.f ? -1.f : 1.f;
        if (glm::dot(sp.ng, sp.n) < 0.f) sp.ng = -sp.ng;  // keep the triangle normal on the exact normal's side
    } else if (!m.normals.empty() && glm::dot(sp.ng, sp.n) < 0.f) {
        sp.ng = -sp.ng;  // mesh winding disagrees with its normals: trust the normals
    }

    // Face the ray's side.
    sp.frontFacing = glm::dot(sp.ng, ray.d) < 0.f;
    if (!sp.frontFacing) {
        sp.ng = -sp.ng;
        sp.n = -sp.n;
        sp.dndu = -sp.dndu;
        sp.dndv = -sp.dndv;
    }
    sp.tangent = Vec4(glm::normalize(tangent), handed);
    sp.frame = Frame::fromNormalTangent(sp.n, Vec3(sp.tangent));

    if (ray.hasDifferentials && derivatives) {
        // Tangent plane of the surface the shading point lies on: the exact one for analytic shapes.
        const Vec3 planeN = sh.surface ? sp.n : sp.ng;
        float d = glm::dot(planeN, sp.p);
        float ndx = glm::dot(planeN, ray.rxDirection), ndy = glm::dot(planeN, ray.ryDirection);
        if (std::abs(ndx) > 1e-8f && std::abs(ndy) > 1e-8f) {
            float tx = -(glm::dot(planeN, ray.rxOrigin) - d) / ndx;
            float ty = -(glm::dot(planeN, ray.ryOrigin) - d) / ndy;
            Vec3 px = ray.rxOrigin + tx * ray.rxDirection;
            Vec3 py = ray.ryOrigin + ty * ray.ryDirection;
            sp.dpdx = px - sp.p;
            sp.dpdy = py - sp.p;
            surfaceDifferentials(sp);
            Vec3 dn = glm::normalize(ray.d);
            sp.dwodx = -(glm::normalize(ray.rxDirection) - dn);
            sp.dwody = -(glm::normalize(ray.ryDirection) - dn);
            sp.differentialScale = Vec2(ray.differentialScale);
            sp.pixelOffset = ray.pixelOffset;
            sp.hasDifferentials = true;
        }
    }
    return sp;
}

void surfaceDifferentials(ShadingPoint& sp) {
    // Least-squares solve of dp/dx = dp/du du/dx + dp/dv dv/dx.
    float a00 = glm::dot(sp.dpdu, sp.dpdu), a01 = glm::dot(sp.dpdu, sp.dpdv), a11 = glm::dot(sp.dpdv, sp.dpdv);
    float det = a00 * a11 - a01 * a01;
    float invDet = std::abs(det) > 1e-20f ? 1.f / det : 0.f;
    auto solve = [&](const Vec3& dp) {
        float b0_ = glm::dot(sp.dpdu, dp), b1_ = glm::dot(sp.dpdv, dp);
        Vec2 r((a11 * b0_ - a01 * b1_) * invDet, (a00 * b1_ - a01 * b0_) * invDet);
        return glm::clamp(r, Vec2(-1e8f), Vec2(1e8f));
    };
    sp.duvdx = solve(sp.dpdx);
    sp.duvdy = solve(sp.dpdy);
    sp.dndx = sp.dndu * sp.duvdx.x + sp.dndv * sp.duvdx.y;
    sp.dndy = sp.dndu * sp.duvdy.x + sp.dndv * sp.duvdy.y;
}

Vec3 offsetRayOrigin(const Vec3& p, const Vec3& ng, const Vec3& w) {
    float scale = 1e-4f * std::max(1.f, std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z))));
    return p + ng * (glm::dot(w, ng) >= 0.f ? scale : -scale);
}

}  // namespace specula
