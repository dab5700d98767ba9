// Procedural glint BRDF (Chermain et al. 2020 "C20") with geometric glint anti-aliasing and slope correlation
// (Chermain et al. 2021 "C21"): spec glint-brdf.md §3 steps S0-S7, in float with the same operations as glint.glsl.
// This header holds the lobe (the query against the cell set, the BRDF of C20 Eq. 14, importance sampling); the
// ideas it is built from live in glint_dictionary.h (§2), glint_params.h (§1), glint_correlation.h (C21 Eqs. 16,
// 18, §5), glint_counting.h (S4.1-S4.5), glint_lookup.h (S5.4), glint_cells.h (S1-S4), glint_ggaa.h (C21 §4,
// Eqs. 20-21), glint_assembly.h (S0, S7), glint_reference.h (the per-query pipeline) and glint_area.h (quad lights).
#pragma once

#include "core/render/bsdf.h"
#include "core/render/lobes/fresnel.h"
#include "nodes/bsdf/glint/glint_assembly.h"
#include "nodes/bsdf/glint/glint_cells.h"
#include "nodes/bsdf/glint/glint_correlation.h"
#include "nodes/bsdf/glint/glint_dictionary.h"
#include "nodes/bsdf/glint/glint_flakes.h"
#include "nodes/bsdf/glint/glint_ggaa.h"
#include "nodes/bsdf/glint/glint_params.h"
#include "nodes/bsdf/glint/glint_reference.h"

#include <limits>

