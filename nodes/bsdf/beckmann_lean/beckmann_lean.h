// Beckmann microfacet reflection with a LEAN slope distribution (Olano & Baker 2010): a non-centred anisotropic
// Gaussian of slopes with mean μ and covariance Σ + (α²/2) I; the lobe bsdf.beckmann_lean builds (CPU side).
#pragma once

#include "core/ltc/ltc_ggx.h"
#include "core/render/bsdf.h"
#include "core/render/lobes/fresnel.h"

#include <cmath>

namespace specula::lean {

// Slope convention (glint-brdf.md §1): slope(w) = (-wx/wz, -wy/wz); D(h) = P22(slope(h)) / hz^4.

// Standard normal CDF Φ(d) = erfc(-d/√2)/2 with Abramowitz & Stegun 7.1.26 for erfc (|error of erf| ≤ 1.5e-7),
// written as poly(t)·exp(-x²) so the tail keeps its relative accuracy. The GLSL twin uses the same formula.
inline float normalCdf(float d) {
    float x = std::abs(d) * 0.70710678118654752f;
    float t = 1.f / (1.f + 0.3275911f * x);
    float poly = t * (0.254829592f + t * (-0.284496736f + t * (1.421413741f + t * (-1.453152027f + t * 1.061405429f))));
    float half = 0.5f * poly * std::exp(-x * x);  // erfc(x)/2
    return d >= 0.f ? 1.f - half : half;
}

// Total slope covariance of the lobe: the LEAN covariance (projected to PSD) plus the material's Beckmann
// roughness α as an isotropic variance α²/2 per axis (Olano & Baker 2010: Σ_total = Σ + (1/s) I with the
// Beckmann variance 1/s = α²/2; glint-brdf.md §1: α = √2 σ). α is clamped to >= kMinAlpha so Σ is invertible.
struct SlopeGaussian {
    Vec2 mean{0.f};
    float a = 0, b = 0, c = 0;  // Σ = [[a, c], [c, b]]
    float det = 0;
};
constexpr float kMinAlpha = 1e-3f;

inline SlopeGaussian makeSlopeGaussian(Vec2 mean, Vec3 cov, float alpha) {
    SlopeGaussian g;
    g.mean = mean;
    float xx = std::max(cov.x, 0.f), yy = std::max(cov.y, 0.f);
    float lim = std::sqrt(xx * yy);
    float xy = std::min(std::max(cov.z, -lim), lim);
    float al = std::max(alpha, kMinAlpha);
    float v = 0.5f * al * al;
    g.a = xx + v;
    g.b = yy + v;
    g.c = xy;
    g.det = g.a * g.b - g.c * g.c;
    return g;
}

// P22(s) = exp(-½ (s-μ)ᵀ Σ⁻¹ (s-μ)) / (2π sqrt(det Σ))  (Chermain et al. 2021 Eq. 16 / glint-brdf.md S7 P_B, shifted).
inline float slopePdf(const SlopeGaussian& g, Vec2 s) {
    float dx = s.x - g.mean.x, dy = s.y - g.mean.y;
    float q = (g.b * dx * dx - 2.f * g.c * dx * dy + g.a * dy * dy) / g.det;
    return std::exp(-0.5f * q) / (2.f * kPi * std::sqrt(g.det));
}

// D(h) = P22(slope(h)) / hz^4; ∫ D(h) hz dω_h = ∫ P22 ds = 1 exactly.
inline float ndf(const SlopeGaussian& g, const Vec3& h) {
    if (h.z <= 0.f) return 0.f;
    float z2 = h.z * h.z;
    return slopePdf(g, Vec2(-h.x / h.z, -h.y / h.z)) / (z2 * z2);
}

// Masking with a mean slope (issue 9 item 7, docs/conformance.md §LEAN). A non-zero mean slope μ tilts the
// microsurface: its mean plane has the (unnormalised) normal n̄ = (−μx, −μy, 1), and a unit area of the geometric
// plane carries a mean-plane area whose projection towards w is
//   e(w) = w·n̄ = wz − wxy·μ                                       (meanPlaneCosine)
// (the signed projected area of the microfacets, ∫ (w·m) D(m) dm = E[wz − r] = e(w)). The lobe is Smith's
// microsurface model over that mean plane (Heitz 2014 §2-5, with the LEADR reading of a mean slope, Dupuy et al.
// 2013): with r = wxy·s ~ N(m, s²) over the slopes s of the Gaussian (m = wxy·μ, s² = wxyᵀ Σ wxy), the projected
// area of the facets visible from w is
//   A⁺(w) = ∫ max(0, w·m̂) D(m̂) dm̂ = E[(wz − r)⁺] = e Φ(e/s) + s φ(e/s)
// (Heitz 2014 Eq. 72 in slope space), and
//   Λ(w) = A⁺(w) / e(w) − 1  (≥ 0 by Jensen),   G1(w) = 1 / (1 + Λ(w)) = e / A⁺,   G1 = 0 for e(w) ≤ 0:
// a viewer (or light) below the mean microsurface plane sees (lights) none of it, and G1 → 0 continuously as e → 0⁺
// (A⁺ → s φ(0) > 0). The earlier model divided by wz instead of e and clamped Λ at 0, so G1 was 1 below the mean
// plane. For μ = 0 both are exactly Beckmann's Λ = (erf(a) − 1)/2 + e^(−a²)/(2a√π), a = cot θ / α (Walter et al.
// 2007, Eq. 27 with Heitz's Λ form). Returns 1e30 (G1 = 0) for e ≤ 0 or wz ≤ 0.
inline float meanPlaneCosine(const SlopeGaussian& g, const Vec3& w) { return w.z - (w.x * g.mean.x + w.y * g.mean.y); }

// Not the GGX Λ of ggx::lambdaOfTan2: the Gaussian slope distribution has its own Λ (above); its one GLSL twin is
// spc_lean_lambda (beckmann_lean.glsl), checked through bsdf.beckmann_lean's node parity test.
inline float lambda(const SlopeGaussian& g, const Vec3& w) {
    float e = meanPlaneCosine(g, w);
    if (w.z <= 0.f || e <= 0.f) return 1e30f;
    float s2 = w.x * w.x * g.a + 2.f * w.x * w.y * g.c + w.y * w.y * g.b;
    float ap;
    if (s2 > 0.f) {
        float s = std::sqrt(s2);
        float d = e / s;
        ap = e * normalCdf(d) + s * 0.39894228040143268f * std::exp(-0.5f * d * d);
    } else {
        ap = e;
    }
    return std::max(ap / e - 1.f, 0.f);  // the clamp only absorbs float rounding
}

// f·cos = F(wo·h) D(h) G2(wo, wi) / (4 e(wo)), G2 height-correlated = 1/(1 + Λ(wo) + Λ(wi)) (Heitz 2014, Eq. 99):
// the Cook-Torrance lobe of the mean plane (D per unit mean-plane area is D n̂z with n̂ = n̄/|n̄|,
// and e(wo) = (wo·n̂)/n̂z),
// so a tilted mirror (Σ → 0, α → 0) keeps the radiance it reflects (albedo → F), ∫ f cos dωi ≤ F, and the lobe is
// reciprocal in the mean-plane measure: f·cos(wo, wi) / e(wi) = F D G2 / (4 e(wo) e(wi)) is symmetric. Zero when
// wo or wi is below the geometric plane or below the mean plane.
inline float evalNoFresnel(const SlopeGaussian& g, const Vec3& wo, const Vec3& wi, Vec3* hOut = nullptr) {
    if (wo.z <= 0.f || wi.z <= 0.f) return 0.f;
    float eo = meanPlaneCosine(g, wo);
    if (eo <= 0.f || meanPlaneCosine(g, wi) <= 0.f) return 0.f;
    Vec3 h = wo + wi;
    float len = std::sqrt(glm::dot(h, h));
    if (len == 0.f) return 0.f;
    h /= len;
    if (hOut) *hOut = h;
    float d = ndf(g, h);
    if (d == 0.f) return 0.f;
    float g2 = 1.f / (1.f + lambda(g, wo) + lambda(g, wi));
    return d * g2 / (4.f * eo);
}

}  // namespace specula::lean

