// LTCs of GGX lobes with matrix roughness (principal axes -> the anisotropic table) and their Fresnel weighting
// (ltc-filtering.md §2 "Magnitude and Fresnel").
#include "core/ltc/ltc_ggx.h"

#include <cmath>

namespace specula::ltc {

Ltc ggxRoughnessMatrix(const LtcTables& t, double a, double c, double d, const Vec3& wo) {
    // Eigen-decomposition of the symmetric 2×2 A: λ1 >= λ2 along the angle φ0 = ½ atan2(2c, a − d).
    double h = 0.5 * (a + d), g = std::sqrt(std::max(0.0, 0.25 * (a - d) * (a - d) + c * c));
    double l1 = h + g, l2 = std::max(h - g, 0.0);
    float ax = float(std::sqrt(std::max(l1, 0.0))), ay = float(std::sqrt(l2));
    if (std::abs(ax - ay) <= 1e-4f * ax) return ggxIsotropic(t, 0.5f * (ax + ay), wo);
    if (std::abs(c) < 1e-12 * std::max(a, d)) {  // already axis-aligned (bsdf.ggx): no rotation
        return ggxAnisotropic(t, float(std::sqrt(std::max(a, 0.0))), float(std::sqrt(std::max(d, 0.0))), wo);
    }
    double phi = 0.5 * std::atan2(2.0 * c, a - d);
    float cs = float(std::cos(phi)), sn = float(std::sin(phi));
    // R maps lobe-frame vectors into the principal frame (x' along the first eigenvector).
    Mat3 R(1.f);
    R[0][0] = cs, R[1][0] = sn, R[0][1] = -sn, R[1][1] = cs;  // rows (cs, sn, 0), (−sn, cs, 0), (0, 0, 1)
    Ltc l = ggxAnisotropic(t, ax, ay, R * wo);
    l.invM = l.invM * R;
    return l;
}

Color3 fresnelScale(const Fresnel& f, const Ltc& l) {
    if (f.mode == Fresnel::Mode::One) return Color3(l.magnitude);
    const Color3 f0 = f.eval(1.f);
    return f0 * l.magnitude + (Color3(1.f) - f0) * l.fresnel;
}

Color3 integrateGgx(const Ltc& l, const Fresnel& f, const Vec3* vertices, int n, uint8_t horizon) {
    double e = integrateForLobe(l, vertices, n, horizon);
    return fresnelScale(f, l) * float(e);
}

}  // namespace specula::ltc
