// Shadowing-masking of the P-NDF (spec §4): exact per-triangle projected area (§4.1, paper App. B), the footprint
// average Ā(ω) and the grazing GGX fit (§4.2).
//
// Derivation of the per-triangle integral (spec §4.1) --------------------------------------------------------------
// Π_T(ω) = ∬_{s(T)∩V} ⟨ω,m(s)⟩/m_z d²s with m = (s_x, s_y, m_z), m_z = sqrt(1-|s|²). Rotating s by -φ_ω (area and
// orientation preserving) gives the canonical frame ω = (sinθ, 0, cosθ), c = cosθ, and the integrand
// f = c + sinθ·x/sqrt(1-x²-y²). Visibility ⟨ω,m⟩ >= 0 is sinθ·x + c·m_z >= 0: always for x >= 0; for x < 0 squaring
// gives c²(1-x²-y²) >= (1-c²)x², i.e. x²/c² + y² <= 1. So V ∩ disk = {x >= 0} ∪ E, E the ellipse of semi-axes c, 1.
// Green: ∬ (∂Q/∂x - ∂P/∂y) = ∮ P dx + Q dy. With P = 0, Q = c·x - sinθ·sqrt(1-x²-y²), ∂Q/∂x = f. So Π_T is the
// counter-clockwise boundary integral of Q dy around s(T)∩V, whose boundary is made of
//  (1) the parts of the edges of T inside V, and (2) the parts of ∂V inside T. Inside the disk ∂V is only the left
//      half of the ellipse, x = -c·sqrt(1-y²) (the segment x = 0, |y| < 1 lies inside E, so it is interior to V).
// (1) Line piece p0 -> p1 (unit direction d, length L): ∫ c·x dy = c(x0+x1)(y1-y0)/2 exactly (x linear in y). With
//     u = d·p along the line, |p|² = h² + u² where h = cross(d, p) is the line's distance from the origin, so
//     ∫ sqrt(1-|p|²) dy = d_y ∫ sqrt(ρ²-u²) du, ρ² = 1-h², = d_y·(ρ²/2)·[q sqrt(1-q²) + asin q] from q0 to q1, q = u/ρ
//     (the area under the circle arc the chord lifts to on the hemisphere, App. B Fig. 17).
//     Which part of an edge is visible: the edge ∩ {x >= 0} is one interval, the edge ∩ E is one interval (E is
//     convex; the quadratic c²(y0+tΔy)² + (x0+tΔx)² = c² written as A t² + 2B t + C = 0 has the well-conditioned
//     discriminant B² - AC = c²(A - cross(p0,Δ)²), so the grazing c -> 0 limit needs no special case). If the edge
//     has points on both sides of x = 0 it crosses x = 0 at |y| < 1, a point of E, so the two intervals overlap and
//     the visible part is a single interval: their hull.
// (2) Ellipse arc: on x = -c sqrt(1-y²), Q = -c² sqrt(1-y²) - sinθ sqrt((1-y²)(1-c²)) = -sqrt(1-y²), independent of
//     θ. V lies east of the left arc, so the counter-clockwise boundary runs down it: the contribution is
//     +∫ sqrt(1-y²) dy = ½[asin y + y sqrt(1-y²)] over the y-intervals where the arc point lies inside T. The arc
//     enters or leaves T only where it crosses an edge, and those crossings are the ellipse roots found in (1), so
//     the intervals are found by sorting those roots' y (with ±1) and testing each sub-interval's midpoint. At
//     c = 0 the arc degenerates to the segment x = 0 and the term stays (Q = -sqrt(1-y²) there is not zero): the
//     integral is continuous in c, which is why no grazing special case is needed.
// Fast path: a triangle whose three vertices are visible lies inside V (E–E edges stay in E by convexity, x>=0
// edges in x >= 0, a mixed edge crosses x = 0 inside E; the same holds for the triangle's x < 0 part). Then
// Π_T = c·|T| + sinθ·⟨u_φ, M_T⟩ with M_T = ∬_T s/m_z, computed once per triangle by Green as well:
// M_x = -∮ sqrt(1-|s|²) dy, M_y = +∮ sqrt(1-|s|²) dx, the same chord integrals as (1). This covers every triangle at
// θ = 0 (so Ā(0) = 1 is exact) and most triangles of a moderately sloped map away from grazing.
#include "nodes/bsdf/glint_pndf/pndf_masking.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace specula::pndf {

