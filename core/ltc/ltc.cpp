// Linearly transformed cosines: density, sampling, the polygon integral with exact clipping or the clip-free sphere
// approximation, polygon-restricted sampling (Malley's method) and the one-LTC lobe (ltc-filtering.md §1, §3).
#include "core/ltc/ltc.h"

#include "core/ltc/ltc_tables.h"
#include "core/render/sampler.h"
#include "core/render/sampling.h"

#include <algorithm>
#include <cmath>

namespace specula::ltc {

namespace {
constexpr double kTwoPi = 6.283185307179586476925;
constexpr double kPiD = 3.141592653589793238463;

glm::dmat3 toDouble(const Mat3& m) { return glm::dmat3(m); }

// Sum of exact edge terms of a closed polygon of unit vectors.
double exactLoop(const DVec3* v, int n) {
    double e = 0.0;
    for (int i = 0; i < n; ++i) e += edgeIntegralExact(v[i], v[(i + 1) % n]);
    return e;
}

// Orientation of a polygon seen from the origin: > 0 when it faces the origin in the sense of the edge formula
// (a counter-clockwise polygon overhead gives a positive form factor).
double facing(const DVec3* v, int n) {
    DVec3 nrm(0.0);
    for (int i = 0; i < n; ++i) nrm += glm::cross(v[i], v[(i + 1) % n]);  // Newell normal (area-weighted)
    DVec3 c(0.0);
    for (int i = 0; i < n; ++i) c += v[i];
    return glm::dot(nrm, c);
}

// Clip-free horizon handling: the cap with the polygon's form-factor vector, horizon-clipped (§3 step 5). With
// tables, the tabulated scale (as the GPU does); without, the exact cap formula.
double sphereHorizon(const DVec3& F, const LtcTables* tables) {
    double len = glm::length(F);
    if (len <= 0.0) return 0.0;
    double z = std::clamp(F.z / len, -1.0, 1.0);
    if (tables) return len * double(sphereScale(*tables, float(z), float(len)));  // as the GPU does
    // The cap centred on the normal with form factor sin²σ = |F| (a cap's vector form factor has that length).
    double sigma = std::asin(std::sqrt(std::min(len, 1.0)));
    return capFormFactor(std::acos(z), sigma);
}
}  // namespace

float Ltc::density(const Vec3& w) const {
    Vec3 o = invM * w;
    float l2 = glm::dot(o, o);
    if (!(l2 > 0.f)) return 0.f;
    float l = std::sqrt(l2);
    float cosO = o.z / l;
    if (cosO <= 0.f) return 0.f;
    // D(w) = D_o(w_o) |det M⁻¹| / |M⁻¹ w|³  (HDHN16 Eq. 1, Jacobian of w_o -> w)
    return cosO * kInvPi * std::abs(glm::determinant(invM)) / (l2 * l);
}

Vec3 Ltc::sample(const Vec2& u) const {
    Vec3 wo = sampleCosineHemisphere(u);
    return glm::normalize(glm::inverse(invM) * wo);
}

double edgeIntegralExact(const DVec3& a, const DVec3& b) {
    DVec3 c = glm::cross(a, b);
    double s = glm::length(c);
    if (s < 1e-300) return 0.0;  // coincident (or antipodal) vertices: no edge
    double x = std::clamp(glm::dot(a, b), -1.0, 1.0);
    return std::acos(x) * (c.z / s) / kTwoPi;
}

double rationalEdgeFactor(double x) {
    // θ/sin θ/2π ≈ a(y)/b(y) for y = |x| (ltc_code's cubic-over-quadratic fit, exact-ish for x ≥ 0); for x < 0,
    // θ/sin θ = π/sin θ − θ'/sin θ' with θ' = π − θ (§3 step 3).
    double y = std::abs(x);
    double a = 0.8543985 + (0.4965155 + 0.0145206 * y) * y;
    double b = 3.4175940 + (4.1616724 + y) * y;
    double v = a / b;
    return x >= 0.0 ? v : 0.5 / std::sqrt(std::max(1.0 - x * x, 1e-7)) - v;
}

DVec3 edgeVectorRational(const DVec3& a, const DVec3& b) { return glm::cross(a, b) * rationalEdgeFactor(glm::dot(a, b)); }

int clipToUpperHemisphere(const DVec3* in, int n, DVec3* out) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const DVec3& p = in[i];
        const DVec3& q = in[(i + 1) % n];
        bool pIn = p.z > 0.0, qIn = q.z > 0.0;
        if (pIn) out[m++] = p;
        if (pIn != qIn) {
            double t = p.z / (p.z - q.z);
            DVec3 x = p + t * (q - p);
            x.z = 0.0;
            out[m++] = x;
        }
    }
    return m;
}

