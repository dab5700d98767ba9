// Charlie sheen lobe (Estevez & Kulla 2017, "Production Friendly Microfacet Sheen BRDF"): the back-scattering fibre
// distribution of cloth and dust, for bsdf.sheen; its GLSL twin is sheen.glsl in this folder.
#pragma once

#include "core/render/bsdf.h"

#include <algorithm>
#include <cmath>

namespace specula {

// Free functions on the local frame (z = normal), shared by the lobe, its albedo table and tests.
namespace sheen {

// Smallest α: below about 0.065 the fitted Λ lets the directional albedo exceed 1 at grazing views (measured by
// quadrature: 1.04 at α = 0.06 and 1.10 at α = 0.05, both at cos θo ≈ 0.005); at 0.08 its maximum is 0.95. The lobe
// clamps α here, sheen.glsl the same.
constexpr float kMinAlpha = 0.08f;

// D(h) = (2 + 1/α) sin(θh)^(1/α) / (2π)   (Estevez & Kulla 2017, §2, the "Charlie" distribution), normalised so
// that ∫ D(h) cos θh dωh = 1 over the hemisphere. sin^(1/α) is written (sin²)^(1/(2α)): no square root.
inline float ndf(float cosThetaH, float alpha) {
    if (cosThetaH <= 0.f) return 0.f;
    const float sin2 = std::max(0.f, 1.f - cosThetaH * cosThetaH);
    const float invAlpha = 1.f / alpha;
    return (2.f + invAlpha) * std::pow(sin2, 0.5f * invAlpha) * (0.5f * kInvPi);
}

// The fitted exponent of Λ, L(x) = a / (1 + b x^c) + d x + e (Estevez & Kulla 2017, §3, Table 1): each coefficient
// interpolates its α = 0 and α = 1 fits with t = (1 − α)², p = (1 − t) p(α=1) + t p(α=0).
inline float lambdaExponent(float x, float alpha) {
    const float t = (1.f - alpha) * (1.f - alpha);
    auto mix = [t](float atOne, float atZero) { return atOne * (1.f - t) + atZero * t; };
    const float a = mix(21.5473f, 25.3245f), b = mix(3.82987f, 3.32435f), c = mix(0.19823f, 0.16801f),
                d = mix(-1.97760f, -1.27393f), e = mix(-4.32054f, -4.85967f);
    return a / (1.f + b * std::pow(x, c)) + d * x + e;
}

// Λ(θ) = exp(L(cos θ)) for cos θ < 0.5, exp(2 L(0.5) − L(1 − cos θ)) above (Estevez & Kulla 2017, §3: the fit holds
// for θ > 60°; the mirrored form continues it smoothly to the pole). Without the paper's terminator softening
// Λ^(1 + 2(1 − cos θ)^8), which is applied to the light only and would break reciprocity.
// 1 − cos θ is clamped at 0: a unit vector's z can round above 1, and x^c of a negative x is NaN.
inline float lambda(float cosTheta, float alpha) {
    if (cosTheta < 0.5f) return std::exp(lambdaExponent(cosTheta, alpha));
    return std::exp(2.f * lambdaExponent(0.5f, alpha) - lambdaExponent(std::max(1.f - cosTheta, 0.f), alpha));
}

// f·cos θi = D(h) G2(wo, wi) / (4 cos θo), G2 = 1 / (1 + Λ(wo) + Λ(wi)) (height-correlated form, as in the paper);
// zero unless both directions are above the surface.
inline float reflectanceCos(const Vec3& wo, const Vec3& wi, float alpha) {
    if (wo.z <= 0.f || wi.z <= 0.f) return 0.f;
    Vec3 h = wo + wi;
    const float len = glm::length(h);
    if (len == 0.f) return 0.f;
    h /= len;
    const float g = 1.f / (1.f + lambda(wo.z, alpha) + lambda(wi.z, alpha));
    return ndf(h.z, alpha) * g / (4.f * wo.z);
}

// Directional albedo ∫ f cos θi dωi for view cos θo and α: bilinear in a table built by quadrature on first use
// (sheen_lobe.cpp). For lobe selection and the albedo AOV only.
float directionalAlbedo(float cosThetaO, float alpha);

}  // namespace sheen

// Charlie sheen: f·cos = D(h) G2 / (4 cos θo) times the tint; wi sampled uniformly over the hemisphere (pdf 1/(2π)):
// the lobe is broad and peaks towards grazing angles, where a cosine-weighted density would starve it.
class SheenLobe final : public BsdfLobe {
public:
    SheenLobe(float alpha, const Color3& tint) : alpha_(std::clamp(alpha, sheen::kMinAlpha, 1.f)), tint_(tint) {}

    // Diffuse category (the diffuse AOV), as Cycles files its sheen closures: a broad fibre lobe, no highlight.
    LobeKind kind() const override { return LobeKind::Diffuse; }
    using BsdfLobe::sample;

    LobeValue evalPdf(const LobeQuery& q) const override {
        if (q.wo.z <= 0.f || q.wi.z <= 0.f) return {};
        return {tint_ * sheen::reflectanceCos(q.wo, q.wi, alpha_), 0.5f * kInvPi};
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        if (q.wo.z <= 0.f) return false;
        const float z = u.x, r = std::sqrt(std::max(0.f, 1.f - z * z)), phi = 2.f * kPi * u.y;
        wi = Vec3(r * std::cos(phi), r * std::sin(phi), z);
        return wi.z > 0.f;
    }
    Color3 albedo(const Vec3& wo) const override { return tint_ * sheen::directionalAlbedo(wo.z, alpha_); }

    const char* modelName() const override { return "sheen"; }
    void parameters(const LobeQuery&, LobeParameters& out) const override { out.push_back({"alpha", {alpha_}}); }

private:
    float alpha_;
    Color3 tint_;
};

}  // namespace specula