namespace {

constexpr double kPiD = 3.14159265358979323846;

struct P2 {
    double x, y;
};
inline P2 operator+(P2 a, P2 b) { return {a.x + b.x, a.y + b.y}; }
inline P2 operator-(P2 a, P2 b) { return {a.x - b.x, a.y - b.y}; }
inline P2 operator*(double k, P2 a) { return {k * a.x, k * a.y}; }
inline double cross(P2 a, P2 b) { return a.x * b.y - a.y * b.x; }
inline double dot(P2 a, P2 b) { return a.x * b.x + a.y * b.y; }

P2 pullIn(P2 p) {
    const double r2 = p.x * p.x + p.y * p.y;
    if (r2 > kMaxProjectedRadius * kMaxProjectedRadius) {
        const double k = kMaxProjectedRadius / std::sqrt(r2);
        p.x *= k;
        p.y *= k;
    }
    return p;
}

// ∫ sqrt(1 - |p|²) dτ along p0 -> p1 (τ = arc length) and the unit direction d: ∫ sqrt dy = d_y·I, ∫ sqrt dx = d_x·I.
inline double chordIntegral(P2 p0, P2 p1, P2& d) {
    const P2 delta = p1 - p0;
    const double len = std::sqrt(dot(delta, delta));
    if (!(len > 0)) {
        d = {0, 0};
        return 0.0;
    }
    d = (1.0 / len) * delta;
    const double h = cross(d, p0);
    const double rho2 = 1.0 - h * h;
    if (!(rho2 > 0)) return 0.0;  // a chord tangent to the rim has no length inside the disk
    const double rho = std::sqrt(rho2);
    const double u0 = dot(d, p0), um = u0 + 0.5 * len;
    // Short chord well away from the rim (the integrand sqrt(ρ²-u²) is analytic within ρ - |u_m| of the midpoint):
    // 4-point Gauss-Legendre, whose error for a singularity >= 10 half-lengths away is ~ (20)^-8 ≈ 4e-11 relative,
    // instead of two asin (3-4x the cost). This is the common case for the small triangles of a fine normal map.
    if (len <= 0.2 * (rho - std::abs(um))) {
        constexpr double x1 = 0.3399810435848563, x2 = 0.8611363115940526;
        constexpr double w1 = 0.6521451548625461, w2 = 0.3478548451374538;
        const double half = 0.5 * len;
        auto f = [&](double u) { return std::sqrt(rho2 - u * u); };
        return half * (w1 * (f(um - half * x1) + f(um + half * x1)) + w2 * (f(um - half * x2) + f(um + half * x2)));
    }
    const double invRho = 1.0 / rho;
    auto g = [](double q) {
        q = std::clamp(q, -1.0, 1.0);
        return q * std::sqrt(std::max(0.0, 1.0 - q * q)) + std::asin(q);
    };
    return 0.5 * rho2 * (g(dot(d, p1) * invRho) - g(dot(d, p0) * invRho));
}

// A normal triangle prepared once for any number of directions: pulled-in vertices in counter-clockwise order,
// m_z per vertex, the s-area and M_T = ∬_T s/m_z d²s.
struct TriGeom {
    P2 v[3];
    double mz[3];
    double area = 0;
    P2 moment{0, 0};
};

TriGeom prepare(const ManifoldTriangle& t) {
    TriGeom g;
    P2 o{t.sOrigin.x, t.sOrigin.y};
    P2 a = pullIn(o), b = pullIn(o + P2{t.sEdge1.x, t.sEdge1.y}), c = pullIn(o + P2{t.sEdge2.x, t.sEdge2.y});
    if (cross(b - a, c - a) < 0) std::swap(b, c);
    g.v[0] = a;
    g.v[1] = b;
    g.v[2] = c;
    double shoelace = 0;
    for (int i = 0; i < 3; ++i) {
        const P2 p = g.v[i], q = g.v[(i + 1) % 3];
        g.mz[i] = std::sqrt(std::max(0.0, 1.0 - dot(p, p)));
        shoelace += (p.x + q.x) * (q.y - p.y);
        P2 d;
        const double I = chordIntegral(p, q, d);
        g.moment.x -= d.y * I;
        g.moment.y += d.x * I;
    }
    g.area = 0.5 * shoelace;
    return g;
}

// A direction in the canonical-frame parametrisation: c = cosθ, s = sinθ, u = (cosφ, sinφ).
struct Dir {
    double c = 1, s = 0;
    P2 u{1, 0};
};

Dir makeDir(const Vec3& w) {
    Dir d;
    const double x = w.x, y = w.y, z = w.z;
    const double len = std::sqrt(x * x + y * y + z * z);
    const double sxy = std::sqrt(x * x + y * y);
    d.c = z / len;
    d.s = sxy / len;
    if (sxy > 0) d.u = {x / sxy, y / sxy};
    return d;
}

// One edge's visible piece (canonical frame): its Q dy integral, and the y of its crossings with the ellipse (the
// candidates where the left arc enters or leaves T).
double visibleEdgeTerm(P2 p0, P2 p1, const Dir& dir, double* ys, int& ny) {
    const P2 delta = p1 - p0;
    if (!(dot(delta, delta) > 0)) return 0.0;
    const double c = dir.c;
    // x >= 0 interval.
    double xlo = 1, xhi = 0;  // empty
    if (delta.x == 0) {
        if (p0.x >= 0) xlo = 0, xhi = 1;
    } else {
        const double ts = -p0.x / delta.x;
        if (delta.x > 0) xlo = std::max(0.0, ts), xhi = 1;
        else xlo = 0, xhi = std::min(1.0, ts);
    }
    // Ellipse interval: A t² + 2B t + C <= 0, roots (-B ± c sqrt(A - cr²))/A.
    double elo = 1, ehi = 0;  // empty
    const double A = delta.x * delta.x + c * c * delta.y * delta.y;
    if (A > 0) {
        const double B = p0.x * delta.x + c * c * p0.y * delta.y;
        const double cr = cross(p0, delta);
        const double disc = A - cr * cr;
        if (disc >= 0) {
            const double root = c * std::sqrt(disc);
            const double ta = (-B - root) / A, tb = (-B + root) / A;
            // Crossings on the edge (with a round-off margin: an extra split point only subdivides an interval).
            for (double t : {ta, tb})
                if (t >= -1e-12 && t <= 1 + 1e-12) ys[ny++] = p0.y + t * delta.y;
            elo = std::max(0.0, ta);
            ehi = std::min(1.0, tb);
        }
    }
    double lo, hi;
    const bool hasX = xlo <= xhi, hasE = elo <= ehi;
    if (hasX && hasE) lo = std::min(xlo, elo), hi = std::max(xhi, ehi);
    else if (hasX) lo = xlo, hi = xhi;
    else if (hasE) lo = elo, hi = ehi;
    else return 0.0;
    if (!(hi > lo)) return 0.0;
    const P2 a = p0 + lo * delta, b = p0 + hi * delta;
    double term = c * 0.5 * (a.x + b.x) * (b.y - a.y);
    if (dir.s > 0) {
        P2 d;
        const double I = chordIntegral(a, b, d);
        term -= dir.s * d.y * I;
    }
    return term;
}

double projectedAreaOf(const TriGeom& g, const Dir& dir) {
    if (!(g.area > 0)) return 0.0;
    if (dir.c <= 0 && dir.s <= 0) return 0.0;
    // Canonical frame coordinate x' = u·s of each vertex and its visibility s·x' + c·m_z >= 0.
    double xr[3];
    bool allVisible = true, allLeft = true;
    for (int i = 0; i < 3; ++i) {
        xr[i] = dot(dir.u, g.v[i]);
        allVisible &= dir.s * xr[i] + dir.c * g.mz[i] >= 0;
        allLeft &= xr[i] <= 0;
    }
    if (allVisible) return std::max(0.0, dir.c * g.area + dir.s * dot(dir.u, g.moment));
    if (dir.c <= 0 && allLeft) return 0.0;  // grazing: V is the half-plane x' >= 0
    // General case: boundary integral in the canonical frame (rotation by -φ: x' = u·s, y' = cross(u, s)).
    P2 r[3];
    for (int i = 0; i < 3; ++i) r[i] = {xr[i], cross(dir.u, g.v[i])};
    double ys[8];
    int ny = 0;
    double sum = 0;
    for (int i = 0; i < 3; ++i) sum += visibleEdgeTerm(r[i], r[(i + 1) % 3], dir, ys, ny);
    // Left ellipse arc inside T.
    if (ny > 0) {
        ys[ny++] = -1.0;
        ys[ny++] = 1.0;
        for (int i = 0; i < ny; ++i) ys[i] = std::clamp(ys[i], -1.0, 1.0);
        std::sort(ys, ys + ny);
        auto prim = [](double y) { return 0.5 * (std::asin(y) + y * std::sqrt(std::max(0.0, 1.0 - y * y))); };
        for (int i = 0; i + 1 < ny; ++i) {
            if (!(ys[i + 1] > ys[i])) continue;
            const double ym = 0.5 * (ys[i] + ys[i + 1]);
            const P2 q{-dir.c * std::sqrt(std::max(0.0, 1.0 - ym * ym)), ym};
            bool inside = true;
            for (int k = 0; k < 3 && inside; ++k) inside = cross(r[(k + 1) % 3] - r[k], q - r[k]) >= 0;
            if (inside) sum += prim(ys[i + 1]) - prim(ys[i]);
        }
    }
    return std::max(0.0, sum);
}

// ---- kernel mass over a triangle's texel area -------------------------------------------------------------------

double gaussianValue(const Footprint& fp, double dx, double dy) {
    // kernelWeight's Gaussian without its box test (points on the clipped polygon lie on the box within round-off).
    const double su = fp.sigmaU, sv = fp.sigmaV;
    const double q = 4.5 * (dx * dx / (su * su) + dy * dy / (sv * sv));
    const double w = 9.0 / (2.0 * kPiD * su * sv) * std::exp(-q);
    return fp.gaussianUnitMass ? w / truncatedGaussianMass() : w;
}

inline bool inBox(const Footprint& fp, P2 p) {
    return std::abs(p.x - fp.centreX) <= fp.sigmaU && std::abs(p.y - fp.centreY) <= fp.sigmaV;
}
inline bool inEllipse(const Footprint& fp, P2 p) {
    const double dx = (p.x - fp.centreX) / fp.sigmaU, dy = (p.y - fp.centreY) / fp.sigmaV;
    return dx * dx + dy * dy <= 1.0;
}

// Edge-midpoint rule (exact for polynomials of degree 2) on the n² similar sub-triangles of a texel triangle. The
// Gaussian's std is σ/3, a third of a texel at σ = 1, so small footprints need n > 1: n = ceil(3/σ_min) keeps the
// sub-triangle size at or below the std, where the mass is accurate to 1e-4 (measured 8e-5, test FootprintInvariants;
// n = ceil(2/σ) gave 9e-4, n = 1 at σ = 1 gave 7e-2).
double gaussianTriangle(const Footprint& fp, P2 a, P2 b, P2 c) {
    const int n = std::clamp(int(std::ceil(3.0 / std::min(fp.sigmaU, fp.sigmaV))), 1, 16);
    const double area = 0.5 * std::abs(cross(b - a, c - a));
    auto k = [&](P2 p) { return gaussianValue(fp, p.x - fp.centreX, p.y - fp.centreY); };
    if (n == 1) return area / 3.0 * (k(0.5 * (a + b)) + k(0.5 * (b + c)) + k(0.5 * (c + a)));
    const P2 e1 = (1.0 / n) * (b - a), e2 = (1.0 / n) * (c - a);
    double sum = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; i + j < n; ++j) {
            const P2 p = a + double(i) * e1 + double(j) * e2;  // sub-triangle (p, p+e1, p+e2) and, above it,
            sum += k(p + 0.5 * e1) + k(p + 0.5 * (e1 + e2)) + k(p + 0.5 * e2);  // (p+e1, p+e1+e2, p+e2)
            if (i + j < n - 1) sum += k(p + e1 + 0.5 * e2) + k(p + 0.5 * e1 + e2) + k(p + 0.5 * (e1 + e2));
        }
    return sum * area / (3.0 * n * n);
}