namespace specula {

class BeckmannLeanLobe final : public ltc::GgxPolygonLobe<BeckmannLeanLobe> {
public:
    BeckmannLeanLobe(const lean::SlopeGaussian& g, const Fresnel& fresnel) : g_(g), fresnel_(fresnel) {}
    LobeKind kind() const override { return LobeKind::Specular; }
    using BsdfLobe::sample;

    // f·cos as lean::evalNoFresnel times F(wo·h). Slope-space sampling of the Gaussian: pdf_h(h) = D(h) hz,
    // pdf_wi = D(h) hz / (4 wo·h).
    LobeValue evalPdf(const LobeQuery& q) const override {
        const Vec3& wo = q.wo;
        const Vec3& wi = q.wi;
        LobeValue r;
        Vec3 hf;
        float v = lean::evalNoFresnel(g_, wo, wi, &hf);
        if (v != 0.f) r.f = fresnel_.eval(glm::dot(wo, hf)) * v;
        if (wo.z <= 0.f || wi.z <= 0.f) return r;
        Vec3 h = wo + wi;
        float len = std::sqrt(glm::dot(h, h));
        if (len == 0.f) return r;
        h /= len;
        float woh = glm::dot(wo, h);
        if (woh <= 0.f) return r;
        r.pdf = lean::ndf(g_, h) * h.z / (4.f * woh);
        return r;
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        const Vec3& wo = q.wo;
        if (wo.z <= 0.f) return false;
        // Box-Muller, then s = μ + L z with the Cholesky factor L of Σ.
        float r = std::sqrt(-2.f * std::log(std::max(1.f - u.x, 1e-30f)));
        float phi = 2.f * kPi * u.y;
        float z1 = r * std::cos(phi), z2 = r * std::sin(phi);
        float l11 = std::sqrt(g_.a), l21 = g_.c / l11, l22 = std::sqrt(std::max(g_.b - l21 * l21, 0.f));
        float sx = g_.mean.x + l11 * z1, sy = g_.mean.y + l21 * z1 + l22 * z2;
        Vec3 m = glm::normalize(Vec3(-sx, -sy, 1.f));
        float wom = glm::dot(wo, m);
        if (wom <= 0.f) return false;
        wi = 2.f * wom * m - wo;
        return wi.z > 0.f;
    }
    Color3 albedo(const Vec3& wo) const override { return fresnel_.eval(std::max(wo.z, 0.f)); }
    const char* modelName() const override { return "beckmann_lean"; }
    void parameters(const LobeQuery&, LobeParameters& out) const override {
        out.push_back({"mean_slope", {g_.mean.x, g_.mean.y}});
        out.push_back({"slope_covariance", {g_.a, g_.b, g_.c}});  // (var_x, var_y, cov_xy)
    }
    // Quad lights (ltc::GgxPolygonLobe) through an equivalent GGX (docs/ltc-tables.md): the frame tilted to the mean
    // normal n' = normalize(−μx, −μy, 1) and a GGX roughness matrix proportional to the slope covariance Σ (kept as is
    // under the tilt; Beckmann α² = 2σ² per axis). The error against the lobe is measured in test_ltc_lobes.
    const Fresnel& polygonFresnel() const { return fresnel_; }
    Color3 polygonTint() const { return Color3(1.f); }
    ltc::Ltc computePolygonLtc(const Vec3& wo) const {
        const Vec3 n = glm::normalize(Vec3(-g_.mean.x, -g_.mean.y, 1.f));
        const Vec3 t = glm::normalize(Vec3(1.f, 0.f, 0.f) - n * n.x);
        const Mat3 tilt = glm::transpose(Mat3(t, glm::cross(n, t), n));  // rows t, b, n: lobe frame -> tilted frame
        // α_GGX² = 1.5 Σ (α_GGX ≈ 0.87 α_Beckmann): of the scales k in α² = kΣ tried (0.8 … 2, k = 2 being α_GGX = α_Beckmann)
        // it gave the smallest quad-light error against this lobe (test_ltc_lobes; docs/ltc-tables.md).
        constexpr double kEquivalentScale = 1.5;
        ltc::Ltc l = ltc::ggxRoughnessMatrix(ltc::builtinTables(), kEquivalentScale * g_.a, kEquivalentScale * g_.c,
                                             kEquivalentScale * g_.b, tilt * wo);
        l.invM = l.invM * tilt;
        return l;
    }
    const lean::SlopeGaussian& gaussian() const { return g_; }

private:
    lean::SlopeGaussian g_;
    Fresnel fresnel_;
};

}  // namespace specula
