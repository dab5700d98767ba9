// LTCs of the renderer's GGX-family lobes from the fitted tables: isotropic, anisotropic and roughness-matrix GGX, and
// the Fresnel weighting F0·mag + (1 − F0)·fres of ltc_code's 2017 revision (exact for Schlick).
#pragma once

#include "core/ltc/ltc_tables.h"
#include "core/render/lobes/fresnel.h"

namespace specula::ltc {

// The LTC of GGX with the roughness matrix A = [[a, c], [c, d]] (entries α², the slope covariance scale of
// filtered-ggx.md; a = αx², d = αy², c = 0 for an axis-aligned lobe), for unit wo in the lobe frame. Isotropic A
// uses the 64×64 Nelder-Mead table; otherwise the principal axes of A (eigenvectors) select the anisotropic table
// and the rotation into them is folded into invM.
Ltc ggxRoughnessMatrix(const LtcTables& t, double a, double c, double d, const Vec3& wo);

// The Schlick-equivalent reflectance a Fresnel term gives an LTC integral: F0·mag + (1 − F0)·fres with F0 = F(1).
// Exact for Mode::One (mag) and Schlick; for dielectrics and conductors it is the Schlick approximation with their
// normal-incidence reflectance (documented in docs/ltc-tables.md, measured in tests/unit/test_ltc_lobes.cpp).
Color3 fresnelScale(const Fresnel& f, const Ltc& l);

// ∫_P f·cos of a GGX-family lobe described by 'l' and 'f' (tint applied by the caller), and its polygon sampling.
Color3 integrateGgx(const Ltc& l, const Fresnel& f, const Vec3* vertices, int n, uint8_t horizon);

// Base of the GGX-family lobes (bsdf.ggx, bsdf.ggx_filtered, bsdf.beckmann_lean): their quad-light answers from the
// LTC that Derived::computePolygonLtc(wo) gives, times polygonTint() · fresnelScale(polygonFresnel()); the polygon
// sample is ∝ the same LTC (the integrand up to that constant). The LTC is memoised per wo: a path vertex asks the
// integral and the shadow sample of every light with one wo (lobes belong to one thread's shading point).
template <class Derived>
class GgxPolygonLobe : public BsdfLobe {
public:
    bool integratePolygon(const LobeQuery& q, const Vec3* vertices, int count, Color3& result) const override {
        const Derived& d = static_cast<const Derived&>(*this);
        result = q.wo.z > 0.f ? d.polygonTint() * integrateGgx(polygonLtc(q.wo), d.polygonFresnel(), vertices, count,
                                                               q.polygonHorizon)
                              : Color3(0.f);
        return true;
    }
    bool samplePolygon(const LobeQuery& q, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                       Vec3& wi) const override {
        return q.wo.z > 0.f && ltc::samplePolygon(polygonLtc(q.wo), vertices, count, u, seed, wi);
    }
    bool environmentLookup(const LobeQuery& q, Vec3& dir, float& alpha) const override {
        if (q.wo.z > 0.f) {
            ltc::environmentLookup(polygonLtc(q.wo), dir, alpha);
        } else {  // integratePolygon answers 0 here; any lookup will do
            dir = Vec3(0.f, 0.f, 1.f);
            alpha = 1.f;
        }
        return true;
    }
    const Ltc& polygonLtc(const Vec3& wo) const {
        if (!(memoValid_ && wo == memoWo_)) {
            memo_ = static_cast<const Derived&>(*this).computePolygonLtc(wo);
            memoWo_ = wo;
            memoValid_ = true;
        }
        return memo_;
    }

protected:
    void invalidatePolygonLtc() { memoValid_ = false; }

private:
    mutable Ltc memo_;
    mutable Vec3 memoWo_{0.f};
    mutable bool memoValid_ = false;
};

}  // namespace specula::ltc
