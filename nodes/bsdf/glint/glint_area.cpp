// Glints under polygonal lights (glint_area.h): half-slope region of the light, exact per-cell masses by Green's
// theorem on the dictionary's piecewise-linear marginals, EWA and LOD weights of the point evaluation.
#include "nodes/bsdf/glint/glint_area.h"

#include "core/ltc/ltc.h"

#include <algorithm>
#include <cmath>

namespace specula::glint {

namespace {

constexpr double kLim = 4.0 * kSigmaO;  // support of the cell marginals: |m| < 4 σ_o
constexpr double kDeltaD = kDelta;      // texel spacing (texel centres at (n + 1/2) δ)

// p_{d,k}(|x|) for |x| <= 4 σ_o as cellSdf reads it (sampleLinear on MIP 0); the caller keeps |x| inside the support.
inline double marginalAt(const float* row, double x) {
    return sampleLinear(row, kRes, float(std::min(std::abs(x), kLim) / kLim));
}

// Appends to t[] the parameters in (0, 1) where x0 + t dx crosses a breakpoint of the marginal grid: 0, the texel
// centres ±(n + 1/2) δ and ±4 σ_o.
inline void gridCrossings(double x0, double dx, double* t, int& n) {
    if (dx == 0.0) return;
    const double xa = std::max(std::min(x0, x0 + dx), -kLim), xb = std::min(std::max(x0, x0 + dx), kLim);
    if (!(xb > xa)) return;
    auto add = [&](double xv) {
        const double tv = (xv - x0) / dx;
        if (tv > 0.0 && tv < 1.0) t[n++] = tv;
    };
    const int m0 = int(std::ceil(xa / kDeltaD - 0.5)), m1 = int(std::floor(xb / kDeltaD - 0.5));
    for (int m = std::max(m0, -kRes); m <= std::min(m1, kRes - 1); ++m) add((m + 0.5) * kDeltaD);
    if (xa < 0.0 && xb > 0.0) add(0.0);
    add(-kLim);
    add(kLim);
}

// One edge's share of (A2): -∫ p_i(x(t)) F_j(y(t)) dx over the part of the edge with |x| < 4 σ_o.
double edgeMass(const Dictionary& dict, int k, int i, int j, DVec2 a, DVec2 b) {
    const double dx = b.x - a.x, dy = b.y - a.y;
    if (dx == 0.0) return 0.0;
    // The t-range where |x| < 4 σ_o (outside it p_i = 0).
    double t0 = (-kLim - a.x) / dx, t1 = (kLim - a.x) / dx;
    if (t0 > t1) std::swap(t0, t1);
    t0 = std::max(t0, 0.0), t1 = std::min(t1, 1.0);
    if (!(t1 > t0)) return 0.0;
    double t[4 * kRes + 16];
    int n = 0;
    gridCrossings(a.x, dx, t, n);
    gridCrossings(a.y, dy, t, n);
    // Keep the breakpoints inside [t0, t1], then add the ends.
    int kept = 0;
    for (int s = 0; s < n; ++s)
        if (t[s] > t0 && t[s] < t1) t[kept++] = t[s];
    t[kept++] = t0;
    t[kept++] = t1;
    std::sort(t, t + kept);
    const float* rowI = dict.row(k, i);
    auto phi = [&](double tv) {
        const double x = a.x + tv * dx, y = a.y + tv * dy;
        return marginalAt(rowI, x) * double(dict.marginalCdf(k, j, float(y)));
    };
    // Simpson's rule on each piece between breakpoints: exact, the integrand is a cubic there.
    double sum = 0.0, fa = phi(t[0]);
    for (int s = 0; s + 1 < kept; ++s) {
        if (!(t[s + 1] > t[s])) continue;
        const double fb = phi(t[s + 1]);
        sum += (t[s + 1] - t[s]) * (fa + 4.0 * phi(0.5 * (t[s] + t[s + 1])) + fb);
        fa = fb;
    }
    return -dx * sum / 6.0;
}

// The smooth factor of (A1) without F: G (wo·h) / (h_z wo.z) at half slope hs; h is returned for F.
double smoothFactor(const Vec3& wo, DVec2 hs, Vec3& h) {
    const DVec3 hd = glm::normalize(DVec3(-hs.x, -hs.y, 1.0));
    h = Vec3(hd);
    const DVec3 o(wo);
    const double woh = glm::dot(o, hd);
    if (!(woh > 0.0)) return 0.0;
    const double wiz = std::max(2.0 * woh * hd.z - o.z, 0.0);  // wi = 2 (wo·h) h - wo; wi·h = wo·h
    const double G = std::min(1.0, 2.0 * hd.z * o.z / woh) * std::min(1.0, 2.0 * hd.z * wiz / woh);
    return G * woh / (hd.z * o.z);
}

}  // namespace

double cellPolygonMass(const Dictionary& dict, int k, int i, int j, const DVec2* q, int n) {
    double sum = 0.0;
    for (int e = 0; e < n; ++e) sum += edgeMass(dict, k, i, j, q[e], q[(e + 1) % n]);
    return sum;
}

double gaussianPolygonMass(const DVec2* q, int n) {
    // (A2) with p = N(0, σ_o²) and F(y) = erf(y / (σ_o √2)) / 2, on each edge's part with |x| < 8 σ_o (beyond it p is
    // below 1e-13 of its peak), Simpson on steps of at most σ_o / 8 (relative error ~1e-6).
    const double so = kSigmaO, xmax = 8.0 * so, h = so / 8.0;
    const double norm = 1.0 / (so * std::sqrt(2.0 * kPiD)), ir = 1.0 / (so * std::sqrt(2.0));
    double total = 0.0;
    for (int e = 0; e < n; ++e) {
        const DVec2 a = q[e], b = q[(e + 1) % n];
        const double dx = b.x - a.x, dy = b.y - a.y;
        if (dx == 0.0) continue;
        double t0 = (-xmax - a.x) / dx, t1 = (xmax - a.x) / dx;
        if (t0 > t1) std::swap(t0, t1);
        t0 = std::max(t0, 0.0), t1 = std::min(t1, 1.0);
        if (!(t1 > t0)) continue;
        const int steps = std::max(1, int(std::ceil((t1 - t0) * std::abs(dx) / h)));
        auto phi = [&](double tv) {
            const double x = a.x + tv * dx, y = a.y + tv * dy;
            return norm * std::exp(-0.5 * x * x / (so * so)) * 0.5 * std::erf(y * ir);
        };
        const double dt = (t1 - t0) / steps;
        double sum = 0.0, fa = phi(t0);
        for (int s = 0; s < steps; ++s) {
            const double ta = t0 + s * dt, fb = phi(ta + dt);
            sum += fa + 4.0 * phi(ta + 0.5 * dt) + fb;
            fa = fb;
        }
        total += -dx * sum * dt / 6.0;
    }
    return total;
}

int halfSlopeRegion(const Vec3& wo, const Vec3* vertices, int count, const GlintAreaSettings& settings, DVec2* out) {
    if (count < 3 || count > 4 || wo.z <= 0.f) return 0;
    DVec3 v[4], c[5];
    for (int i = 0; i < count; ++i) v[i] = DVec3(vertices[i]);
    // One-sided, as the LTC lobes: the Newell normal against the centroid (ltc.cpp facing()).
    DVec3 nrm(0.0), cen(0.0);
    for (int i = 0; i < count; ++i) nrm += glm::cross(v[i], v[(i + 1) % count]), cen += v[i];
    if (!(glm::dot(nrm, cen) > 0.0)) return 0;
    const int m = ltc::clipToUpperHemisphere(v, count, c);
    if (m < 3) return 0;
    for (int i = 0; i < m; ++i) c[i] = glm::normalize(c[i]);
    const DVec3 o = glm::normalize(DVec3(wo));
    const int maxChords = std::clamp(settings.maxChordsPerEdge, 1, 24);
    int n = 0;
    for (int e = 0; e < m; ++e) {
        const DVec3 a = c[e], b = c[(e + 1) % m];
        const double angle = std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
        const int chords = std::clamp(int(std::ceil(angle / std::max(double(settings.maxChordAngle), 1e-4))), 1, maxChords);
        for (int s = 0; s < chords; ++s) {
            // Points of the great-circle arc (the edge of the spherical polygon) by normalised linear interpolation.
            const DVec3 wi = glm::normalize(a + (b - a) * (double(s) / chords));
            const DVec3 h = glm::normalize(o + wi);  // h.z > 0: wo.z > 0 and wi.z >= 0
            out[n++] = DVec2(-h.x / h.z, -h.y / h.z);
        }
    }
    // Orientation: the map may mirror the plane (h~ = -h_xy/h_z); make the region counter-clockwise for (A2).
    double area2 = 0.0;
    for (int i = 0; i < n; ++i) area2 += out[i].x * out[(i + 1) % n].y - out[(i + 1) % n].x * out[i].y;
    if (area2 < 0.0) std::reverse(out, out + n);
    return area2 != 0.0 ? n : 0;
}

bool glintPolygonIntegral(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                          const GlintEvalInputs& in, const Vec3& wo, const Vec3* vertices, int count,
                          GlintAreaResult& out, const GlintAreaSettings& settings) {
    out = GlintAreaResult{};
    DVec2 region[kMaxRegionVertices];
    const int n = halfSlopeRegion(wo, vertices, count, settings, region);
    if (n < 3) return false;
    // Area centroid of R, where the smooth factor of (A1) is taken.
    double A = 0.0, cx = 0.0, cy = 0.0;
    for (int e = 0; e < n; ++e) {
        const DVec2 a = region[e], b = region[(e + 1) % n];
        const double cr = a.x * b.y - b.x * a.y;
        A += cr, cx += (a.x + b.x) * cr, cy += (a.y + b.y) * cr;
    }
    DVec2 centroid = A != 0.0 ? DVec2(cx, cy) / (3.0 * A) : region[0];
    const double g = smoothFactor(wo, centroid, out.hCentroid);
    if (!(g > 0.0)) return true;

    // R in M^-1 space (m before the cell's rotation), and its distance range to the origin: a cell's rotated polygon
    // misses the support square |m| < 4 σ_o when R lies beyond its circumcircle of radius 4 σ_o √2.
    DVec2 mr[kMaxRegionVertices];
    const double mi00 = shape.mi00, mi01 = shape.mi01, mi11 = shape.mi11;
    for (int e = 0; e < n; ++e) mr[e] = DVec2(mi00 * region[e].x + mi01 * region[e].y, mi11 * region[e].y);
    bool containsOrigin = false;  // crossing-number test (R may be slightly non-convex: its edges are chords of curves)
    double minDist2 = 1e300;
    for (int e = 0; e < n; ++e) {
        const DVec2 a = mr[e], b = mr[(e + 1) % n], d = b - a;
        if ((a.y > 0.0) != (b.y > 0.0) && a.x - a.y * d.x / d.y > 0.0) containsOrigin = !containsOrigin;
        const double len2 = glm::dot(d, d);
        const double tt = len2 > 0.0 ? std::clamp(-glm::dot(a, d) / len2, 0.0, 1.0) : 0.0;
        const DVec2 c = a + tt * d;
        minDist2 = std::min(minDist2, glm::dot(c, c));
    }
    const bool missesAll = !containsOrigin && minDist2 >= 2.0 * kLim * kLim;

    double convergedMass = -1.0;  // the Beckmann mass, computed on first use (shared by all converged cells)
    auto beckmannMass = [&]() {
        if (convergedMass < 0.0) convergedMass = std::max(gaussianPolygonMass(mr, n), 0.0);
        return convergedMass;
    };
    const Footprint fp = footprint(in.duvdx, in.duvdy, p.maxAniso);
    if (!fp.valid) {
        out.integral = float(g * beckmannMass());
        return true;
    }
    SdfQuery q;  // the point evaluation's per-query constants that drawCell reads (no half vector: none is fixed here)
    q.relArea = p.relArea;
    q.jitter = p.jitter;
    q.lcBase = p.logDensity / 1.38629436f - float(kLevels - 1);

    DVec2 rotated[kMaxRegionVertices];
    // The EWA average of the cells' masses at level l: the point evaluation's levelSdf with each SDF value replaced
    // by its integral over R (the weights do not depend on h~, so the average commutes with the integral).
    auto levelMass = [&](int l) {
        double sumW = 0.0, sumWM = 0.0;
        out.cells += forEachCell(l, in.uv, fp.a1, fp.a2, [&](int s, int t, float W) {
            sumW += W;
            const CellDraw d = drawCell(q, l, s, t);
            if (d.empty) return;
            if (d.converged) {
                sumWM += W * beckmannMass();
                return;
            }
            if (missesAll) return;
            // Rot(-θ): m = (c x + s y, -s x + c y), as cellSdf.
            const double c = std::cos(double(d.theta)), sn = std::sin(double(d.theta));
            double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
            for (int e = 0; e < n; ++e) {
                rotated[e] = DVec2(c * mr[e].x + sn * mr[e].y, -sn * mr[e].x + c * mr[e].y);
                x0 = std::min(x0, rotated[e].x), x1 = std::max(x1, rotated[e].x);
                y0 = std::min(y0, rotated[e].y), y1 = std::max(y1, rotated[e].y);
            }
            if (x0 >= kLim || x1 <= -kLim || y0 >= kLim || y1 <= -kLim) return;  // outside the support square
            sumWM += W * cellPolygonMass(dict, d.k, d.i, d.j, rotated, n);
        });
        return sumW > 0.0 ? sumWM / sumW : 0.0;
    };
    // The LOD blend of patchSdf (C20 Eq. 3).
    const float i0f = std::floor(fp.lodP);
    const int l0 = int(i0f);
    const double w = fp.lodP - i0f;
    double mass = levelMass(l0);
    if (w > 0.0) mass = (1.0 - w) * mass + w * levelMass(std::min(l0 + 1, kLevels - 1));
    out.integral = float(g * std::max(mass, 0.0));
    return true;
}

bool glintSamplePolygon(const Vec3* vertices, int count, const Vec2& u, uint64_t seed, Vec3& wi) {
    return ltc::samplePolygon(ltc::Ltc{}, vertices, count, u, seed, wi);
}

// ---- GlintLobe's polygon entries (declared in glint_bsdf.h) ----------------------------------------------------

bool GlintLobe::integratePolygon(const LobeQuery& q, const Vec3* vertices, int count, Color3& result) const {
    result = Color3(0.f);
    GlintAreaResult r;
    if (glintPolygonIntegral(dict_, p_, shape_, in_, q.wo, vertices, count, r) && r.integral > 0.f)
        result = fresnel_.eval(glm::dot(q.wo, r.hCentroid)) * r.integral;  // F at the region's centroid (A1)
    return true;  // invisible lights integrate to 0, as LtcLobe
}

bool GlintLobe::samplePolygon(const LobeQuery& q, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                              Vec3& wi) const {
    return q.wo.z > 0.f && glintSamplePolygon(vertices, count, u, seed, wi);
}

}  // namespace specula::glint