// Signed area of the unit disk ∩ triangle (0, a, b): the chord part inside the circle plus circular sectors where the
// edge runs outside (the standard polygon-circle intersection, summed over a polygon's edges it gives its area ∩ disk).
double originTriangleDiskArea(P2 a, P2 b) {
    auto sector = [](P2 u, P2 v) { return 0.5 * std::atan2(cross(u, v), dot(u, v)); };
    const P2 e = b - a;
    const double A = dot(e, e);
    if (!(A > 0)) return 0.0;
    const double B = dot(a, e), C = dot(a, a) - 1.0;
    const double disc = B * B - A * C;
    if (disc <= 0) return sector(a, b);  // the line misses the circle
    const double root = std::sqrt(disc);
    const double t1 = (-B - root) / A, t2 = (-B + root) / A;
    if (t1 >= 1 || t2 <= 0) return sector(a, b);  // the segment lies outside
    const P2 p1 = a + std::max(t1, 0.0) * e, p2 = a + std::min(t2, 1.0) * e;
    double area = 0.5 * cross(p1, p2);
    if (t1 > 0) area += sector(a, p1);
    if (t2 < 1) area += sector(p2, b);
    return area;
}

// Disk kernel on a triangle cut by the ellipse: exact, in coordinates where the ellipse is the unit circle.
double diskTriangle(const Footprint& fp, const P2* v) {
    P2 q[3];
    for (int i = 0; i < 3; ++i) q[i] = {(v[i].x - fp.centreX) / fp.sigmaU, (v[i].y - fp.centreY) / fp.sigmaV};
    double area = 0;
    for (int i = 0; i < 3; ++i) area += originTriangleDiskArea(q[i], q[(i + 1) % 3]);
    return std::abs(area) / kPiD;  // (scaled area · σuσv) / (π σuσv)
}

