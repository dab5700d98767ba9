// Lambertian reflection lobe: f = albedo/π, cosine-weighted hemisphere sampling.
#pragma once

#include "core/render/bsdf.h"
#include "core/render/sampling.h"

namespace specula {

class LambertLobe final : public BsdfLobe {
public:
    explicit LambertLobe(const Color3& albedo) : albedo_(albedo) {}
    LobeKind kind() const override { return LobeKind::Diffuse; }
    Color3 eval(const Vec3& wo, const Vec3& wi) const override {
        if (wo.z <= 0.f || wi.z <= 0.f) return Color3(0.f);
        return albedo_ * (kInvPi * wi.z);
    }
    float pdf(const Vec3& wo, const Vec3& wi) const override {
        return (wo.z > 0.f && wi.z > 0.f) ? wi.z * kInvPi : 0.f;
    }
    bool sample(const Vec3& wo, const Vec2& u, Vec3& wi) const override {
        if (wo.z <= 0.f) return false;
        wi = sampleCosineHemisphere(u);
        return wi.z > 0.f;
    }
    Color3 albedo(const Vec3&) const override { return albedo_; }

private:
    Color3 albedo_;
};

}  // namespace specula
