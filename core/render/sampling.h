// Warping functions from [0,1)^2 to directions and shapes, with their densities (pbrt-v4 ch. A.5),
// and the power heuristic for multiple importance sampling.
#pragma once

#include "core/math/math.h"

namespace specula {

inline Vec2 sampleConcentricDisk(const Vec2& u) {
    Vec2 o = 2.f * u - Vec2(1.f);
    if (o.x == 0.f && o.y == 0.f) return Vec2(0.f);
    float r, theta;
    if (std::abs(o.x) > std::abs(o.y)) {
        r = o.x;
        theta = 0.25f * kPi * (o.y / o.x);
    } else {
        r = o.y;
        theta = 0.5f * kPi - 0.25f * kPi * (o.x / o.y);
    }
    return r * Vec2(std::cos(theta), std::sin(theta));
}

inline Vec3 sampleCosineHemisphere(const Vec2& u) {
    Vec2 d = sampleConcentricDisk(u);
    float z = safeSqrt(1.f - d.x * d.x - d.y * d.y);
    return {d.x, d.y, z};
}

inline Vec3 sampleUniformSphere(const Vec2& u) {
    float z = 1.f - 2.f * u.x;
    float r = safeSqrt(1.f - z * z);
    float phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

// Uniform direction inside a cone around +z with cos of half-angle cosMax.
inline Vec3 sampleUniformCone(const Vec2& u, float cosMax) {
    float cosTheta = (1.f - u.x) + u.x * cosMax;
    float sinTheta = safeSqrt(1.f - cosTheta * cosTheta);
    float phi = u.y * 2.f * kPi;
    return {std::cos(phi) * sinTheta, std::sin(phi) * sinTheta, cosTheta};
}

inline float powerHeuristic(float pdfA, float pdfB) {
    float a = pdfA * pdfA, b = pdfB * pdfB;
    if (std::isinf(a)) return 1.f;
    return (a + b) > 0.f ? a / (a + b) : 0.f;
}

}  // namespace specula