// Sutherland-Hodgman clip of a convex polygon against one axis-aligned half-plane (axis 0 = x, 1 = y).
int clipHalfPlane(const P2* in, int n, P2* out, int axis, double bound, bool keepBelow) {
    auto val = [&](P2 p) { return (axis == 0 ? p.x : p.y) - bound; };
    auto keep = [&](double v) { return keepBelow ? v <= 0 : v >= 0; };
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const P2 p = in[i], q = in[(i + 1) % n];
        const double vp = val(p), vq = val(q);
        if (keep(vp)) out[m++] = p;
        if (keep(vp) != keep(vq)) out[m++] = p + (vp / (vp - vq)) * (q - p);
    }
    return m;
}

}  // namespace

double triangleProjectedArea(const ManifoldTriangle& t, const Vec3& w) {
    if (!(w.z > 0)) return 0.0;
    return projectedAreaOf(prepare(t), makeDir(w));
}

double triangleNormalArea(const ManifoldTriangle& t) { return prepare(t).area; }

double triangleKernelMass(const ManifoldTriangle& t, const Footprint& fp) {
    const P2 o{t.xOrigin.x, t.xOrigin.y};
    const P2 v[3] = {o, o + P2{t.xStep1.x, t.xStep1.y}, o + P2{t.xStep2.x, t.xStep2.y}};
    const double area = 0.5 * std::abs(cross(v[1] - v[0], v[2] - v[0]));
    const bool disk = fp.kernel == FootprintKernel::Disk;
    bool inside = true;
    for (const P2& p : v) inside &= disk ? inEllipse(fp, p) : inBox(fp, p);
    if (inside) {
        switch (fp.kernel) {
            case FootprintKernel::Gaussian: return gaussianTriangle(fp, v[0], v[1], v[2]);
            case FootprintKernel::Box: return area / (4.0 * fp.sigmaU * fp.sigmaV);
            case FootprintKernel::Disk: return area / (kPiD * fp.sigmaU * fp.sigmaV);
        }
    }
    if (disk) return diskTriangle(fp, v);
    // Cut by the box: clip to it, then integrate the polygon's fan.
    P2 bufA[8], bufB[8];
    int n = 3;
    std::copy(v, v + 3, bufA);
    n = clipHalfPlane(bufA, n, bufB, 0, fp.centreX - fp.sigmaU, false);
    n = clipHalfPlane(bufB, n, bufA, 0, fp.centreX + fp.sigmaU, true);
    n = clipHalfPlane(bufA, n, bufB, 1, fp.centreY - fp.sigmaV, false);
    n = clipHalfPlane(bufB, n, bufA, 1, fp.centreY + fp.sigmaV, true);
    double mass = 0;
    for (int i = 1; i + 1 < n; ++i) {
        const P2 a = bufA[0], b = bufA[i], c = bufA[i + 1];
        switch (fp.kernel) {
            case FootprintKernel::Gaussian: mass += gaussianTriangle(fp, a, b, c); break;
            case FootprintKernel::Box: mass += 0.5 * std::abs(cross(b - a, c - a)) / (4.0 * fp.sigmaU * fp.sigmaV); break;
            case FootprintKernel::Disk: break;  // handled above
        }
    }
    return mass;
}

