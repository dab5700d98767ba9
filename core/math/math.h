// Small math vocabulary shared by every Specula module: GLM vector aliases, constants,
// an orthonormal shading frame and a few helpers that pbrt/Mitsuba users expect.
#pragma once

#define GLM_FORCE_XYZW_ONLY
#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace specula {

using Vec2 = glm::vec2;
using Vec3 = glm::vec3;
using Vec4 = glm::vec4;
using DVec3 = glm::dvec3;
using Mat3 = glm::mat3;
using Mat4 = glm::mat4;
using Color3 = glm::vec3;  // linear, scene-referred RGB in the working space (lin_rec709)

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kInv2Pi = 0.15915494309189533577f;
constexpr float kInv4Pi = 0.07957747154594766788f;

inline float luminance(const Color3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
inline float sqr(float x) { return x * x; }
inline float safeSqrt(float x) { return std::sqrt(std::max(0.f, x)); }
// A texel coordinate safe to convert to int: NaN becomes 0 and magnitudes beyond ±2^30 are clamped (a float that large
// has no fraction left, and int(inf) is undefined behaviour: found by fuzz_scene through a LEAN lookup at an infinite uv).
inline float texelCoordinate(float s) { return s == s ? std::clamp(s, -1073741824.f, 1073741824.f) : 0.f; }
inline bool isFinite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
inline float maxComponent(const Vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }

// Orthonormal basis (t, b, n): local shading space has z = n. Local <-> world conversions.
struct Frame {
    Vec3 t{1, 0, 0}, b{0, 1, 0}, n{0, 0, 1};

    Frame() = default;
    Frame(const Vec3& t_, const Vec3& b_, const Vec3& n_) : t(t_), b(b_), n(n_) {}

    // Frame from a normal alone (Duff et al. 2017, "Building an orthonormal basis, revisited").
    static Frame fromNormal(const Vec3& n) {
        float sign = std::copysign(1.f, n.z);
        float a = -1.f / (sign + n.z);
        float bb = n.x * n.y * a;
        Vec3 t(1.f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
        Vec3 b(bb, sign + n.y * n.y * a, -n.y);
        return {t, b, n};
    }
    // Frame from a normal and an approximate tangent (Gram-Schmidt); falls back to fromNormal.
    static Frame fromNormalTangent(const Vec3& n, const Vec3& tApprox) {
        Vec3 t = tApprox - n * glm::dot(n, tApprox);
        float len2 = glm::dot(t, t);
        if (!(len2 > 1e-12f)) return fromNormal(n);
        t /= std::sqrt(len2);
        return {t, glm::cross(n, t), n};
    }
    Vec3 toLocal(const Vec3& v) const { return {glm::dot(v, t), glm::dot(v, b), glm::dot(v, n)}; }
    Vec3 toWorld(const Vec3& v) const { return t * v.x + b * v.y + n * v.z; }
};

}  // namespace specula
