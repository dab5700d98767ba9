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

void environmentLookup(const Ltc& ltc, Vec3& dir, float& alpha) {
    const Vec3 m = glm::inverse(ltc.invM)[2];  // M·ẑ
    const float len = glm::length(m), det = std::abs(glm::determinant(ltc.invM));
    if (!(len > 0.f) || !(det > 0.f)) {
        dir = Vec3(0.f, 0.f, 1.f);
        alpha = 1.f;
        return;
    }
    dir = m / len;
    alpha = std::clamp(0.5f / (std::sqrt(det) * len * std::sqrt(len)), 0.f, 1.f);
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

namespace {
// Highest z of the great-circle arc a->b (unit vectors).
double arcMaxZ(const DVec3& a, const DVec3& b) {
    double z = std::max(a.z, b.z);
    DVec3 n = glm::cross(a, b);
    double nl = glm::length(n);
    if (nl < 1e-12) return z;
    n /= nl;
    DVec3 p = DVec3(0, 0, 1) - n * n.z;  // the great circle's highest point
    double pl = glm::length(p);
    if (pl < 1e-12) return z;
    p /= pl;
    if (glm::dot(glm::cross(a, p), n) >= 0.0 && glm::dot(glm::cross(p, b), n) >= 0.0) z = std::max(z, p.z);
    return z;
}

// Interior angle at vertex a of the spherical triangle (a, b, c).
double vertexAngle(const DVec3& a, const DVec3& b, const DVec3& c) {
    DVec3 tb = b - a * glm::dot(a, b), tc = c - a * glm::dot(a, c);
    return std::atan2(glm::length(glm::cross(tb, tc)), glm::dot(tb, tc));
}

// Uniform point of the spherical triangle (a, b, c) of area 'area' (Arvo 1995, "Stratified sampling of spherical
// triangles", §2: invert the sub-triangle area, then the arc from b).
DVec3 sampleSphericalTriangle(const DVec3& a, const DVec3& b, const DVec3& c, double area, double u1, double u2) {
    const double alpha = vertexAngle(a, b, c);
    const double ahat = u1 * area;
    const double s = std::sin(ahat - alpha), t = std::cos(ahat - alpha);
    const double ca = std::cos(alpha), sa = std::sin(alpha);
    const double uu = t - ca, vv = s + sa * glm::dot(a, b);
    const double den = (vv * s + uu * t) * sa;
    double q = den != 0.0 ? ((vv * t - uu * s) * ca - vv) / den : 1.0;
    q = std::clamp(q, -1.0, 1.0);
    DVec3 perp = c - a * glm::dot(c, a);
    double pl = glm::length(perp);
    DVec3 chat = pl > 0.0 ? q * a + std::sqrt(std::max(0.0, 1.0 - q * q)) * (perp / pl) : c;
    double z = 1.0 - u2 * (1.0 - glm::dot(chat, b));
    DVec3 r = chat - b * glm::dot(chat, b);
    double rl = glm::length(r);
    return rl > 0.0 ? z * b + std::sqrt(std::max(0.0, 1.0 - z * z)) * (r / rl) : b;
}

double hashUniform(uint64_t seed, uint32_t t, uint32_t k) {
    return double(mix64(seed ^ (0x9E3779B97F4A7C15ULL * (uint64_t(t) * 4 + k + 1))) >> 11) * 0x1.0p-53;
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
    const double E = exactLoop(c, k);  // ∫_P D_o: the projected area on the disk is π E
    if (!(E > 0.0)) return false;
    DVec3 edge[9];
    double x0 = 1, x1 = -1, y0 = 1, y1 = -1, zmax = 0;
    for (int i = 0; i < k; ++i) {
        edge[i] = glm::cross(c[i], c[(i + 1) % k]);
        arcBounds(c[i], c[(i + 1) % k], x0, x1, y0, y1);
        zmax = std::max(zmax, arcMaxZ(c[i], c[(i + 1) % k]));
    }
    // The extremes of x and y lie on the boundary (the x/y poles are on the horizon, the clipped polygon's edge at
    // most); z can peak inside: at the zenith, when the polygon contains it.
    bool zenith = true;
    for (int i = 0; i < k && zenith; ++i) zenith = edge[i].z >= 0.0;
    if (zenith) zmax = 1.0;
    x0 = std::max(x0, -1.0), y0 = std::max(y0, -1.0), x1 = std::min(x1, 1.0), y1 = std::min(y1, 1.0);
    if (!(x1 > x0) || !(y1 > y0) || !(zmax > 0.0)) return false;
    // Two exact samplers of the density ∝ cos θ on the polygon (cosine space); the one with the higher acceptance is
    // chosen from the polygon alone (so the choice does not bias the result):
    // (a) Malley: a uniform point of the polygon's projection onto the unit disk, lifted to the hemisphere, by
    //     rejection from the projection's exact bounding box (acceptance π E / box area): small or overhead lights;
    // (b) a uniform point of the spherical polygon (triangle fan, Arvo 1995) kept with probability z / z_max
    //     (acceptance π E / (Ω z_max)): large or grazing polygons, e.g. thin crescents near the horizon.
    // The fan's areas (and so (b)'s acceptance) are computed only when (a) is poor: most lights are small or overhead.
    const double accBox = kPiD * E / ((x1 - x0) * (y1 - y0));
    double area[8], omega = 0;
    bool malley = true;
    if (accBox < 0.3) {
        for (int i = 1; i + 1 < k; ++i) {
            double ar = vertexAngle(c[0], c[i], c[i + 1]) + vertexAngle(c[i], c[i + 1], c[0]) +
                        vertexAngle(c[i + 1], c[0], c[i]) - kPiD;
            area[i] = std::max(ar, 0.0);
            omega += area[i];
        }
        const double accArvo = omega > 0.0 ? kPiD * E / (omega * zmax) : 0.0;
        malley = accBox >= accArvo;
    }
    const glm::dmat3 M = glm::inverse(m);
    for (uint32_t t = 0; t < 4096; ++t) {
        double u0 = t == 0 ? double(u.x) : hashUniform(seed, t, 0), u1 = t == 0 ? double(u.y) : hashUniform(seed, t, 1);
        DVec3 p;
        if (malley) {
            double x = x0 + u0 * (x1 - x0), y = y0 + u1 * (y1 - y0);
            double r2 = x * x + y * y;
            if (r2 >= 1.0) continue;
            p = DVec3(x, y, std::sqrt(1.0 - r2));
            bool inside = true;
            for (int i = 0; i < k && inside; ++i) inside = glm::dot(p, edge[i]) >= 0.0;
            if (!inside) continue;
        } else {
            // Pick a fan triangle ∝ its area with u0 (then rescaled for reuse), sample it with (u0', u1).
            double pick = u0 * omega;
            int tri = 1;
            while (tri + 2 < k && pick >= area[tri]) pick -= area[tri++];
            double ur = area[tri] > 0.0 ? std::clamp(pick / area[tri], 0.0, 1.0) : 0.0;
            p = sampleSphericalTriangle(c[0], c[tri], c[tri + 1], area[tri], ur, u1);
            if (hashUniform(seed, t, 2) * zmax >= p.z) continue;
        }
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
