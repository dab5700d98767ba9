// PndfLobe: evaluation, sampling and masking of the position-normal-manifold glint lobe (spec pndf-manifold.md §5).
#include "nodes/bsdf/glint_pndf/pndf_lobe.h"

#include "nodes/bsdf/glint_pndf/pndf_sample.h"

#include <algorithm>
#include <cmath>

namespace specula::pndf {

namespace {
// Spec §5: "if D·cosθ_h < 1e-20, treat it as 0" (the tails of clamped triangles are not worth an evaluation).
constexpr double kNdfFloor = 1e-20;
constexpr int kAnalyticMaskingCells = 1024;
// Up to this half-width (17² cells) the GGX-fit masking takes the footprint's own tilt (~20 ns per cell, once per
// shading point) rather than the fit's block average.
constexpr double kExactTiltSigma = 8.0;
}  // namespace

PndfLobe::PndfLobe(const PndfLobeParams& p) : p_(p) {
    if (p_.masking == MaskingModel::GgxFit && p_.ggxFit) {
        alpha_ = p_.ggxFit->alphaAt(p_.footprint);
        // Small footprints lean as their few facets do, not as the fit's 2^ℓ block (pndf_masking.h footprintTilt).
        if (std::max(p_.footprint.sigmaU, p_.footprint.sigmaV) <= kExactTiltSigma) {
            const Vec2d t = footprintTilt(*p_.manifold, p_.footprint);
            alpha_.tiltX = t.x;
            alpha_.tiltY = t.y;
        }
    }
}

double PndfLobe::ndf(const Vec3& h) const {
    const Vec2d s{double(h.x), p_.flipY ? -double(h.y) : double(h.y)};
    return evalPndfHierarchy(*p_.manifold, p_.footprint, s, nullptr, p_.clusterThreshold);
}

double PndfLobe::maskingG1(const Vec3& w) const {
    Vec3 v = w;
    if (p_.flipY) v.y = -v.y;
    if (p_.masking == MaskingModel::GgxFit) return smithG1GgxFit(alpha_, v);
    // The analytic area sums every cell of the footprint (~200 ns each, 3.6 ms at σ = 64): at most 1024 stratified
    // cells keep a query near 0.15 ms at ~5e-4 relative error (pndf_masking.h ProjectedAreaOptions).
    ProjectedAreaOptions opt;
    opt.maxCells = kAnalyticMaskingCells;
    return smithG1Analytic(*p_.manifold, p_.footprint, v, opt);
}

double PndfLobe::maskingG1Wo(const Vec3& wo) const {
    if (memoG1_ < 0.0 || memoWo_ != wo) {
        memoWo_ = wo;
        memoG1_ = maskingG1(wo);
    }
    return memoG1_;
}

LobeValue PndfLobe::evalPdf(const LobeQuery& q) const {
    LobeValue v;
    const Vec3& wo = q.wo;
    const Vec3& wi = q.wi;
    if (wo.z <= 0.f || wi.z <= 0.f) return v;
    const Vec3 sum = wo + wi;
    const float len = glm::length(sum);
    if (!(len > 0.f)) return v;
    const Vec3 h = sum / len;
    if (h.z <= 0.f) return v;
    const double d = ndf(h);
    if (!(d * h.z >= kNdfFloor)) return v;
    const double woh = std::max(double(glm::dot(wo, h)), 1e-8);
    const double g = maskingG1Wo(wo) * maskingG1(wi);
    // f·cosθi = F G D / (4 cosθo) (spec §5); pdf(wi) = D cosθ_h / (4 wo·h) (spec §2.4).
    v.f = p_.fresnel.eval(float(woh)) * float(g * d / (4.0 * double(wo.z)));
    v.pdf = float(d * double(h.z) / (4.0 * woh));
    return v;
}

bool PndfLobe::sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const {
    const Vec3& wo = q.wo;
    if (wo.z <= 0.f) return false;
    Vec2d s;
    if (!samplePndf(*p_.manifold, p_.footprint, p_.clusterThreshold, double(u.x), double(u.y), s)) return false;
    if (p_.flipY) s.y = -s.y;
    const double r2 = s.x * s.x + s.y * s.y;
    if (!(r2 < 1.0)) return false;
    const Vec3 m(float(s.x), float(s.y), float(std::sqrt(1.0 - r2)));
    const float wom = glm::dot(wo, m);
    if (wom <= 0.f) return false;  // a microfacet facing away from the viewer reflects nothing towards it
    wi = 2.f * wom * m - wo;
    return wi.z > 0.f;
}

Color3 PndfLobe::albedo(const Vec3& wo) const {
    // Lobe selection only: a conductor-like lobe reflects about F(θo) G1(θo) of what arrives (no energy is lost to a
    // second lobe inside it); G1 is the memoised masking of wo.
    if (wo.z <= 0.f) return Color3(0.f);
    return p_.fresnel.eval(wo.z) * float(maskingG1Wo(wo));
}

void PndfLobe::parameters(const LobeQuery& q, LobeParameters& out) const {
    const Footprint& fp = p_.footprint;
    out.push_back({"footprint_centre_texels", {fp.centreX, fp.centreY}});
    out.push_back({"footprint_sigma_texels", {fp.sigmaU, fp.sigmaV}});
    out.push_back({"kernel", {double(int(fp.kernel))}});
    out.push_back({"cluster_threshold", {p_.clusterThreshold}});
    if (p_.masking == MaskingModel::GgxFit) out.push_back({"ggx_fit_alpha", {alpha_.alpha1, alpha_.alpha2, alpha_.phi0}});
    out.push_back({"g1_wo", {maskingG1(q.wo)}});
    out.push_back({"g1_wi", {maskingG1(q.wi)}});
}

}  // namespace specula::pndf