namespace {
// Deterministic per-block offset in [0, k)² for the stratified subsampling (a 64-bit mix of the block index).
inline void blockOffset(int br, int bc, int k, int& oy, int& ox) {
    uint64_t z = (uint64_t(uint32_t(br)) << 32) ^ uint64_t(uint32_t(bc)) ^ (uint64_t(k) * 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    oy = int((z & 0xffffffffull) % uint64_t(k));
    ox = int((z >> 32) % uint64_t(k));
}
}  // namespace

namespace {
// The n² affine sub-triangles of t (the same map restricted to a uniform split of its parameter simplex): upright
// ones at (i, j)/n with steps (1/n, 0), (0, 1/n), inverted ones at (i + 1, j + 1)/n with steps (-1/n, 0), (0, -1/n).
template <class F>
void forEachSubTriangle(const ManifoldTriangle& t, int n, F f) {
    if (n <= 1) {
        f(t);
        return;
    }
    const double h = 1.0 / n;
    auto at = [&](double t1, double t2, ManifoldTriangle& s) {
        s.sOrigin = {t.sOrigin.x + t1 * t.sEdge1.x + t2 * t.sEdge2.x, t.sOrigin.y + t1 * t.sEdge1.y + t2 * t.sEdge2.y};
        s.xOrigin = {t.xOrigin.x + t1 * t.xStep1.x + t2 * t.xStep2.x, t.xOrigin.y + t1 * t.xStep1.y + t2 * t.xStep2.y};
    };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i + j < n; ++i)
            for (int inverted = 0; inverted < 2; ++inverted) {
                if (inverted && i + j > n - 2) continue;
                const double d = inverted ? -h : h;
                ManifoldTriangle s = t;
                at(inverted ? (i + 1) * h : i * h, inverted ? (j + 1) * h : j * h, s);
                s.sEdge1 = {t.sEdge1.x * d, t.sEdge1.y * d};
                s.sEdge2 = {t.sEdge2.x * d, t.sEdge2.y * d};
                s.xStep1 = {t.xStep1.x * d, t.xStep1.y * d};
                s.xStep2 = {t.xStep2.x * d, t.xStep2.y * d};
                s.jacobian = t.jacobian * h * h;
                s.xArea = t.xArea * h * h;
                f(s);
            }
}
}  // namespace

