// Sampling of the position-normal manifold P-NDF (spec §2.4): kernel offset, representation lookup, affine map.
#include "nodes/bsdf/glint_pndf/pndf_sample.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace specula::pndf {

namespace {

constexpr double kPiD = 3.14159265358979323846;
constexpr double kSqrt2 = 1.41421356237309504880;
constexpr double kSqrt2Pi = 2.50662827463100050242;

double cross(const Vec2d& p, const Vec2d& q) { return p.x * q.y - p.y * q.x; }

// Φ⁻¹(p) for 0 < p <= 0.5 (the lower half; the upper half follows by symmetry, which keeps the Halley residual
// Φ(z) - p free of the cancellation near p = 1).
double inverseNormalCdfLower(double p) {
    // Acklam's rational approximations: a central one in r = (p - 1/2)² for p >= p_low, a tail one in
    // q = sqrt(-2 ln p) below it. Published coefficients; relative error < 1.15e-9 before refinement.
    constexpr double a[6] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
    constexpr double b[5] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01,  -1.328068155288572e+01};
    constexpr double c[6] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
    constexpr double d[4] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
    constexpr double pLow = 0.02425;
    double z;
    if (p < pLow) {
        const double q = std::sqrt(-2.0 * std::log(p));
        z = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
    } else {
        const double q = p - 0.5, r = q * q;
        z = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
            (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
    }
    // One Halley step on f(z) = Φ(z) - p (f' = φ, f''/f' = -z): cubic convergence takes the 1e-9 start to the
    // accuracy of erfc. Φ(z) = erfc(-z/√2)/2 is accurate in the lower tail, where p is small.
    const double e = 0.5 * std::erfc(-z / kSqrt2) - p;
    const double u = e * kSqrt2Pi * std::exp(0.5 * z * z);
    return z - u / (1.0 + 0.5 * z * u);
}

// One axis of the Gaussian with std 1 truncated to [-3, 3] (σ is a 3-std half-width, spec §1), by the inverse CDF:
// z = Φ⁻¹(Φ(-3) + u (Φ(3) - Φ(-3))). The draw is taken from the nearer tail (u < 1/2 directly, else mirrored with
// 1 - u) so that Φ⁻¹ only sees p <= 1/2, where p carries full relative precision.
double truncatedStdNormal(double u) {
    const double tail = 0.5 * std::erfc(3.0 / kSqrt2);  // Φ(-3) = 1.3499e-3
    const double width = 1.0 - 2.0 * tail;
    double z;
    if (u < 0.5) {
        z = inverseNormalCdfLower(tail + u * width);
    } else {
        z = -inverseNormalCdfLower(tail + (1.0 - u) * width);
    }
    // Φ⁻¹(Φ(∓3)) = ∓3 up to round-off: clamp so that the offset never leaves eval's box |Δ| <= σ.
    return std::clamp(z, -3.0, 3.0);
}

}  // namespace

double inverseNormalCdf(double p) {
    if (std::isnan(p)) return std::numeric_limits<double>::quiet_NaN();
    if (p <= 0.0) return -std::numeric_limits<double>::infinity();
    if (p >= 1.0) return std::numeric_limits<double>::infinity();
    return p <= 0.5 ? inverseNormalCdfLower(p) : -inverseNormalCdfLower(1.0 - p);
}

Vec2d sampleKernelOffset(const Footprint& fp, double u1, double u2) {
    const double su = fp.sigmaU, sv = fp.sigmaV;
    switch (fp.kernel) {
        case FootprintKernel::Gaussian:
            // Independent axes (spec §1), std σ/3, each truncated to |Δ| <= σ exactly like eval's box: no mass
            // outside eval's support (spec §2.4 caveat, fixed without rejection so that one (u1, u2) is one sample).
            return {su / 3.0 * truncatedStdNormal(u1), sv / 3.0 * truncatedStdNormal(u2)};
        case FootprintKernel::Box:
            return {su * (2.0 * u1 - 1.0), sv * (2.0 * u2 - 1.0)};
        case FootprintKernel::Disk: {
            // Uniform on the ellipse (Δ_u/σ_u)² + (Δ_v/σ_v)² <= 1: the unit disk by r = sqrt(u1), φ = 2π u2, scaled
            // per axis (the scale has constant Jacobian σ_u σ_v, so uniformity is kept). r < 1 for u1 < 1, and
            // r²(cos²+sin²) <= 1 holds up to an ulp, inside eval's closed test q <= 1 in practice.
            const double r = std::sqrt(u1), phi = 2.0 * kPiD * u2;
            return {su * r * std::cos(phi), sv * r * std::sin(phi)};
        }
    }
    return {0.0, 0.0};
}

