// Rough dielectric transmission (Walter, Marschner, Li & Torrance 2007, "Microfacet Models for Refraction through Rough
// Surfaces"): the GGX BTDF with height-correlated Smith G2 and visible-normal sampling; bsdf.dielectric pairs it with GgxLobe.
#pragma once

#include "core/render/bsdf.h"
#include "core/render/lobes/fresnel.h"
#include "core/render/lobes/ggx.h"

namespace specula {

namespace dielectric {

// Refracts w (unit, pointing away from the surface on the side m faces) through the microfacet normal m (unit,
// dot(w, m) > 0) with eta = n_t / n_w, the index of the far side over that of w's side. False on total internal
// reflection (Snell: sin θt = sin θw / eta).
inline bool refract(const Vec3& w, const Vec3& m, float eta, Vec3& t) {
    const float cosW = glm::dot(w, m);
    const float sin2T = std::max(0.f, 1.f - cosW * cosW) / (eta * eta);
    if (sin2T >= 1.f) return false;
    const float cosT = std::sqrt(1.f - sin2T);
    t = -w / eta + (cosW / eta - cosT) * m;
    return true;
}

}  // namespace dielectric

// The transmission half of a rough dielectric interface, in the interface's frame (z = the normal of the side the
// viewer is on when rendering). eta = n_below / n_above, the relative index of the -z side over the +z side; both sides
// are modelled (wo below the interface means the viewer is inside), so generalised reciprocity can be tested.
// f·|cos θi| = tint (1 − F(wo·h)) D(h) G2(wo, wi) |wi·h| |wo·h| / (|wo.z| (wi·h + wo·h/η')² η'²)   (Walter 2007, Eq. 21
// with the radiance factor (n_o/n_i)² = 1/η'²), η' = n_wi / n_wo and the generalised half vector h = ±normalize(wo + η' wi)
// (Eq. 16) turned to +z. Sampling: a visible normal (Heitz 2018) refracted; pdf = D_wo(h) |wi·h| / (wi·h + wo·h/η')²
// (Eq. 17 Jacobian).
class GgxTransmissionLobe final : public BsdfLobe {
public:
    GgxTransmissionLobe(float alphaX, float alphaY, float eta, const Color3& tint = Color3(1.f))
        : ax_(std::max(alphaX, ggx::kMinAlpha)), ay_(std::max(alphaY, ggx::kMinAlpha)), eta_(eta), tint_(tint) {}

    LobeKind kind() const override { return LobeKind::Specular; }
    bool transmits() const override { return true; }
    using BsdfLobe::sample;

    LobeValue evalPdf(const LobeQuery& q) const override {
        const Vec3& wo = q.wo;
        const Vec3& wi = q.wi;
        if (wo.z * wi.z >= 0.f) return {};  // a reflection pair (or grazing): not this lobe
        const float etaP = wo.z > 0.f ? eta_ : 1.f / eta_;  // n_wi / n_wo
        Vec3 h = wo + etaP * wi;
        const float len = glm::length(h);
        if (!(len > 0.f)) return {};
        h /= len;
        if (h.z < 0.f) h = -h;
        const float woh = glm::dot(wo, h), wih = glm::dot(wi, h);
        // Microfacets seen from behind by either direction do not refract between them.
        if (woh * wo.z <= 0.f || wih * wi.z <= 0.f) return {};
        const float denom = sqr(wih + woh / etaP);
        if (!(denom > 0.f)) return {};
        const float d = ggx::ndf(h, ax_, ay_);
        const float g = ggx::g2(wo, wi, ax_, ay_);
        // Fresnel transmittance is the same from both sides of a refraction pair; it is evaluated from the less dense
        // side, where it is well conditioned (from the denser side it has an infinite slope at the critical angle).
        const float fr = fresnelDielectric(etaP >= 1.f ? woh : wih, eta_);
        LobeValue v;
        v.f = tint_ * ((1.f - fr) * d * g * std::abs(wih * woh) / (std::abs(wo.z) * denom * etaP * etaP));
        // The visible normals of the side wo is on (the microsurface seen from below is the same one, flipped).
        const float dv = ggx::visibleNdf(wo.z > 0.f ? wo : -wo, h, ax_, ay_);
        v.pdf = dv * std::abs(wih) / denom;
        return v;
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        const Vec3& wo = q.wo;
        if (wo.z == 0.f) return false;
        const bool above = wo.z > 0.f;
        const Vec3 h = ggx::sampleVisibleNormal(above ? wo : -wo, u, ax_, ay_);
        const Vec3 m = above ? h : -h;  // the microfacet normal on wo's side
        if (!dielectric::refract(wo, m, above ? eta_ : 1.f / eta_, wi)) return false;  // total internal reflection
        return wi.z * wo.z < 0.f;
    }
    // For lobe selection and the albedo AOV: the transmitted fraction at normal-incidence microfacets, with the radiance
    // factor 1/η'².
    Color3 albedo(const Vec3& wo) const override {
        const float etaP = wo.z > 0.f ? eta_ : 1.f / eta_;
        return tint_ * ((1.f - fresnelDielectric(wo.z, eta_)) / (etaP * etaP));
    }
    const char* modelName() const override { return "ggx_transmission"; }
    void parameters(const LobeQuery&, LobeParameters& out) const override {
        out.push_back({"alpha", {ax_, ay_}});
        out.push_back({"eta", {eta_}});
    }
    // A polygon entirely above the interface receives no transmitted light: exactly zero. Polygons reaching below it
    // have no closed form here (the caller samples them).
    bool integratePolygon(const LobeQuery&, const Vec3* vertices, int count, Color3& result) const override {
        for (int k = 0; k < count; ++k)
            if (vertices[k].z < 0.f) return false;
        result = Color3(0.f);
        return true;
    }
    // Split-sum environment lighting (raster integrator, GPU preview): the environment seen through the interface along
    // the refracted view direction, weighted by the transmitted fraction (1 − F(wo.z)). The refracted lobe is narrower
    // than a reflected one of the same microfacets: a facet tilted by θm turns the refracted ray by about (1 − 1/η)θm and
    // the reflected one by 2θm, so the prefiltered environment is read at α (1 − 1/η) / 2. Single refraction: the exit
    // through the far side of a solid object is not modelled (an approximation of the preview; the path tracer is exact).
    bool environmentLookup(const LobeQuery& q, Vec3& dir, float& alpha) const override {
        alpha = std::sqrt(ax_ * ay_) * std::abs(1.f - 1.f / eta_) * 0.5f;
        // Total internal reflection (or a viewer below the interface): environmentIntegral is 0, any direction will do.
        if (q.wo.z <= 0.f || !dielectric::refract(q.wo, Vec3(0, 0, 1), eta_, dir)) dir = Vec3(0, 0, -1);
        return true;
    }
    bool environmentIntegral(const LobeQuery& q, const Vec3*, int, Color3& result) const override {
        result = q.wo.z > 0.f ? tint_ * (1.f - fresnelDielectric(q.wo.z, eta_)) : Color3(0.f);
        return true;
    }

    float eta() const { return eta_; }

private:
    float ax_, ay_;
    float eta_;
    Color3 tint_;
};

}  // namespace specula