double projectedArea(const PndfManifold& m, const Footprint& fp, const Vec3& w, const ProjectedAreaOptions& opt,
                     ProjectedAreaStats* stats) {
    if (stats) *stats = {};
    if (!(w.z > 0)) return 0.0;
    const Dir dir = makeDir(w);
    const IndexRange r = footprintRange(fp, 0);
    const long rows = long(r.rowHi) - r.rowLo + 1, cols = long(r.colHi) - r.colLo + 1;
    int k = 1;
    if (opt.maxCells > 0 && rows * cols > opt.maxCells)
        k = int(std::ceil(std::sqrt(double(rows * cols) / double(opt.maxCells))));
    // The kernel is held constant over each (sub-)triangle: at σ of a few texels it varies within a texel, and a
    // triangle's mass times its mean visible area misses how they correlate (the lobe's albedo then exceeds 1 by up to
    // ~2 % at grazing, σ = 1); n² sub-triangles per triangle where σ < 3 (as footprintTilt).
    const int subdivisions = std::clamp(int(std::ceil(3.0 / std::min(fp.sigmaU, fp.sigmaV))), 1, 3);
    double num = 0, den = 0;
    long cells = 0;
    for (long br = 0; br * k < rows; ++br)
        for (long bc = 0; bc * k < cols; ++bc) {
            int oy = 0, ox = 0;
            if (k > 1) blockOffset(int(br), int(bc), k, oy, ox);
            const long lr = br * k + oy, lc = bc * k + ox;
            if (lr >= rows || lc >= cols) continue;  // the block's pick fell outside the range (edge blocks)
            ManifoldTriangle tris[2];
            m.cellTriangles(int(r.rowLo + lr), int(r.colLo + lc), tris);
            ++cells;
            for (const ManifoldTriangle& whole : tris)
                // A replaced triangle's normals span the clamp's equilateral triangle E (circumradius 6e-4) around
                // one normal: not subdivided, so E keeps its centroid and a flat map keeps Ā = cosθ exactly.
                forEachSubTriangle(whole, whole.replaced ? 1 : subdivisions, [&](const ManifoldTriangle& t) {
                    const double g = triangleKernelMass(t, fp);
                    if (!(g > 0)) return;
                    // Π_T/|J_T| is the texel-area integral per unit triangle parameter; dividing the kernel mass g by
                    // the triangle's texel area (xArea/2) and multiplying by xArea turns it into 2g/|J|.
                    const double weight = 2.0 * g / std::abs(t.jacobian);
                    const TriGeom geom = prepare(t);
                    num += weight * projectedAreaOf(geom, dir);
                    den += weight * geom.area;
                });
        }
    if (stats) {
        stats->kernelMass = den;
        stats->cellsIntegrated = cells;
        stats->stride = k;
    }
    return den > 0 ? num / den : dir.c;
}


Vec2d footprintTilt(const PndfManifold& m, const Footprint& fp) {
    const IndexRange r = footprintRange(fp, 0);
    // The kernel varies within a texel at σ of a few texels, so each triangle is split into n² sub-triangles and the
    // midpoint rule weights s/m_z at their centroids by the kernel there (box and disk: their exact mass); once per
    // shading point, ~20 ns per sub-triangle.
    const int n = std::clamp(int(std::ceil(3.0 / std::min(fp.sigmaU, fp.sigmaV))), 1, 3);
    const bool gaussian = fp.kernel == FootprintKernel::Gaussian;
    double tx = 0, ty = 0, den = 0;
    for (int row = r.rowLo; row <= r.rowHi; ++row)
        for (int col = r.colLo; col <= r.colHi; ++col) {
            ManifoldTriangle tris[2];
            m.cellTriangles(row, col, tris);
            for (const ManifoldTriangle& whole : tris)
                forEachSubTriangle(whole, whole.replaced ? 1 : n, [&](const ManifoldTriangle& t) {
                    const double cx = t.xOrigin.x + (t.xStep1.x + t.xStep2.x) / 3.0;
                    const double cy = t.xOrigin.y + (t.xStep1.y + t.xStep2.y) / 3.0;
                    const double g = gaussian ? kernelWeight(fp, cx - fp.centreX, cy - fp.centreY) * 0.5 * t.xArea
                                              : triangleKernelMass(t, fp);
                    if (!(g > 0)) return;
                    const double sx = t.sOrigin.x + (t.sEdge1.x + t.sEdge2.x) / 3.0;
                    const double sy = t.sOrigin.y + (t.sEdge1.y + t.sEdge2.y) / 3.0;
                    const double mz = std::sqrt(std::max(1.0 - sx * sx - sy * sy, 1e-12));
                    tx += g * sx / mz;
                    ty += g * sy / mz;
                    den += g;
                });
        }
    return den > 0 ? Vec2d{tx / den, ty / den} : Vec2d{0, 0};
}

double smithG1FromProjectedArea(double area, double cosTheta) {
    if (!(cosTheta > 0)) return 0.0;
    const double c = std::min(cosTheta, 1.0);
    return c / std::clamp(area, c, 1.0);
}

double smithG1Analytic(const PndfManifold& m, const Footprint& fp, const Vec3& w, const ProjectedAreaOptions& opt) {
    if (!(w.z > 0)) return 0.0;
    const double len = std::sqrt(double(w.x) * w.x + double(w.y) * w.y + double(w.z) * w.z);
    return smithG1FromProjectedArea(projectedArea(m, fp, w, opt), w.z / len);
}

// ---- GGX fit (spec §4.2) ------------------------------------------------------------------------------------------

double GgxAlpha::alphaSquaredAt(double phi) const {
    const double cp = std::cos(phi - phi0), sp = std::sin(phi - phi0);
    return alpha1 * alpha1 * cp * cp + alpha2 * alpha2 * sp * sp;
}

