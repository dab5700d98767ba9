// Geometric glint anti-aliasing (C21 §4): the per-pixel derivative of the half vector (C21 Eq. 21, or of the half
// slope, Eq. 20) from the screen derivatives of the frame and wo or a 2x2-quad partner (C21 §6.1), for Eq. 19's kernel.
#pragma once

#include "core/math/math.h"
#include "nodes/bsdf/glint/glint_params.h"

#include <cmath>

namespace specula::glint {

// Derivative of the GGAA quantity from dh: the projected half vector (h_x, h_y) (C21 Eq. 21) or the half slope
// h~ = (-h_x/h_z, -h_y/h_z) (C21 Eq. 20, first order).
inline Vec2 quantityDerivative(const Vec3& h, const Vec3& dh, DerivMode mode) {
    if (mode == DerivMode::ProjectedHalf) return {dh.x, dh.y};
    const float iz2 = 1.f / (h.z * h.z);
    return {-(dh.x * h.z - h.x * dh.z) * iz2, -(dh.y * h.z - h.y * dh.z) * iz2};
}

// A 2x2-quad partner pixel (render setting "derivatives": "quad", ShadingPoint::quad), in this lobe's local frame:
// the GGAA difference is sign * (q(partner) - q(this)) with each h expressed in its own (normal-mapped) frame, as
// dFdx of the tangent-space h does on a GPU (C21 §6.1).
struct GlintNeighbour {
    bool valid = false;
    float sign = 1.f;
    Vec3 dp{0.f}, wo{0.f};  // partner position minus this position, partner wo
    Vec3 t{1, 0, 0}, b{0, 1, 0}, n{0, 0, 1};  // partner frame
};

// Per-pixel change of the local frame and of wo, from which dh is formed at eval time (C21 §6.1 computes
// dFdx(h) once per pixel). dn: (t.dN, b.dN), the infinitesimal rotation of the frame; dwo/dp: local change of wo
// and of the position (CPU only: the GLSL inputs carry neither). wi changes only for delta lights at a finite
// distance (the query's light distance); otherwise it is held fixed (directional light).
struct GlintDifferentials {
    Vec2 dnx{0.f}, dny{0.f};
    Vec3 dwox{0.f}, dwoy{0.f};
    Vec3 dpx{0.f}, dpy{0.f};
    GlintNeighbour nb[2];
};

// d(w_local) for a fixed world vector under the frame rotation a = (t.dN, b.dN): (-a.x w.z, -a.y w.z, a.w_xy).
inline Vec3 frameRotation(Vec2 a, const Vec3& w) { return {-a.x * w.z, -a.y * w.z, a.x * w.x + a.y * w.y}; }

// dh = (I - h h^T)(dwo + dwi) / |wo + wi|.
inline Vec3 halfDerivative(const Vec3& h, float len, const Vec3& dsum) {
    return (dsum - h * glm::dot(h, dsum)) / len;
}

// GGAA derivative of the quantity along screen axis k (0 = x, 1 = y).
inline Vec2 ggaaDerivative(const GlintDifferentials& d, int k, DerivMode mode, const Vec3& wo, const Vec3& wi,
                           const Vec3& h, float len, float dist) {
    const bool finite = std::isfinite(dist) && dist > 0.f;
    const GlintNeighbour& nb = d.nb[k];
    if (nb.valid) {
        const Vec3 wiN = finite ? glm::normalize(wi * dist - nb.dp) : wi;
        const Vec3 hN = glm::normalize(nb.wo + wiN);
        const Vec3 hl(glm::dot(hN, nb.t), glm::dot(hN, nb.b), glm::dot(hN, nb.n));
        if (hl.z > 0.f) {
            if (mode == DerivMode::ProjectedHalf) return Vec2(hl.x - h.x, hl.y - h.y) * nb.sign;
            return (Vec2(-hl.x / hl.z, -hl.y / hl.z) - Vec2(-h.x / h.z, -h.y / h.z)) * nb.sign;
        }
    }
    const Vec2 a = k == 0 ? d.dnx : d.dny;
    Vec3 dsum = frameRotation(a, wo) + (k == 0 ? d.dwox : d.dwoy) + frameRotation(a, wi);
    if (finite) {  // wi = (L - p)/|L - p|: dwi = -(I - wi wi^T) dp / dist
        const Vec3 dp = k == 0 ? d.dpx : d.dpy;
        dsum -= (dp - wi * glm::dot(wi, dp)) / dist;
    }
    return quantityDerivative(h, halfDerivative(h, len, dsum), mode);
}

// The per-shading-point inputs of a query: the uv footprint (spec S1) and the GGAA differentials.
struct GlintEvalInputs {
    Vec2 uv{0.f}, duvdx{0.f}, duvdy{0.f};  // already multiplied by the uv scale
    GlintDifferentials diff;
};

}  // namespace specula::glint
