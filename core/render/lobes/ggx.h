// Anisotropic GGX (Trowbridge-Reitz) microfacet reflection with height-correlated Smith masking-
// shadowing (Heitz 2014, Eq. 99) and visible-normal importance sampling (Heitz 2018, JCGT 7(4)).
#pragma once

#include "core/ltc/ltc_ggx.h"
#include "core/render/bsdf.h"
#include "core/render/lobes/fresnel.h"

namespace specula {

// Free functions on the local frame (z = normal) so filtered variants and tests can reuse them.
namespace ggx {

// D(h) = 1 / (π αx αy (hx²/αx² + hy²/αy² + hz²)²)   (Walter et al. 2007, Eq. 33, anisotropic form)
inline float ndf(const Vec3& h, float ax, float ay) {
    if (h.z <= 0.f) return 0.f;
    float e = sqr(h.x / ax) + sqr(h.y / ay) + h.z * h.z;
    return 1.f / (kPi * ax * ay * e * e);
}

// Smith Λ = (−1 + sqrt(1 + α²tan²θ)) / 2 of the GGX distribution (Heitz 2014, Eq. 86) from the direction's projected
// α²tan²θ: the one home of the formula for both Λ forms, ggx::lambda below (axis-aligned, float) and fggx::lambda /
// fggx::PreparedGgx::lambda (roughness matrix A, α²tan²θ = w⊥ᵀ A w⊥ / wz², double; A = diag(αx², αy²) is the
// axis-aligned case). Each form keeps its own precision and operation order, so renders do not change.
// GLSL twin: spc_ggx_lambda_of_tan2 (nodes/shared/ggx_microfacet.glsl).
template <class T>
inline T lambdaOfTan2(T a2tan2) {
    return T(0.5) * (T(-1) + std::sqrt(T(1) + a2tan2));
}

// Smith Λ(w) for the anisotropic GGX distribution (Heitz 2014, Eq. 86): α²tan²θ = ((αx wx)² + (αy wy)²) / wz².
inline float lambda(const Vec3& w, float ax, float ay) {
    float z2 = w.z * w.z;
    if (z2 <= 0.f) return 1e30f;
    float a2tan2 = (sqr(ax * w.x) + sqr(ay * w.y)) / z2;
    return lambdaOfTan2(a2tan2);
}

inline float g1(const Vec3& w, float ax, float ay) { return 1.f / (1.f + lambda(w, ax, ay)); }

// Height-correlated masking-shadowing G2 = 1 / (1 + Λ(wo) + Λ(wi)).
inline float g2(const Vec3& wo, const Vec3& wi, float ax, float ay) {
    return 1.f / (1.f + lambda(wo, ax, ay) + lambda(wi, ax, ay));
}

// Distribution of visible normals D_wo(h) = G1(wo) max(0, wo·h) D(h) / wo.z (Heitz 2018, Eq. 1).
inline float visibleNdf(const Vec3& wo, const Vec3& h, float ax, float ay) {
    float woh = glm::dot(wo, h);
    if (woh <= 0.f || wo.z <= 0.f) return 0.f;
    return g1(wo, ax, ay) * woh * ndf(h, ax, ay) / wo.z;
}

// Samples a visible normal (Heitz 2018, Listing 1).
inline Vec3 sampleVisibleNormal(const Vec3& wo, const Vec2& u, float ax, float ay) {
    Vec3 vh = glm::normalize(Vec3(ax * wo.x, ay * wo.y, wo.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    Vec3 t1 = lensq > 0.f ? Vec3(-vh.y, vh.x, 0.f) / std::sqrt(lensq) : Vec3(1.f, 0.f, 0.f);
    Vec3 t2 = glm::cross(vh, t1);
    float r = std::sqrt(u.x);
    float phi = 2.f * kPi * u.y;
    float p1 = r * std::cos(phi);
    float p2 = r * std::sin(phi);
    float s = 0.5f * (1.f + vh.z);
    p2 = (1.f - s) * safeSqrt(1.f - p1 * p1) + s * p2;
    Vec3 nh = p1 * t1 + p2 * t2 + safeSqrt(1.f - p1 * p1 - p2 * p2) * vh;
    return glm::normalize(Vec3(ax * nh.x, ay * nh.y, std::max(1e-7f, nh.z)));
}

inline Vec3 reflect(const Vec3& wo, const Vec3& h) { return 2.f * glm::dot(wo, h) * h - wo; }

// Roughness is clamped so that the NDF stays representable in float.
constexpr float kMinAlpha = 1e-4f;

}  // namespace ggx

class GgxLobe final : public ltc::GgxPolygonLobe<GgxLobe> {
public:
    GgxLobe(float alphaX, float alphaY, const Fresnel& fresnel, const Color3& tint = Color3(1.f))
        : ax_(std::max(alphaX, ggx::kMinAlpha)), ay_(std::max(alphaY, ggx::kMinAlpha)), fresnel_(fresnel), tint_(tint) {}

    LobeKind kind() const override { return LobeKind::Specular; }
    using BsdfLobe::sample;

    // f·cos = F(wo·h) D(h) G2(wo,wi) / (4 wo.z); pdf = D_wo(h) / (4 wo·h)
    LobeValue evalPdf(const LobeQuery& q) const override {
        const Vec3& wo = q.wo;
        const Vec3& wi = q.wi;
        if (wo.z <= 0.f || wi.z <= 0.f) return {};
        Vec3 h = wo + wi;
        float len = glm::length(h);
        if (len == 0.f) return {};
        h /= len;
        float d = ggx::ndf(h, ax_, ay_);
        float g = ggx::g2(wo, wi, ax_, ay_);
        LobeValue v;
        v.f = tint_ * fresnel_.eval(glm::dot(wo, h)) * (d * g / (4.f * wo.z));
        float woh = glm::dot(wo, h);
        if (woh > 0.f) v.pdf = ggx::visibleNdf(wo, h, ax_, ay_) / (4.f * woh);
        return v;
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        const Vec3& wo = q.wo;
        if (wo.z <= 0.f) return false;
        Vec3 h = ggx::sampleVisibleNormal(wo, u, ax_, ay_);
        wi = ggx::reflect(wo, h);
        return wi.z > 0.f;
    }
    // Approximation used only for lobe selection and the albedo AOV.
    Color3 albedo(const Vec3& wo) const override { return tint_ * fresnel_.eval(std::max(wo.z, 0.f)); }

    const char* modelName() const override { return "ggx"; }
    void parameters(const LobeQuery&, LobeParameters& out) const override { out.push_back({"alpha", {ax_, ay_}}); }

    // Quad lights (ltc::GgxPolygonLobe): the fitted LTC of this GGX lobe (HDHN16; isotropic 64×64 table, anisotropic
    // t-EM table) with Fresnel F0·mag + (1 − F0)·fres.
    ltc::Ltc computePolygonLtc(const Vec3& wo) const {
        return ltc::ggxRoughnessMatrix(ltc::builtinTables(), double(ax_) * ax_, 0.0, double(ay_) * ay_, wo);
    }
    const Fresnel& polygonFresnel() const { return fresnel_; }
    Color3 polygonTint() const { return tint_; }

    float alphaX() const { return ax_; }
    float alphaY() const { return ay_; }

private:
    float ax_, ay_;
    Fresnel fresnel_;
    Color3 tint_;
};

}  // namespace specula
