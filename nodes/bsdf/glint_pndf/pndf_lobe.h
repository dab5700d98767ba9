// The position-normal-manifold glint lobe (Wu et al. 2024 Eq. 1, spec pndf-manifold.md §5): f = F(wo·h) G D_P(h) /
// (4 cosθi cosθo) with the exact P-NDF of the pixel footprint as D, sampled from D_P for MIS (spec §2.4).
//
// D_P is a pdf over the projected disk and also the microfacet D in solid angle (d²s = cosθ_m dω_m, spec §1), so
// f·cosθi = F G D_P(h_xy) / (4 cosθo), the half-vector pdf is D_P cosθ_h and the reflected direction's pdf is
// D_P cosθ_h / (4 |wo·h|). G is separable Smith, G1(wi) G1(wo), from either the analytic projected area of the footprint
// (spec §4.1) or the per-texel GGX fit of the grazing projected area (spec §4.2). The lobe holds pointers into the
// prepared manifold and fit (owned by the node's prepared data, alive while the material is).
#pragma once

#include "core/render/bsdf.h"
#include "core/render/lobes/fresnel.h"
#include "nodes/bsdf/glint_pndf/pndf_eval.h"
#include "nodes/bsdf/glint_pndf/pndf_masking.h"

namespace specula::pndf {

enum class MaskingModel : uint8_t { Analytic, GgxFit };

struct PndfLobeParams {
    const PndfManifold* manifold = nullptr;
    Footprint footprint;
    double clusterThreshold = 0.0;  // ε_c of the cluster cut (0: exact)
    MaskingModel masking = MaskingModel::GgxFit;
    const PndfGgxFit* ggxFit = nullptr;  // required for MaskingModel::GgxFit
    Fresnel fresnel;
    // Left-handed tangent frames (bitangent sign < 0): the map's +v is the lobe frame's -y.
    bool flipY = false;
};

class PndfLobe final : public BsdfLobe {
public:
    explicit PndfLobe(const PndfLobeParams& p);
    LobeKind kind() const override { return LobeKind::Specular; }
    using BsdfLobe::sample;
    LobeValue evalPdf(const LobeQuery& q) const override;
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override;
    Color3 albedo(const Vec3& wo) const override;
    const char* modelName() const override { return "pndf"; }
    void parameters(const LobeQuery& q, LobeParameters& out) const override;

    // D_P at the half vector h (lobe frame, unit, h.z > 0): the exact footprint P-NDF (cluster cut at ε_c).
    double ndf(const Vec3& h) const;
    // Smith G1 of direction w (lobe frame) by the chosen masking model, in (0, 1].
    double maskingG1(const Vec3& w) const;

private:
    double maskingG1Wo(const Vec3& wo) const;  // maskingG1(wo) through the memo below

    PndfLobeParams p_;
    GgxAlpha alpha_{};  // the GGX fit's footprint roughness (MaskingModel::GgxFit), looked up once
    // G1(wo) memo: a path vertex asks one wo many times (each light, the BSDF sample); the analytic area is costly.
    mutable Vec3 memoWo_{0.f};
    mutable double memoG1_ = -1.0;
};

}  // namespace specula::pndf
