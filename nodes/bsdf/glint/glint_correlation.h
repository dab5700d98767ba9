// Slope correlation (Chermain et al. 2021 "C21" §3): the matrix M of C21 Eq. 18 that shears the dictionary into a
// correlated lobe, the correlated Beckmann SDF it converges to (C21 Eq. 16), its sampling, and LEAN mapping (C21 §5).
#pragma once

#include "core/math/math.h"
#include "nodes/bsdf/glint/glint_dictionary.h"

#include <algorithm>
#include <cmath>

namespace specula::glint {

// The linear transformation of C21 Eq. 18, M = (1/sigma_o) [[sx sqrt(1-rho^2), rho sx], [0, sy]], through its inverse
// M^-1 = sigma_o [[1/(sx sq), -rho/(sy sq)], [0, 1/sy]] and det(M^-1) = sigma_o^2 / (sx sy sq)   (spec S4.7, S4.10).
struct GlintShape {
    float sx, sy, rho, sq;
    float mi00, mi01, mi11;
    float detMinv;
    static GlintShape make(float sigmaX, float sigmaY, float rho) {
        GlintShape s;
        s.sx = std::clamp(sigmaX, 0.01f, 1.f);
        s.sy = std::clamp(sigmaY, 0.01f, 1.f);
        s.rho = std::clamp(rho, -0.99f, 0.99f);
        s.sq = std::sqrt(1.f - s.rho * s.rho);
        const float so = float(kSigmaO);
        s.mi00 = so / (s.sx * s.sq);
        s.mi01 = -so * s.rho / (s.sy * s.sq);
        s.mi11 = so / s.sy;
        s.detMinv = so * so / (s.sx * s.sy * s.sq);
        return s;
    }
    Vec2 applyInv(Vec2 v) const { return {mi00 * v.x + mi01 * v.y, mi11 * v.y}; }
};

// Non-axis-aligned Beckmann SDF (spec S7; C21 Eq. 16 covariance):
// P_B(x, y) = exp(-q/2) / (2 pi sx sy sqrt(1-rho^2)), q = [x^2/sx^2 - 2 rho x y/(sx sy) + y^2/sy^2] / (1-rho^2).
inline float beckmannSdf(Vec2 h, const GlintShape& s) {
    const float a = h.x / s.sx, b = h.y / s.sy;
    const float q = (a * a - 2.f * s.rho * a * b + b * b) / (s.sq * s.sq);
    return std::exp(-0.5f * q) / (2.f * kPi * s.sx * s.sy * s.sq);
}

// Half slope from the limiting correlated Beckmann lobe N(0, Sigma) (C21 Eq. 16): h~ = L z with L the Cholesky factor
// [[sx, 0], [rho sy, sy sqrt(1-rho^2)]] and z from Box-Muller; its density is P_B(h~).
inline Vec2 sampleBeckmannSlope(const GlintShape& s, const Vec2& u) {
    const float r = std::sqrt(-2.f * std::log(std::max(1.f - u.x, 1e-12f)));
    const float phi = 2.f * kPi * u.y;
    const float z1 = r * std::cos(phi), z2 = r * std::sin(phi);
    return {s.sx * z1, s.sy * (s.rho * z1 + s.sq * z2)};
}

// Importance sampling: half slopes from the limiting correlated Beckmann lobe N(0, Sigma) (C21 Eq. 16),
// h~ = L z with L the Cholesky factor [[sx, 0], [rho sy, sy sqrt(1-rho^2)]], z from Box-Muller; wi = reflect.
// Its exact solid-angle pdf is P_B(h~) / h_z^3 / (4 wo.h), so MIS stays unbiased whatever the glints are.
inline Vec3 sampleBeckmannHalf(const GlintShape& s, const Vec2& u) {
    const Vec2 hs = sampleBeckmannSlope(s, u);  // half slope h~
    return glm::normalize(Vec3(-hs.x, -hs.y, 1.f));
}

// S6 (C21 §5): LEAN mapping with glints. cov = (var_x, var_y, cov_xy) of the normal-map slopes over the footprint
// (var = E[x^2] - E[x]^2, from the LEAN moments). Variances are clamped to [1e-4, 1]; if either hit the lower clamp the
// normal-map term is dropped. Otherwise sigma^2 = sigma_m^2 + sigma_n^2 per axis and
// rho = (rho_m sigma_mx sigma_my + rho_n sigma_nx sigma_ny) / (sigma_x sigma_y), then sigma in [0.01, 1], rho in +-0.99.
// Returns whether the normal-map term was applied.
inline bool leanCombine(float& sigmaX, float& sigmaY, float& rho, const Vec3& cov) {
    const float vx = std::min(cov.x, 1.f), vy = std::min(cov.y, 1.f);
    if (!(vx > 1e-4f) || !(vy > 1e-4f)) return false;
    const float snx = std::sqrt(vx), sny = std::sqrt(vy);
    const float rn = std::clamp(cov.z / (snx * sny), -0.99f, 0.99f);
    const float sx = std::sqrt(sigmaX * sigmaX + vx), sy = std::sqrt(sigmaY * sigmaY + vy);
    rho = std::clamp((rho * sigmaX * sigmaY + rn * snx * sny) / (sx * sy), -0.99f, 0.99f);
    sigmaX = std::clamp(sx, 0.01f, 1.f);
    sigmaY = std::clamp(sy, 0.01f, 1.f);
    return true;
}
// S6.4: the shading normal of the mean slope (E[x], E[y]) in the frame (t, b, n): n' ∝ (-E[x], -E[y], 1); if it faces
// away from wo it is pulled towards wo by 1.01 times its component along wo. (The tangent follows by Gram-Schmidt.)
inline Vec3 leanNormal(const Vec3& t, const Vec3& b, const Vec3& n, Vec2 mean, const Vec3& wo) {
    Vec3 m = glm::normalize(n - mean.x * t - mean.y * b);
    const float c = glm::dot(m, wo);
    if (c < 0.f) m = glm::normalize(m - 1.01f * c * wo);
    return m;
}

}  // namespace specula::glint