double capFormFactor(double omega, double sigma) {
    // Snyder 1996 (ltc-filtering.md §3 step 5): the form factor of a cap of half-angle σ whose axis makes the angle
    // ω with the normal, clipped by the horizon.
    double s = std::sin(sigma);
    s *= s;
    if (omega <= 0.5 * kPiD - sigma) return std::cos(omega) * s;
    if (omega >= 0.5 * kPiD + sigma) return 0.0;
    double sw = std::sin(omega), cw = std::cos(omega), cs = std::cos(sigma);
    double g = std::asin(std::clamp(cs / sw, -1.0, 1.0));
    double cg = std::cos(g), sg = std::sin(g);
    double G = -2.0 * sw * cs * cg + 0.5 * kPiD - g + sg * cg;
    double H = cw * (cg * std::sqrt(std::max(s - cg * cg, 0.0)) + s * std::asin(std::clamp(cg / std::sin(sigma), -1.0, 1.0)));
    return omega < 0.5 * kPiD ? (kPiD * cw * s + G - H) / kPiD : (G + H) / kPiD;
}

double clampedCosineIntegral(const DVec3* v, int n, bool twoSided, Horizon horizon, const LtcTables* tables) {
    if (n < 3 || n > 8) return 0.0;
    if (horizon == Horizon::Clip) {
        DVec3 c[9];
        int m = clipToUpperHemisphere(v, n, c);
        if (m < 3) return 0.0;
        for (int i = 0; i < m; ++i) c[i] = glm::normalize(c[i]);
        double e = exactLoop(c, m);
        return twoSided ? std::abs(e) : std::max(0.0, e);
    }
    DVec3 u[8];
    for (int i = 0; i < n; ++i) u[i] = glm::normalize(v[i]);
    DVec3 F(0.0);
    for (int i = 0; i < n; ++i) F += edgeVectorRational(u[i], u[(i + 1) % n]);
    if (facing(v, n) < 0.0) {  // seen from behind: the vector points away from the polygon
        if (!twoSided) return 0.0;
        F = -F;
    }
    return sphereHorizon(F, tables);
}

double integrate(const Ltc& ltc, const Vec3* vertices, int n, bool twoSided, Horizon horizon, const LtcTables* tables) {
    if (n < 3 || n > 8) return 0.0;
    glm::dmat3 m = toDouble(ltc.invM);
    DVec3 v[8];
    // A reflection in M⁻¹ reverses the winding: restore it so the sign convention holds in cosine space.
    const bool flip = glm::determinant(m) < 0.0;
    for (int i = 0; i < n; ++i) v[flip ? n - 1 - i : i] = m * DVec3(vertices[i]);
    return clampedCosineIntegral(v, n, twoSided, horizon, tables);
}

double integrateForLobe(const Ltc& ltc, const Vec3* vertices, int n, uint8_t horizon) {
    const Horizon h = Horizon(horizon);
    return integrate(ltc, vertices, n, false, h, h == Horizon::Clipless ? &builtinTables() : nullptr);
}

namespace {
// Extent of the projection (x, y) of the great-circle arc a->b (unit, z ≥ 0) onto the disk.
void arcBounds(const DVec3& a, const DVec3& b, double& x0, double& x1, double& y0, double& y1) {
    auto add = [&](const DVec3& p) {
        x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
        y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    };
    add(a);
    add(b);
    DVec3 n = glm::cross(a, b);
    double nl = glm::length(n);
    if (nl < 1e-12) return;
    n /= nl;
    for (int axis = 0; axis < 2; ++axis) {
        DVec3 e(axis == 0 ? 1.0 : 0.0, axis == 1 ? 1.0 : 0.0, 0.0);
        DVec3 p = e - n * glm::dot(n, e);  // the great circle's extreme point along e
        double pl = glm::length(p);
        if (pl < 1e-12) continue;
        p /= pl;
        for (double s : {1.0, -1.0}) {
            DVec3 c = s * p;
            if (glm::dot(glm::cross(a, c), n) >= 0.0 && glm::dot(glm::cross(c, b), n) >= 0.0) add(c);
        }
    }
}
}  // namespace