GgxAlpha ggxAlphaFromFit(double a, double b, double e) {
    // [[a, h], [h, b]], h = e/2: λ = (a+b)/2 ± sqrt(((a-b)/2)² + h²); the λ1 eigenvector's angle φ0 solves
    // tan 2φ0 = 2h/(a-b).
    const double h = 0.5 * e, mean = 0.5 * (a + b), d = 0.5 * (a - b);
    const double rad = std::hypot(d, h);
    GgxAlpha g;
    g.alpha1 = std::sqrt(std::max(0.0, mean + rad));
    g.alpha2 = std::sqrt(std::max(0.0, mean - rad));  // a degenerate fit can give λ2 < 0: clamp
    g.phi0 = (rad > 0) ? 0.5 * std::atan2(h, d) : 0.0;
    return g;
}

double smithG1GgxFit(const GgxAlpha& alpha, const Vec3& w) {
    const double x = w.x, y = w.y, z = w.z;
    if (!(z > 0)) return 0.0;
    const double cp = std::cos(alpha.phi0), sp = std::sin(alpha.phi0);
    const double p = x * cp + y * sp, q = -x * sp + y * cp;  // ω_xy in the principal frame
    // α(φ)² |ω_xy|² = α1² (ω_xy·d1)² + α2² (ω_xy·d2)².
    const double a2s2 = alpha.alpha1 * alpha.alpha1 * p * p + alpha.alpha2 * alpha.alpha2 * q * q;
    const double e = z + x * alpha.tiltX + y * alpha.tiltY;
    const double area = 0.5 * (e + std::sqrt(a2s2 + e * e));
    return z / std::max(area, z);
}

double cellGrazingArea(const PndfManifold& m, int row, int col, double phi) {
    ManifoldTriangle tris[2];
    m.cellTriangles(row, col, tris);
    Dir dir;
    dir.c = 0;
    dir.s = 1;
    dir.u = {std::cos(phi), std::sin(phi)};
    double sum = 0;
    for (const ManifoldTriangle& t : tris) sum += projectedAreaOf(prepare(t), dir) * t.xArea / std::abs(t.jacobian);
    return sum;
}

PndfGgxFit::PndfGgxFit(const PndfManifold& m, int azimuths)
    : width_(m.width()), height_(m.height()), azimuths_(azimuths) {
    if (azimuths < 3) throw std::invalid_argument("PndfGgxFit: need >= 3 azimuths, got " + std::to_string(azimuths));
    // Directions φ_k = 2πk/K and the least-squares normal matrix of the basis (cos²φ, sin²φ, cosφ sinφ).
    std::vector<Dir> dirs(azimuths);
    std::vector<double> basis(3 * size_t(azimuths));
    double G[3][3] = {};
    for (int k = 0; k < azimuths; ++k) {
        const double phi = 2.0 * kPiD * k / azimuths;
        const double c = std::cos(phi), s = std::sin(phi);
        dirs[k].c = 0;
        dirs[k].s = 1;
        dirs[k].u = {c, s};
        const double f[3] = {c * c, s * s, c * s};
        for (int i = 0; i < 3; ++i) {
            basis[3 * k + i] = f[i];
            for (int j = 0; j < 3; ++j) G[i][j] += f[i] * f[j];
        }
    }
    // Inverse of the 3x3 normal matrix by cofactors; singular when the azimuths give < 3 distinct angles mod π
    // (e.g. K = 4: the basis is π-periodic).
    const double det = G[0][0] * (G[1][1] * G[2][2] - G[1][2] * G[2][1]) -
                       G[0][1] * (G[1][0] * G[2][2] - G[1][2] * G[2][0]) +
                       G[0][2] * (G[1][0] * G[2][1] - G[1][1] * G[2][0]);
    if (!(std::abs(det) > 1e-9 * azimuths * azimuths * azimuths))
        throw std::invalid_argument("PndfGgxFit: " + std::to_string(azimuths) +
                                    " azimuths give fewer than 3 distinct angles mod π; the fit is singular");
    double Gi[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
            Gi[i][j] = (G[i1][j1] * G[i2][j2] - G[i1][j2] * G[i2][j1]) / det;
        }

    firstLevel_ = (width_ % 2 == 0 && height_ % 2 == 0) ? 1 : 0;
    const int B = 1 << firstLevel_;
    const int w0 = width_ >> firstLevel_, h0 = height_ >> firstLevel_;
    levels_.emplace_back(size_t(w0) * h0);
    std::vector<Coeffs>& first = levels_.back();
    tbb::parallel_for(tbb::blocked_range<int>(0, h0), [&](const tbb::blocked_range<int>& range) {
        std::vector<double> y(azimuths);
        for (int nr = range.begin(); nr < range.end(); ++nr)
            for (int nc = 0; nc < w0; ++nc) {
                double acc[5] = {0, 0, 0, 0, 0};
                for (int r = nr * B; r < (nr + 1) * B; ++r)
                    for (int c = nc * B; c < (nc + 1) * B; ++c) {
                        ManifoldTriangle tris[2];
                        m.cellTriangles(r, c, tris);
                        const TriGeom g0 = prepare(tris[0]), g1 = prepare(tris[1]);
                        const double w0t = tris[0].xArea / std::abs(tris[0].jacobian);
                        const double w1t = tris[1].xArea / std::abs(tris[1].jacobian);
                        // The cell's mean tilt ∫ s/m_z dx = Σ_T (x-area/|J|) ∬_{s(T)} s/m_z d²s.
                        const double tx = g0.moment.x * w0t + g1.moment.x * w1t;
                        const double ty = g0.moment.y * w0t + g1.moment.y * w1t;
                        double rhs[3] = {0, 0, 0};
                        for (int k = 0; k < azimuths; ++k) {
                            const double A = projectedAreaOf(g0, dirs[k]) * w0t + projectedAreaOf(g1, dirs[k]) * w1t;
                            // α(φ)² of the GGX sheared by the tilt whose grazing area is A: 2A = e + sqrt(α² + e²).
                            const double e = dirs[k].u.x * tx + dirs[k].u.y * ty;
                            const double y2 = std::max(0.0, 4.0 * A * (A - e));
                            for (int i = 0; i < 3; ++i) rhs[i] += basis[3 * k + i] * y2;
                        }
                        for (int i = 0; i < 3; ++i)
                            acc[i] += Gi[i][0] * rhs[0] + Gi[i][1] * rhs[1] + Gi[i][2] * rhs[2];
                        acc[3] += tx;
                        acc[4] += ty;
                    }
                const double inv = 1.0 / (B * B);
                first[size_t(nr) * w0 + nc] = {float(acc[0] * inv), float(acc[1] * inv), float(acc[2] * inv),
                                               float(acc[3] * inv), float(acc[4] * inv)};
            }
    });
    // Coarser levels: 2x2 averages (in double) while both sides stay divisible.
    for (int l = firstLevel_ + 1; l <= 30; ++l) {
        if ((width_ % (1 << l)) != 0 || (height_ % (1 << l)) != 0) break;
        const std::vector<Coeffs>& fine = levels_.back();
        const int fw = width_ >> (l - 1), w = width_ >> l, h = height_ >> l;
        std::vector<Coeffs> level(size_t(w) * h);
        for (int nr = 0; nr < h; ++nr)
            for (int nc = 0; nc < w; ++nc) {
                double s[5] = {0, 0, 0, 0, 0};
                for (int dr = 0; dr < 2; ++dr)
                    for (int dc = 0; dc < 2; ++dc) {
                        const Coeffs& f = fine[size_t(2 * nr + dr) * fw + 2 * nc + dc];
                        s[0] += f.a;
                        s[1] += f.b;
                        s[2] += f.e;
                        s[3] += f.tiltX;
                        s[4] += f.tiltY;
                    }
                level[size_t(nr) * w + nc] = {float(0.25 * s[0]), float(0.25 * s[1]), float(0.25 * s[2]),
                                              float(0.25 * s[3]), float(0.25 * s[4])};
            }
        levels_.push_back(std::move(level));
    }
}

