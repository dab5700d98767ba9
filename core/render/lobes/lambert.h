// Lambertian reflection lobe: f = albedo/π, cosine-weighted hemisphere sampling.
#pragma once

#include "core/ltc/ltc.h"
#include "core/render/bsdf.h"
#include "core/render/sampling.h"

namespace specula {

class LambertLobe final : public BsdfLobe {
public:
    explicit LambertLobe(const Color3& albedo) : albedo_(albedo) {}
    LobeKind kind() const override { return LobeKind::Diffuse; }
    using BsdfLobe::sample;
    // f·cos = albedo cos θi / π, pdf = cos θi / π.
    LobeValue evalPdf(const LobeQuery& q) const override {
        if (q.wo.z <= 0.f || q.wi.z <= 0.f) return {};
        return {albedo_ * (kInvPi * q.wi.z), q.wi.z * kInvPi};
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        if (q.wo.z <= 0.f) return false;
        wi = sampleCosineHemisphere(u);
        return wi.z > 0.f;
    }
    Color3 albedo(const Vec3&) const override { return albedo_; }
    // The cosine lobe is the LTC with M = I: its polygon integral is Lambert's form factor, exact (HDHN16 §4).
    bool integratePolygon(const LobeQuery& q, const Vec3* vertices, int count, Color3& result) const override {
        result = q.wo.z > 0.f
                     ? albedo_ * float(ltc::integrateForLobe(ltc::Ltc{}, vertices, count, q.polygonHorizon))
                     : Color3(0.f);
        return true;
    }
    bool samplePolygon(const LobeQuery& q, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                       Vec3& wi) const override {
        return q.wo.z > 0.f && ltc::samplePolygon(ltc::Ltc{}, vertices, count, u, seed, wi);
    }
    // The cosine lobe reads the irradiance map at the normal.
    bool environmentLookup(const LobeQuery&, Vec3& dir, float& alpha) const override {
        dir = Vec3(0.f, 0.f, 1.f);
        alpha = -1.f;
        return true;
    }
    const char* modelName() const override { return "lambert"; }
    void parameters(const LobeQuery&, LobeParameters& out) const override {
        out.push_back({"albedo", {albedo_.x, albedo_.y, albedo_.z}});
    }

private:
    Color3 albedo_;
};

}  // namespace specula