int manifoldTriangleAt(const PndfManifold& m, const Footprint& fp, double clusterThreshold, double x, double y,
                       ManifoldTriangle& tri, double& t1, double& t2) {
    ManifoldTriangle pair[2];
    int level = 0;
    // Eval (spec §3.1) starts at the entry level, but clusterAccepted is false above kMaxQueryClusterLevel, so the
    // first level that can pick a cluster is min(entry, 4); levels above it only ever descend.
    for (int l = std::min(entryLevel(m, fp), kMaxQueryClusterLevel); l >= 1; --l) {
        const double size = double(1 << l);
        const int row = int(std::floor(y / size)), col = int(std::floor(x / size));
        if (clusterAccepted(m, l, row, col, fp, clusterThreshold)) {
            m.clusterTriangles(l, row, col, pair);
            level = l;
            break;
        }
    }
    if (level == 0) m.cellTriangles(int(std::floor(y)), int(std::floor(x)), pair);
    // Invert the x parametrisation of each triangle (Cramer's rule on x - xOrigin = t1 xStep1 + t2 xStep2): this works
    // for cell (unit steps) and cluster (2^ℓ steps) triangles alike, and is exactly the map triangleContribution
    // evaluates forwards. T⁺'s parameters are the node-local (ξ, η); T⁻ is used when ξ + η >= 1 (spec §2.1).
    auto invert = [x, y](const ManifoldTriangle& t, double& a, double& b) {
        const Vec2d d{x - t.xOrigin.x, y - t.xOrigin.y};
        const double inv = 1.0 / cross(t.xStep1, t.xStep2);
        a = cross(d, t.xStep2) * inv;
        b = cross(t.xStep1, d) * inv;
    };
    double xi, eta;
    invert(pair[0], xi, eta);
    if (xi + eta < 1.0) {
        tri = pair[0];
        t1 = xi;
        t2 = eta;
    } else {
        tri = pair[1];
        invert(pair[1], t1, t2);
    }
    // Round-off on the node's edges can leave the parameters an ulp outside the simplex; clamp them so that s stays
    // in the triangle's (closed) normal image, where eval's hit test finds it.
    t1 = std::max(t1, 0.0);
    t2 = std::max(t2, 0.0);
    if (t1 + t2 > 1.0) {
        const double sum = t1 + t2;
        t1 /= sum;
        t2 /= sum;
    }
    return level;
}

bool samplePndf(const PndfManifold& m, const Footprint& fp, double clusterThreshold, double u1, double u2, Vec2d& s,
                Vec2d* x) {
    if (!(std::isfinite(fp.centreX) && std::isfinite(fp.centreY) && fp.sigmaU > 0 && fp.sigmaV > 0 &&
          std::isfinite(fp.sigmaU) && std::isfinite(fp.sigmaV) && std::isfinite(u1) && std::isfinite(u2)))
        return false;
    const Vec2d delta = sampleKernelOffset(fp, u1, u2);
    const Vec2d pos{fp.centreX + delta.x, fp.centreY + delta.y};
    ManifoldTriangle tri;
    double t1, t2;
    manifoldTriangleAt(m, fp, clusterThreshold, pos.x, pos.y, tri, t1, t2);
    const Vec2d out{tri.sOrigin.x + t1 * tri.sEdge1.x + t2 * tri.sEdge2.x,
                    tri.sOrigin.y + t1 * tri.sEdge1.y + t2 * tri.sEdge2.y};
    if (!(std::isfinite(out.x) && std::isfinite(out.y))) return false;
    s = out;
    if (x) *x = pos;
    return true;
}

}  // namespace specula::pndf