const PndfGgxFit::Coeffs& PndfGgxFit::node(int level, int row, int col) const {
    const int w = width_ >> level, h = height_ >> level;
    return levels_[level - firstLevel_][size_t(PndfManifold::wrap(row, h)) * w + PndfManifold::wrap(col, w)];
}

int PndfGgxFit::levelFor(const Footprint& fp) const {
    const double sigma = std::max(fp.sigmaU, fp.sigmaV);
    const int l = sigma > 0 ? int(std::lround(std::log2(2.0 * sigma))) : firstLevel_;
    return std::clamp(l, firstLevel_, firstLevel_ + levelCount() - 1);
}

GgxAlpha PndfGgxFit::alphaAt(const Footprint& fp) const {
    const int l = levelFor(fp);
    const double size = double(1 << l);
    // Bilinear between node centres ((col + ½)·2^ℓ, (row + ½)·2^ℓ): interpolating the linear coefficients is the
    // fit of the interpolated (2A)².
    const double fx = fp.centreX / size - 0.5, fy = fp.centreY / size - 0.5;
    const double cx = std::floor(fx), cy = std::floor(fy);
    const double tx = fx - cx, ty = fy - cy;
    const int c0 = int(cx), r0 = int(cy);
    double s[5] = {0, 0, 0, 0, 0};
    for (int dr = 0; dr < 2; ++dr)
        for (int dc = 0; dc < 2; ++dc) {
            const double wgt = (dr ? ty : 1 - ty) * (dc ? tx : 1 - tx);
            const Coeffs& n = node(l, r0 + dr, c0 + dc);
            s[0] += wgt * n.a;
            s[1] += wgt * n.b;
            s[2] += wgt * n.e;
            s[3] += wgt * n.tiltX;
            s[4] += wgt * n.tiltY;
        }
    GgxAlpha g = ggxAlphaFromFit(s[0], s[1], s[2]);
    g.tiltX = s[3];
    g.tiltY = s[4];
    return g;
}

size_t PndfGgxFit::memoryBytes() const {
    size_t bytes = 0;
    for (const auto& l : levels_) bytes += l.size() * sizeof(Coeffs);
    return bytes;
}

}  // namespace specula::pndf