bool samplePolygon(const Ltc& ltc, const Vec3* vertices, int n, const Vec2& u, uint64_t seed, Vec3& w) {
    if (n < 3 || n > 8) return false;
    glm::dmat3 m = toDouble(ltc.invM);
    const bool flip = glm::determinant(m) < 0.0;
    DVec3 v[8], c[9];
    for (int i = 0; i < n; ++i) v[flip ? n - 1 - i : i] = m * DVec3(vertices[i]);
    if (facing(v, n) <= 0.0) return false;  // one-sided: seen from behind
    int k = clipToUpperHemisphere(v, n, c);
    if (k < 3) return false;
    for (int i = 0; i < k; ++i) c[i] = glm::normalize(c[i]);
    DVec3 edge[9];
    double x0 = 1, x1 = -1, y0 = 1, y1 = -1;
    for (int i = 0; i < k; ++i) {
        edge[i] = glm::cross(c[i], c[(i + 1) % k]);
        arcBounds(c[i], c[(i + 1) % k], x0, x1, y0, y1);
    }
    x0 = std::max(x0, -1.0), y0 = std::max(y0, -1.0), x1 = std::min(x1, 1.0), y1 = std::min(y1, 1.0);
    if (!(x1 > x0) || !(y1 > y0)) return false;
    // Malley: a uniform point of the polygon's projection onto the unit disk, lifted to the hemisphere, is
    // distributed ∝ cos θ over the spherical polygon. Rejection from the bounding box of the projection.
    const glm::dmat3 M = glm::inverse(m);
    for (uint32_t t = 0; t < 4096; ++t) {
        double ux = u.x, uy = u.y;
        if (t > 0) {
            uint64_t h = mix64(seed ^ (0x9E3779B97F4A7C15ULL * t));
            ux = double(h >> 11) * 0x1.0p-53;
            uy = double(mix64(h) >> 11) * 0x1.0p-53;
        }
        double x = x0 + ux * (x1 - x0), y = y0 + uy * (y1 - y0);
        double r2 = x * x + y * y;
        if (r2 >= 1.0) continue;
        DVec3 p(x, y, std::sqrt(1.0 - r2));
        bool inside = true;
        for (int i = 0; i < k && inside; ++i) inside = glm::dot(p, edge[i]) >= 0.0;
        if (!inside) continue;
        w = Vec3(glm::normalize(M * p));
        return true;
    }
    return false;
}

LobeValue LtcLobe::evalPdf(const LobeQuery& q) const {
    if (q.wo.z <= 0.f || q.wi.z <= 0.f) return {};
    float d = ltc_.density(q.wi);
    return {tint_ * (ltc_.magnitude * d), d};
}

bool LtcLobe::sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const {
    if (q.wo.z <= 0.f) return false;
    wi = ltc_.sample(u);
    return wi.z > 0.f;
}

void LtcLobe::parameters(const LobeQuery&, LobeParameters& out) const {
    std::vector<double> m;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) m.push_back(ltc_.invM[c][r]);
    out.push_back({"inverse_matrix", m});
    out.push_back({"magnitude", {ltc_.magnitude}});
    out.push_back({"tint", {tint_.x, tint_.y, tint_.z}});
}

bool LtcLobe::integratePolygon(const LobeQuery& q, const Vec3* vertices, int count, Color3& result) const {
    if (q.wo.z <= 0.f) {
        result = Color3(0.f);
        return true;
    }
    double e = integrateForLobe(ltc_, vertices, count, q.polygonHorizon);
    result = tint_ * float(ltc_.magnitude * e);
    return true;
}

bool LtcLobe::samplePolygon(const LobeQuery& q, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                            Vec3& wi) const {
    return q.wo.z > 0.f && ltc::samplePolygon(ltc_, vertices, count, u, seed, wi);
}

}  // namespace specula::ltc
