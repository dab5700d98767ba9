// The BRDF assembly of spec S0 and S7 (C20 Eq. 14): the half vector with its rejections and f cos = G D / (4 wo.z),
// D = P / h_z^4, V-cavity G, shared by the lobe, the per-query reference and the limiting Beckmann lobe.
#pragma once

#include "core/math/math.h"
#include "nodes/bsdf/glint/glint_correlation.h"

#include <algorithm>
#include <cmath>

namespace specula::glint {

// S0 and the half vector: h = (wo + wi) / |wo + wi|, rejected (false) where wo.z, wi.z or h.z <= 0, |wo + wi| is not
// > 0, or wo.h <= 0 (a NaN h.z or wo.h is not rejected). wi.h is returned untested: the pdf needs h where wi.h <= 0.
struct HalfVector {
    Vec3 h{0.f};
    float len = 0.f, woh = 0.f, wih = 0.f;
};
inline bool halfVector(const Vec3& wo, const Vec3& wi, HalfVector& hv) {
    if (wo.z <= 0.f || wi.z <= 0.f) return false;
    const Vec3 hs = wo + wi;
    hv.len = std::sqrt(glm::dot(hs, hs));
    if (!(hv.len > 0.f)) return false;
    hv.h = hs / hv.len;
    hv.woh = glm::dot(wo, hv.h);
    hv.wih = glm::dot(wi, hv.h);
    return !(hv.h.z <= 0.f || hv.woh <= 0.f);
}

// S7 (C20 Eq. 14): f cos = G D / (4 wo.z) with D = P / h_z^4 and the V-cavity G = G1(wo) G1(wi),
// G1(w) = min(1, 2 h_z w_z / (w.h)), for the patch SDF P at h~ (wi.h > 0).
inline float fCosFromSdf(float P, const HalfVector& hv, const Vec3& wo, const Vec3& wi) {
    const Vec3& h = hv.h;
    const float hz2 = h.z * h.z;
    const float D = P / (hz2 * hz2);
    const float G = std::min(1.f, 2.f * h.z * wo.z / hv.woh) * std::min(1.f, 2.f * h.z * wi.z / hv.wih);
    return G * D / (4.f * wo.z);
}

// Reference limit (spec S7, "Limit as density -> infinity"): Cook-Torrance with P_B and the same V-cavity G.
inline float beckmannFCosScalar(const GlintShape& shape, const Vec3& wo, const Vec3& wi) {
    HalfVector hv;
    if (!halfVector(wo, wi, hv) || hv.wih <= 0.f) return 0.f;
    const Vec3& h = hv.h;
    return fCosFromSdf(beckmannSdf(Vec2(-h.x / h.z, -h.y / h.z), shape), hv, wo, wi);
}

// The solid-angle pdf of sampleBeckmannHalf: P_B(h~) / h_z^3 / (4 wo.h).
inline float beckmannHalfPdf(const GlintShape& s, const Vec3& wo, const Vec3& wi) {
    HalfVector hv;
    if (!halfVector(wo, wi, hv)) return 0.f;
    const Vec3& h = hv.h;
    return beckmannSdf(Vec2(-h.x / h.z, -h.y / h.z), s) / (h.z * h.z * h.z) / (4.f * hv.woh);
}

}  // namespace specula::glint