namespace specula::glint {

// One query against the cells of its shading point: the BRDF times cos(theta_i) without Fresnel, G D / (4 wo.z)
// (C20 Eq. 14 + S7, fCosFromSdf; GGAA-filtered P when GGAA is on; 0 per the S0 rejections) and, for the sampling pdf,
// the unfiltered P and P_B at the same half vector.
struct GlintQueryValue {
    bool valid = false;  // h passed S0 (wo.z, wi.z, h.z, wo.h > 0)
    Vec3 h{0.f};
    float woh = 0.f;
    float fcos = 0.f;         // G D / (4 wo.z)
    float pUnfiltered = 0.f;  // unfiltered patch SDF at h~ (only with wantPdf)
    float pB = 0.f;           // P_B(h~)
};
template <bool kWantPdf>
inline GlintQueryValue glintQuery(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                                  const GlintEvalInputs& in, const GlintCellSet& cells, const Vec3& wo, const Vec3& wi,
                                  float lightDistance) {
    GlintQueryValue v;
    HalfVector hv;
    if (!halfVector(wo, wi, hv)) return v;
    const Vec3 h = hv.h;
    const float len = hv.len, woh = hv.woh, wih = hv.wih;
    v.valid = true;
    v.h = h;
    v.woh = woh;
    const Vec2 slope(-h.x / h.z, -h.y / h.z);
    v.pB = beckmannSdf(slope, shape);
    if (wih <= 0.f && !kWantPdf) return v;
    Vec2 gx(0.f), gy(0.f);
    if (p.ggaa && wih > 0.f) {
        const float k = p.kernelScale / float(4.0 * kSigmaO);  // g = s_K M^-1 d / (4 sigma_o) (S5.2)
        gx = shape.applyInv(ggaaDerivative(in.diff, 0, p.mode, wo, wi, h, len, lightDistance)) * k;
        gy = shape.applyInv(ggaaDerivative(in.diff, 1, p.mode, wo, wi, h, len, lightDistance)) * k;
    }
    const GlintSdfPair P = cells.evaluate<kWantPdf>(dict, shape, shape.applyInv(slope), v.pB, p.ggaa, gx, gy);
    v.pUnfiltered = P.unfiltered;
    if (wih > 0.f) v.fcos = fCosFromSdf(P.filtered, hv, wo, wi);
    return v;
}

// The lobe's path for one query: builds the cells and answers one query (tests compare it with the reference).
inline float glintFCosCells(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                            const GlintEvalInputs& in, const Vec3& wo, const Vec3& wi,
                            float lightDistance = std::numeric_limits<float>::infinity()) {
    if (wo.z <= 0.f || wi.z <= 0.f) return 0.f;
    GlintCellSet cells;
    cells.build(dict, p, in.uv, footprint(in.duvdx, in.duvdy, p.maxAniso));
    return glintQuery<false>(dict, p, shape, in, cells, wo, wi, lightDistance).fcos;
}

// Fraction of the lobe's samples drawn from the limiting Beckmann lobe instead of the glints. It keeps the pdf > 0
// wherever the eval can be > 0: the GGAA-filtered P is nonzero where the unfiltered P (the glint sampling density)
// can be 0, and MIS needs pdf > 0 there to stay unbiased.
constexpr float kGlintBeckmannFraction = 0.15f;

// The two shares of one polygon query (glint_area.cpp): (1 - w_e) x the counted cells' integral and w_e x the flakes',
// each without F, with the half vectors F is read at; kept by the lobe for the light it was asked about last, so that
// samplePolygon, asked right after integratePolygon for the same light, does not integrate again.
struct GlintPolygonShares {
    double glint = 0.0, flake = 0.0;
    Vec3 hGlint{0.f, 0.f, 1.f}, hFlake{0.f, 0.f, 1.f};
    bool visible = false;
    // The query: wo and the light's vertices.
    bool valid = false;
    Vec3 wo{0.f};
    int count = 0;
    Vec3 vertices[4];
    bool matches(const Vec3& w, const Vec3* v, int n) const {
        if (!valid || n != count || w != wo) return false;
        for (int k = 0; k < n; ++k)
            if (v[k] != vertices[k]) return false;
        return true;
    }
};

// The glint lobe of the renderer: eval = F(wo.h) * f cos with the GGAA-filtered P. Sampling (issue 11 item 3): a
// mixture of the glint distribution of this shading point (GlintCellSet::sampleSlope) and, with probability
// kGlintBeckmannFraction, the limiting Beckmann lobe. Exact pdf, with dw_h = d(slope) h_z^3 (D h_z dw_h = P22 d(slope))
// and dw_i = 4 (wo.h) dw_h:
//   pdf(wi) = [beta P_B(h~) + (1 - beta) P_unfiltered(h~) / keptWeight] / h_z^3 / (4 wo.h).
// With explicit flakes (GlintParams::flakeSize > 0, glint_flakes.h) the slope density is w_e P_flakes + (1 - w_e) P:
// the footprint's flakes (findFlakes: box-filtered over the footprint) with weight w_e = flakeWeight(footprint), and
// the sampler picks them with probability w_e (where the footprint holds a flake; a flake by its weight), the mixture
// above otherwise.
// The cells are built on the first query and shared by every later query of the shading point (the lobe lives in
// one thread's scratch arena for one shading point); a lobe whose flakes take the whole weight never builds them.
class GlintLobe final : public BsdfLobe {
public:
    GlintLobe(const Dictionary& dict, const GlintParams& p, const GlintEvalInputs& in, const Fresnel& fresnel)
        : dict_(dict), p_(p), shape_(GlintShape::make(p.sigmaX, p.sigmaY, p.rho)), in_(in), fresnel_(fresnel) {
        if (p_.flakeSize > 0.f) {
            const Footprint fp = footprint(in_.duvdx, in_.duvdy, p_.maxAniso);
            const float width = fp.valid ? std::sqrt(std::sqrt(glm::dot(fp.a1, fp.a1) * glm::dot(fp.a2, fp.a2))) : 0.f;
            const bool located = flakeCoordinatesValid(in_.uv, p_.flakeSize);
            flakeWeight_ = located ? glint::flakeWeight(width, p_.flakeSize) : 0.f;
            flakeSigma_ = glint::flakeSigma(p_.flakeRoughness, shape_);
            // A footprint the LOD rejects (a zero minor axis, a non-finite axis) reads the flake under its centre.
            const Vec2 dx = fp.valid ? in_.duvdx : Vec2(0.f), dy = fp.valid ? in_.duvdy : Vec2(0.f);
            if (flakeWeight_ > 0.f) flakes_ = findFlakes(in_.uv, dx, dy, p_.flakeSize, p_.relArea, shape_, flakeSigma_);
        }
    }
    LobeKind kind() const override { return LobeKind::Specular; }
    using BsdfLobe::sample;
    LobeValue evalPdf(const LobeQuery& q) const override {
        LobeValue v;
        const float we = flakeWeight_;
        float fcos = 0.f, pdf = 0.f, woh = 0.f;
        HalfVector hv;
        if (we < 1.f) {
            const GlintCellSet& c = cells();
            const GlintQueryValue g = glintQuery<true>(dict_, p_, shape_, in_, c, q.wo, q.wi, q.lightDistance);
            if (!g.valid) return v;
            const float beta = beckmannFraction();
            const float glint = c.keptWeight > 0.f ? g.pUnfiltered / c.keptWeight : 0.f;
            fcos = (1.f - we) * g.fcos;
            const float glintPdf = (beta * g.pB + (1.f - beta) * glint) / (g.h.z * g.h.z * g.h.z * 4.f * g.woh);
            pdf = (1.f - flakeSampleWeight()) * glintPdf;
            woh = g.woh;
        }
        if (we > 0.f && flakes_.count > 0) {
            if (!halfVector(q.wo, q.wi, hv)) return v;
            const Vec3& h = hv.h;
            const float pf = flakeSetSdf(flakes_, Vec2(-h.x / h.z, -h.y / h.z), flakeSigma_);
            if (hv.wih > 0.f) fcos += we * fCosFromSdf(pf, hv, q.wo, q.wi);
            pdf += flakeSampleWeight() * (pf / flakes_.covered) / (h.z * h.z * h.z * 4.f * hv.woh);
            woh = hv.woh;
        }
        if (fcos > 0.f) v.f = fresnel_.eval(woh) * fcos;
        v.pdf = pdf;
        return v;
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        const Vec3& wo = q.wo;
        if (wo.z <= 0.f) return false;
        Vec2 uu = u, slope;
        const float qf = flakeSampleWeight();
        if (uu.x < qf) {
            // A flake by its weight, then a slope of its Gaussian; u.x rescaled for each choice.
            float t = std::min(uu.x / qf, 0.99999994f) * flakes_.covered;
            int k = 0;
            while (k + 1 < flakes_.count && t >= flakes_.weight[k]) t -= flakes_.weight[k++];
            uu.x = std::clamp(t / flakes_.weight[k], 0.f, 0.99999994f);
            slope = sampleFlakeSlope(flakes_.flakes[k].slope, flakeSigma_, uu);
        } else {
            if (flakeWeight_ >= 1.f) return false;  // an empty flake cell: nothing reflects here
            if (qf > 0.f) uu.x = std::min((uu.x - qf) / (1.f - qf), 0.99999994f);
            const float beta = beckmannFraction();
            if (uu.x < beta) {
                uu.x = std::min(uu.x / beta, 0.99999994f);
                slope = sampleBeckmannSlope(shape_, uu);
            } else {
                uu.x = std::min((uu.x - beta) / (1.f - beta), 0.99999994f);
                if (!cells().sampleSlope(dict_, shape_, uu, slope)) return false;
            }
        }
        const Vec3 h = glm::normalize(Vec3(-slope.x, -slope.y, 1.f));
        const float woh = glm::dot(wo, h);
        if (woh <= 0.f) return false;
        wi = 2.f * woh * h - wo;
        return wi.z > 0.f;
    }
    // Expected albedo estimate (selection weights, albedo AOV): A F(wo.z), the limit's mean energy.
    Color3 albedo(const Vec3& wo) const override {
        return fresnel_.eval(std::max(wo.z, 0.f)) * std::clamp(p_.relArea, 0.f, 1.f);
    }
    const char* modelName() const override { return "glint"; }
    void parameters(const LobeQuery&, LobeParameters& out) const override {
        out.push_back({"sigma", {p_.sigmaX, p_.sigmaY}});
        out.push_back({"rho", {p_.rho}});
        out.push_back({"log_density", {p_.logDensity}});
        out.push_back({"ggaa", {p_.ggaa ? 1.0 : 0.0}});
        out.push_back({"footprint_duv", {in_.duvdx.x, in_.duvdx.y, in_.duvdy.x, in_.duvdy.y}});
        if (p_.flakeSize > 0.f) out.push_back({"flakes", {p_.flakeSize, flakeSigma_, flakeWeight_}});
        // At close range the lobe is the footprint's platelets: the slope of the plane they make (their weighted mean
        // slope), whose projected area wo.z - wo.xy . slope is what a tilted platelet reflects with (as a normal map's
        // shading normal, or bsdf.beckmann_lean's mean plane): a platelet facing the viewer reflects up to twice the
        // light of the geometric plane's area, the surface's mean stays the converged lobe (glint_flakes.h).
        if (flakeWeight_ >= 1.f && flakes_.count > 0) {
            Vec2 mean(0.f);
            for (int k = 0; k < flakes_.count; ++k) mean += flakes_.weight[k] * flakes_.flakes[k].slope;
            mean /= flakes_.covered;
            out.push_back({"plane_slope", {mean.x, mean.y}});
        }
    }
    // Quad lights (issue 11 item 2): the per-cell polygon integral and the shadow-ray direction (glint_area.cpp).
    bool integratePolygon(const LobeQuery& q, const Vec3* vertices, int count, Color3& result) const override;
    bool samplePolygon(const LobeQuery& q, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                       Vec3& wi) const override;
    const GlintParams& params() const { return p_; }
    const GlintEvalInputs& inputs() const { return in_; }
    // The footprint's cells (built on first use): shared with the area-light integral of the same shading point.
    const GlintCellSet& cells() const {
        if (!cellsBuilt_) {
            cells_.build(dict_, p_, in_.uv, footprint(in_.duvdx, in_.duvdy, p_.maxAniso));
            cellsBuilt_ = true;
        }
        return cells_;
    }
    // The mixture weight of the Beckmann lobe: kGlintBeckmannFraction, or 1 when every cell is empty or glint
    // sampling is off.
    float beckmannFraction() const {
        return p_.sampleGlints && cells().keptWeight > 0.f ? kGlintBeckmannFraction : 1.f;
    }
    // The explicit flakes' share of the slope density (w_e: 0 without flakes or beyond one flake per footprint), the
    // flake under the shading point, and the probability that sample() draws from it (w_e where a flake is present).
    float flakeWeight() const { return flakeWeight_; }
    const FlakeSet& flakes() const { return flakes_; }
    float flakeSigma() const { return flakeSigma_; }
    float flakeSampleWeight() const { return flakes_.count > 0 ? flakeWeight_ : 0.f; }
    // The shares of a polygon query (computed, or the last query's when it was the same light).
    const GlintPolygonShares& polygonShares(const Vec3& wo, const Vec3* vertices, int count) const;

private:
    const Dictionary& dict_;
    GlintParams p_;
    GlintShape shape_;
    GlintEvalInputs in_;
    Fresnel fresnel_;
    float flakeWeight_ = 0.f, flakeSigma_ = 0.f;
    FlakeSet flakes_;
    mutable GlintPolygonShares polygonShares_;
    mutable bool cellsBuilt_ = false;
    mutable GlintCellSet cells_;
};

}  // namespace specula::glint
