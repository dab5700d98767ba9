// Fresnel reflectance terms used by microfacet lobes: Schlick with a coloured F0, exact dielectric,
// and exact conductor with a complex index of refraction per RGB channel.
#pragma once

#include "core/math/math.h"

namespace specula {

// Exact unpolarised dielectric reflectance for relative IOR eta = n_t/n_i (total internal reflection -> 1).
inline float fresnelDielectric(float cosThetaI, float eta) {
    cosThetaI = std::clamp(cosThetaI, -1.f, 1.f);
    if (cosThetaI < 0.f) {
        eta = 1.f / eta;
        cosThetaI = -cosThetaI;
    }
    float sin2T = (1.f - cosThetaI * cosThetaI) / (eta * eta);
    if (sin2T >= 1.f) return 1.f;
    float cosT = safeSqrt(1.f - sin2T);
    float rPar = (eta * cosThetaI - cosT) / (eta * cosThetaI + cosT);
    float rPerp = (cosThetaI - eta * cosT) / (cosThetaI + eta * cosT);
    return 0.5f * (rPar * rPar + rPerp * rPerp);
}

// Exact conductor reflectance for complex IOR eta + i k (one channel), from the standard closed form.
inline float fresnelConductor(float cosThetaI, float eta, float k) {
    float c2 = std::clamp(cosThetaI * cosThetaI, 0.f, 1.f);
    float s2 = 1.f - c2;
    float eta2 = eta * eta, k2 = k * k;
    float t0 = eta2 - k2 - s2;
    float a2b2 = std::sqrt(std::max(0.f, t0 * t0 + 4.f * eta2 * k2));
    float t1 = a2b2 + c2;
    float a = safeSqrt(0.5f * (a2b2 + t0));
    float t2 = 2.f * std::sqrt(c2) * a;
    float rs = (t1 - t2) / std::max(t1 + t2, 1e-12f);
    float t3 = c2 * a2b2 + s2 * s2;
    float t4 = t2 * s2;
    float rp = rs * (t3 - t4) / std::max(t3 + t4, 1e-12f);
    return 0.5f * (rp + rs);
}

inline Color3 fresnelSchlick(float cosTheta, const Color3& f0) {
    float m = std::clamp(1.f - cosTheta, 0.f, 1.f);
    float m5 = (m * m) * (m * m) * m;
    return f0 + (Color3(1.f) - f0) * m5;
}

// A Fresnel term selected at material build time (no virtual call in the lobe).
struct Fresnel {
    enum class Mode : uint8_t { One, Schlick, Dielectric, Conductor } mode = Mode::One;
    Color3 f0{1.f};     // Schlick
    float eta = 1.5f;   // Dielectric
    Color3 etaC{1.f}, kC{0.f};  // Conductor

    static Fresnel one() { return {}; }
    static Fresnel schlick(const Color3& f0) {
        Fresnel f;
        f.mode = Mode::Schlick;
        f.f0 = f0;
        return f;
    }
    static Fresnel dielectric(float eta) {
        Fresnel f;
        f.mode = Mode::Dielectric;
        f.eta = eta;
        return f;
    }
    static Fresnel conductor(const Color3& eta, const Color3& k) {
        Fresnel f;
        f.mode = Mode::Conductor;
        f.etaC = eta;
        f.kC = k;
        return f;
    }
    // Inline for the modes a lobe evaluates on its hot path (Schlick, One), so every lobe gets them without a call;
    // the exact dielectric and conductor terms, long and rarer, are one call to evalExact (fresnel.cpp).
    Color3 eval(float cosThetaD) const {
        if (mode == Mode::Schlick) return fresnelSchlick(cosThetaD, f0);
        if (mode == Mode::One) return Color3(1.f);
        return evalExact(cosThetaD);
    }

private:
    Color3 evalExact(float cosThetaD) const;  // Dielectric and Conductor
};

}  // namespace specula
