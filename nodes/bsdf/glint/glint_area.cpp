// Glints under polygonal lights (glint_area.h): half-slope region of the light, exact per-cell masses by Green's
// theorem on the dictionary's piecewise-linear marginals, EWA and LOD weights of the point evaluation.
#include "nodes/bsdf/glint/glint_area.h"

#include "core/ltc/ltc.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <vector>

namespace specula::glint {

namespace {

using DVec4 = glm::dvec4;

constexpr double kPiD = 3.14159265358979323846;
constexpr double kLim = 4.0 * kSigmaO;  // support of the cell marginals: |m| < 4 σ_o
constexpr double kDeltaD = kDelta;      // texel spacing (texel centres at (n + 1/2) δ)

// One cell marginal as the point evaluation reads it: MIP m0 (or, with GGAA, the blend of MIPs m0 and m0 + 1 of
// textureGrad1D), its value p(|x|) and its signed cumulative F(x) = ∫_0^x p(|x'|) dx' (as Dictionary::marginalCdf
// for MIP 0). Both are exact for the GL_LINEAR reconstruction: p piecewise linear, F piecewise quadratic between the
// texel centres of the MIPs read.
struct FilteredMarginal {
    const Dictionary* dict;
    int k, d;
    int mip[2];
    const float* p[2];
    int res[2];
    double spacing[2];
    float f = 0.f;  // weight of the second MIP
    int mips = 1;
    FilteredMarginal(const Dictionary& dictionary, int level, int marginal, MipBlend b)
        : dict(&dictionary), k(level), d(marginal) {
        mips = b.f > 0.f ? 2 : 1;
        f = b.f;
        for (int e = 0; e < 2; ++e) {
            mip[e] = std::min(b.m0 + e, kMips - 1);
            p[e] = dictionary.mip(k, d, mip[e]);
            res[e] = mipRes(mip[e]);
            spacing[e] = kLim / res[e];
        }
    }
    // p(|x|) for |x| <= 4 σ_o (the caller keeps |x| inside the support).
    double value(double x) const {
        const float u = float(std::min(std::abs(x), kLim) / kLim);
        const double v0 = sampleLinear(p[0], res[0], u);
        if (mips == 1) return v0;
        return (1.0 - f) * v0 + f * double(sampleLinear(p[1], res[1], u));
    }
    double cdf(double x) const {
        const double ax = std::min(std::abs(x), kLim), sign = x < 0.0 ? -1.0 : 1.0;
        double v = dict->mipCdf(k, d, mip[0], ax);
        if (mips == 2) v = (1.0 - f) * v + f * dict->mipCdf(k, d, mip[1], ax);
        return sign * v;
    }
};

// Appends to t[] the parameters in (0, 1) where x0 + t dx crosses a breakpoint of the marginal's grids: 0, the texel
// centres ±(n + 1/2) s of each MIP read and ±4 σ_o.
inline void gridCrossings(const FilteredMarginal& fm, double x0, double dx, double* t, int& n) {
    if (dx == 0.0) return;
    const double xa = std::max(std::min(x0, x0 + dx), -kLim), xb = std::min(std::max(x0, x0 + dx), kLim);
    if (!(xb > xa)) return;
    auto add = [&](double xv) {
        const double tv = (xv - x0) / dx;
        if (tv > 0.0 && tv < 1.0) t[n++] = tv;
    };
    for (int e = 0; e < fm.mips; ++e) {
        const double s = fm.spacing[e];
        const int m0 = int(std::ceil(xa / s - 0.5)), m1 = int(std::floor(xb / s - 0.5));
        for (int m = std::max(m0, -fm.res[e]); m <= std::min(m1, fm.res[e] - 1); ++m) add((m + 0.5) * s);
    }
    if (xa < 0.0 && xb > 0.0) add(0.0);
    add(-kLim);
    add(kLim);
}

// One edge's share of the cell's mass and first moments over a CCW polygon Q, by Green's theorem:
//   mass = ∫∫ p_i p_j = -∮ p_i(x) F_j(y) dx,   ∫∫ x p_i p_j = -∮ x p_i(x) F_j(y) dx,   ∫∫ y p_i p_j = ∮ F_i(x) y p_j(y) dy.
// Between breakpoints of both texel grids the mass integrand is a cubic (Simpson exact); the moments' are quartics
// (Simpson's error on pieces of at most one texel is ~1e-5 relative): they only place the smooth factor (A1).
// kMoments = false: the mass alone (the moments' entries stay 0), half the table reads.
template <bool kMoments>
DVec3 edgeMoments(const FilteredMarginal& X, const FilteredMarginal& Y, DVec2 a, DVec2 b) {
    const double dx = b.x - a.x, dy = b.y - a.y;
    // Nothing to integrate where both |x| >= 4 σ_o (p_i = 0) and |y| >= 4 σ_o (p_j = 0).
    auto inside = [&](double lim, double p0, double dp, double& t0, double& t1) {
        if (dp == 0.0) {
            t0 = 0.0, t1 = std::abs(p0) < lim ? 1.0 : 0.0;
            return;
        }
        t0 = (-lim - p0) / dp, t1 = (lim - p0) / dp;
        if (t0 > t1) std::swap(t0, t1);
        t0 = std::max(t0, 0.0), t1 = std::min(t1, 1.0);
    };
    double tx0, tx1, ty0, ty1;
    inside(kLim, a.x, dx, tx0, tx1);
    inside(kLim, a.y, dy, ty0, ty1);
    const bool useX = dx != 0.0 && tx1 > tx0, useY = kMoments && dy != 0.0 && ty1 > ty0;
    if (!useX && !useY) return DVec3(0.0);
    const double t0 = useX && useY ? std::min(tx0, ty0) : (useX ? tx0 : ty0);
    const double t1 = useX && useY ? std::max(tx1, ty1) : (useX ? tx1 : ty1);
    double t[4 * (kRes + kRes / 2) + 16];
    int n = 0;
    gridCrossings(X, a.x, dx, t, n);
    gridCrossings(Y, a.y, dy, t, n);
    int kept = 0;
    for (int s = 0; s < n; ++s)
        if (t[s] > t0 && t[s] < t1) t[kept++] = t[s];
    t[kept++] = t0;
    t[kept++] = t1;
    std::sort(t, t + kept);
    // Integrands at parameter tv: (p_i F_j, x p_i F_j, F_i y p_j); the pieces of one edge share their end values.
    auto phi = [&](double tv) {
        const double x = a.x + tv * dx, y = a.y + tv * dy;
        DVec3 v(0.0);
        if (useX && std::abs(x) <= kLim) {
            const double f = X.value(x) * Y.cdf(y);
            v.x = f;
            if constexpr (kMoments) v.y = x * f;
        }
        if (kMoments && useY && std::abs(y) <= kLim) v.z = X.cdf(x) * y * Y.value(y);
        return v;
    };
    DVec3 sum(0.0), fa = phi(t[0]);
    for (int s = 0; s + 1 < kept; ++s) {
        if (!(t[s + 1] > t[s])) continue;
        const DVec3 fb = phi(t[s + 1]);
        sum += (t[s + 1] - t[s]) * (fa + 4.0 * phi(0.5 * (t[s] + t[s + 1])) + fb);
        fa = fb;
    }
    return DVec3(-dx * sum.x, -dx * sum.y, dy * sum.z) / 6.0;
}

template <bool kMoments>
DVec3 polygonMoments(const FilteredMarginal& X, const FilteredMarginal& Y, const DVec2* q, int n) {
    DVec3 sum(0.0);
    for (int e = 0; e < n; ++e) sum += edgeMoments<kMoments>(X, Y, q[e], q[(e + 1) % n]);
    return sum;
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


DVec3 cellPolygonMoments(const Dictionary& dict, int k, int i, int j, const DVec2* q, int n, MipBlend bx, MipBlend by) {
    return polygonMoments<true>(FilteredMarginal(dict, k, i, bx), FilteredMarginal(dict, k, j, by), q, n);
}

double cellPolygonMass(const Dictionary& dict, int k, int i, int j, const DVec2* q, int n, MipBlend bx, MipBlend by) {
    return polygonMoments<false>(FilteredMarginal(dict, k, i, bx), FilteredMarginal(dict, k, j, by), q, n).x;
}

DVec3 gaussianPolygonMoments(const DVec2* q, int n) {
    // The moments of edgeMoments with p = N(0, σ_o²) and F(y) = erf(y / (σ_o √2)) / 2, on each edge's part with
    // |x| < 8 σ_o or |y| < 8 σ_o (beyond it p is below 1e-13 of its peak and the integrand is exactly 0), Simpson on
    // steps of at most σ_o / 8 (relative error ~1e-6). Only that part is stepped: an edge of a flake's region
    // (glint_flakes.h) can be hundreds of σ_o long in m', of which at most two slabs 16 σ_o wide contribute.
    const double so = kSigmaO, lim = 8.0 * so, h = so / 8.0;
    const double norm = 1.0 / (so * std::sqrt(2.0 * kPiD)), ir = 1.0 / (so * std::sqrt(2.0));
    auto pdf = [&](double x) { return norm * std::exp(-0.5 * x * x / (so * so)); };
    auto cdf = [&](double x) { return 0.5 * std::erf(x * ir); };
    DVec3 total(0.0);
    for (int e = 0; e < n; ++e) {
        const DVec2 a = q[e], b = q[(e + 1) % n];
        const DVec2 d = b - a;
        const double len = std::max(std::abs(d.x), std::abs(d.y));
        if (len == 0.0) continue;
        auto phi = [&](double tv) {
            const double x = a.x + tv * d.x, y = a.y + tv * d.y;
            DVec3 v(0.0);
            if (std::abs(x) < lim) {
                const double f = pdf(x) * cdf(y);
                v.x = f, v.y = x * f;
            }
            if (std::abs(y) < lim) v.z = cdf(x) * y * pdf(y);
            return v;
        };
        // The parameter interval of the slab |c0 + t dc| < lim within [0, 1] (empty: lo >= hi).
        auto slab = [&](double c0, double dc, double& lo, double& hi) {
            if (dc == 0.0) {
                lo = 0.0, hi = std::abs(c0) < lim ? 1.0 : 0.0;
                return;
            }
            const double t0 = (-lim - c0) / dc, t1 = (lim - c0) / dc;
            lo = std::max(std::min(t0, t1), 0.0), hi = std::min(std::max(t0, t1), 1.0);
        };
        double xl, xh, yl, yh;
        slab(a.x, d.x, xl, xh);
        slab(a.y, d.y, yl, yh);
        double spans[2][2];
        int count = 0;
        if (xl < xh) spans[count][0] = xl, spans[count++][1] = xh;
        if (yl < yh) {
            if (count == 1 && yl <= spans[0][1] && xl <= yh) {  // overlapping: one span
                spans[0][0] = std::min(spans[0][0], yl), spans[0][1] = std::max(spans[0][1], yh);
            } else {
                spans[count][0] = yl, spans[count++][1] = yh;
            }
        }
        DVec3 sum(0.0);
        for (int k = 0; k < count; ++k) {
            const double t0 = spans[k][0], width = spans[k][1] - spans[k][0];
            const int steps = std::clamp(int(std::ceil(width * len / h)), 1, 4096);
            const double dt = width / steps;
            DVec3 part(0.0), fa = phi(t0);
            for (int s = 0; s < steps; ++s) {
                const double ta = t0 + s * dt;
                const DVec3 fb = phi(ta + dt);
                part += fa + 4.0 * phi(ta + 0.5 * dt) + fb;
                fa = fb;
            }
            sum += part * (dt / 6.0);
        }
        total += DVec3(-d.x * sum.x, -d.x * sum.y, d.y * sum.z);
    }
    return total;
}

double gaussianPolygonMass(const DVec2* q, int n) { return gaussianPolygonMoments(q, n).x; }

namespace {

// Adaptive chords of one spherical edge a -> b (unit vectors) mapped to half slopes: the arc's midpoint is split
// off while its image lies farther than the tolerance from the chord, measured in M^-1 space (where the cell
// distributions live, lobes σ_l = 0.02 wide). Appends the edge's start and its inner vertices, in order.
struct RegionBuilder {
    DVec3 o;
    const GlintShape* shape;
    double tolerance;
    int maxDepth;
    DVec2* out;
    int n = 0;
    DVec2 map(const DVec3& wi) const {
        const DVec3 h = glm::normalize(o + wi);  // h.z > 0: wo.z > 0 and wi.z >= 0
        return DVec2(-h.x / h.z, -h.y / h.z);
    }
    DVec2 toM(DVec2 hs) const { return DVec2(shape->mi00 * hs.x + shape->mi01 * hs.y, shape->mi11 * hs.y); }
    void edge(const DVec3& a, DVec2 ha, const DVec3& b, DVec2 hb, int depth) {
        // Points of the great-circle arc (the edge of the spherical polygon) by normalised linear interpolation.
        const DVec3 m = glm::normalize(a + b);
        const DVec2 hm = map(m);
        const DVec2 pa = toM(ha), pb = toM(hb), pm = toM(hm), d = pb - pa;
        const double len2 = glm::dot(d, d);
        const double tt = len2 > 0.0 ? std::clamp(glm::dot(pm - pa, d) / len2, 0.0, 1.0) : 0.0;
        const DVec2 off = pm - (pa + tt * d);
        if (depth < maxDepth && glm::dot(off, off) > tolerance * tolerance) {
            edge(a, ha, m, hm, depth + 1);
            edge(m, hm, b, hb, depth + 1);
            return;
        }
        out[n++] = ha;
    }
};

}  // namespace

int halfSlopeRegion(const Vec3& wo, const Vec3* vertices, int count, const GlintShape& shape,
                    const GlintAreaSettings& settings, DVec2* out) {
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
    RegionBuilder rb{glm::normalize(DVec3(wo)), &shape, std::max(double(settings.chordTolerance), 1e-7),
                     std::clamp(settings.maxDepth, 1, kMaxChordDepth), out};  // <= 5 edges x 2^depth vertices
    // Each edge at least 4 chords deep is not needed: the midpoint test starts on the whole edge, but an S-shaped
    // image could hide behind a straight midpoint, so the first split is unconditional for long edges (> 0.1 rad).
    for (int e = 0; e < m; ++e) {
        const DVec3 a = c[e], b = c[(e + 1) % m];
        if (glm::dot(a, b) < std::cos(0.1)) {
            const DVec3 mid = glm::normalize(a + b);
            rb.edge(a, rb.map(a), mid, rb.map(mid), 1);
            rb.edge(mid, rb.map(mid), b, rb.map(b), 1);
        } else {
            rb.edge(a, rb.map(a), b, rb.map(b), 0);
        }
    }
    int n = rb.n;
    // Orientation: the map may mirror the plane (h~ = -h_xy/h_z); make the region counter-clockwise for (A2).
    double area2 = 0.0;
    for (int i = 0; i < n; ++i) area2 += out[i].x * out[(i + 1) % n].y - out[(i + 1) % n].x * out[i].y;
    if (area2 < 0.0) std::reverse(out, out + n);
    return area2 != 0.0 ? n : 0;
}

namespace {

// The smooth factor of (A1) at direction wi (lobe frame, any length), 0 below the horizon.
double smoothFactorAt(const Vec3& wo, const Vec3& wi) {
    const DVec3 w = glm::normalize(DVec3(wi));
    if (!(w.z > 0.0)) return 0.0;
    const DVec3 h = glm::normalize(DVec3(wo) + w);
    Vec3 hf;
    return smoothFactor(wo, DVec2(-h.x / h.z, -h.y / h.z), hf);
}

// Splits the light polygon (3 or 4 vertices) into pieces over which the smooth factor is close to linear: a piece
// whose corner and centre values of g spread by more than 'tolerance' of their maximum is split into four (quads
// bilinearly, planar for the planar quads of lights; triangles at their edge midpoints), at most maxDepth times.
// The V-cavity G has a kink (min(1, .)) and falls to 0 at the horizon, where the centroid rule alone erred by up to
// 13 % (test_glint_area.cpp).
void splitLight(const Vec3& wo, const Vec3* v, int count, float tolerance, int depth, int maxDepth,
                std::vector<std::array<Vec3, 4>>& pieces, std::vector<int>& counts, std::vector<double>& spreads) {
    double gmin = 1e300, gmax = 0.0;
    Vec3 centre(0.f);
    for (int i = 0; i < count; ++i) {
        const double g = smoothFactorAt(wo, v[i]);
        gmin = std::min(gmin, g), gmax = std::max(gmax, g);
        centre += v[i] / float(count);
    }
    const double gc = smoothFactorAt(wo, centre);
    gmin = std::min(gmin, gc), gmax = std::max(gmax, gc);
    if (depth >= maxDepth || !(gmax - gmin > tolerance * gmax)) {
        std::array<Vec3, 4> piece{};
        for (int i = 0; i < count; ++i) piece[i] = v[i];
        pieces.push_back(piece);
        counts.push_back(count);
        spreads.push_back(gmax > 0.0 ? (gmax - gmin) / gmax : 0.0);
        return;
    }
    if (count == 4) {
        const Vec3 e01 = 0.5f * (v[0] + v[1]), e12 = 0.5f * (v[1] + v[2]), e23 = 0.5f * (v[2] + v[3]),
                   e30 = 0.5f * (v[3] + v[0]), c = 0.25f * (v[0] + v[1] + v[2] + v[3]);
        const Vec3 q[4][4] = {{v[0], e01, c, e30}, {e01, v[1], e12, c}, {c, e12, v[2], e23}, {e30, c, e23, v[3]}};
        for (const auto& sub : q) splitLight(wo, sub, 4, tolerance, depth + 1, maxDepth, pieces, counts, spreads);
    } else {
        const Vec3 e01 = 0.5f * (v[0] + v[1]), e12 = 0.5f * (v[1] + v[2]), e20 = 0.5f * (v[2] + v[0]);
        const Vec3 t[4][3] = {{v[0], e01, e20}, {e01, v[1], e12}, {e20, e12, v[2]}, {e01, e12, e20}};
        for (const auto& sub : t) splitLight(wo, sub, 3, tolerance, depth + 1, maxDepth, pieces, counts, spreads);
    }
}

// One piece of the light in M^-1 space: its vertices (offset into the shared buffer), and whether no cell rotation
// can bring it into the support square |m| < 4 σ_o (it lies beyond the square's circumcircle, radius 4 σ_o √2).
struct Piece {
    int offset = 0, n = 0;
    bool missesAll = false;
    // Smooth factor nearly constant over the piece (spread below GlintAreaSettings::constantFactorSpread): the cells'
    // masses alone, times (g, h~) at the piece's area centroid, instead of each cell's centroid.
    bool constantFactor = false;
    DVec4 factor{0.0};  // (g, h~x, h~y, 1) at the area centroid
};

// One cell's share of the integral, recorded for samplePolygon: its draws, the piece (-1: a converged cell, whose
// Gaussian spans all pieces) and its weight (level weight x EWA weight x mass x smooth factor).
struct CellRecord {
    double weight;
    int piece;
    CellDraw draw;
};

// Per-thread buffers of one query (the integral's, then read by the sampler right after).
struct AreaScratch {
    std::vector<std::array<Vec3, 4>> lightPieces;
    std::vector<int> lightCounts;
    std::vector<double> lightSpreads;
    std::vector<DVec2> mAll, rotated;
    std::vector<Piece> pieces;
    std::vector<CellRecord> records;
    // The query these buffers belong to: the integrator asks samplePolygon right after integratePolygon for the same
    // shading point and light, so the sampler reuses the recorded cells instead of recomputing the integral.
    std::array<float, 32> key{};
    bool valid = false;
};
thread_local AreaScratch scratch;

std::array<float, 32> queryKey(const GlintParams& p, const GlintEvalInputs& in, const Vec3& wo, const Vec3* v, int count,
                               const GlintAreaSettings& settings) {
    std::array<float, 32> k{};
    int n = 0;
    for (float x : {wo.x, wo.y, wo.z, in.uv.x, in.uv.y, in.duvdx.x, in.duvdx.y, in.duvdy.x, in.duvdy.y, p.sigmaX,
                    p.sigmaY, p.rho, p.logDensity, p.relArea, float(count), settings.chordTolerance})
        k[n++] = x;
    for (int i = 0; i < count; ++i) k[n++] = v[i].x, k[n++] = v[i].y, k[n++] = v[i].z;
    return k;  // GGAA differentials are not in the key: equal for one shading point
}

bool integrateImpl(const Dictionary& dict, const GlintParams& p, const GlintShape& shape, const GlintEvalInputs& in,
                   const Vec3& wo, const Vec3* vertices, int count, GlintAreaResult& out,
                   const GlintAreaSettings& settings, bool record) {
    out = GlintAreaResult{};
    if (count < 3 || count > 4 || wo.z <= 0.f) return false;
    auto& lightPieces = scratch.lightPieces;
    auto& lightCounts = scratch.lightCounts;
    auto& lightSpreads = scratch.lightSpreads;
    auto& mAll = scratch.mAll;
    auto& rotated = scratch.rotated;
    auto& records = scratch.records;
    records.clear();
    scratch.valid = false;
    lightPieces.clear(), lightCounts.clear(), lightSpreads.clear(), mAll.clear();
    splitLight(wo, vertices, count, settings.splitTolerance, 0, std::clamp(settings.maxSplitDepth, 0, 3), lightPieces,
               lightCounts, lightSpreads);
    auto& pieces = scratch.pieces;  // small: at most 4^maxSplitDepth
    pieces.clear();
    DVec2 region[kMaxRegionVertices];
    const double mi00 = shape.mi00, mi01 = shape.mi01, mi11 = shape.mi11;
    DVec2 fallbackCentroid(0.0);
    for (size_t k = 0; k < lightPieces.size(); ++k) {
        const int n = halfSlopeRegion(wo, lightPieces[k].data(), lightCounts[k], shape, settings, region);
        if (n < 3) continue;
        Piece pc;
        pc.offset = int(mAll.size()), pc.n = n;
        bool containsOrigin = false;  // crossing-number test (R may be slightly non-convex: chords of curves)
        double minDist2 = 1e300;
        for (int e = 0; e < n; ++e) mAll.push_back(DVec2(mi00 * region[e].x + mi01 * region[e].y, mi11 * region[e].y));
        const DVec2* mr = mAll.data() + pc.offset;
        for (int e = 0; e < n; ++e) {
            const DVec2 a = mr[e], b = mr[(e + 1) % n], d = b - a;
            if ((a.y > 0.0) != (b.y > 0.0) && a.x - a.y * d.x / d.y > 0.0) containsOrigin = !containsOrigin;
            const double len2 = glm::dot(d, d);
            const double tt = len2 > 0.0 ? std::clamp(-glm::dot(a, d) / len2, 0.0, 1.0) : 0.0;
            const DVec2 c = a + tt * d;
            minDist2 = std::min(minDist2, glm::dot(c, c));
        }
        pc.missesAll = !containsOrigin && minDist2 >= 2.0 * kLim * kLim;
        fallbackCentroid = region[0];
        if (lightSpreads[k] < settings.constantFactorSpread) {
            double A = 0.0, cx = 0.0, cy = 0.0;  // area centroid of the piece's region
            for (int e = 0; e < n; ++e) {
                const DVec2 a = region[e], b = region[(e + 1) % n];
                const double cr = a.x * b.y - b.x * a.y;
                A += cr, cx += (a.x + b.x) * cr, cy += (a.y + b.y) * cr;
            }
            if (A > 0.0) {
                const DVec2 hs(cx / (3.0 * A), cy / (3.0 * A));
                Vec3 h;
                pc.constantFactor = true;
                pc.factor = DVec4(smoothFactor(wo, hs, h), hs.x, hs.y, 1.0);
            }
        }
        pieces.push_back(pc);
    }
    if (pieces.empty()) return false;
    out.hCentroid = Vec3(glm::normalize(DVec3(-fallbackCentroid.x, -fallbackCentroid.y, 1.0)));

    // The smooth factor g of (A1) is evaluated at each cell's mass centroid inside each piece (its first moments,
    // mapped back from m-space by M = (M^-1)^-1): exact for g linear over the cell's mass in the piece. Accumulated:
    // Σ mass g and Σ mass h~ (the mass-weighted centroid, where the caller evaluates F).
    const double m00 = 1.0 / mi00, m01 = -mi01 / (mi00 * mi11), m11 = 1.0 / mi11;
    // (mass g, mass h~x, mass h~y, mass) of one cell from its moments in its rotated m-space (rotation θ).
    auto weighted = [&](const DVec3& moments, double c, double sn) {
        if (!(moments.x > 0.0)) return DVec4(0.0);
        const DVec2 mc(moments.y / moments.x, moments.z / moments.x);  // centroid in the cell's rotated m-space
        const DVec2 mu(c * mc.x - sn * mc.y, sn * mc.x + c * mc.y);    // Rot(θ): back to M^-1 space
        const DVec2 hs(m00 * mu.x + m01 * mu.y, m11 * mu.y);
        Vec3 h;
        return moments.x * DVec4(smoothFactor(wo, hs, h), hs.x, hs.y, 1.0);
    };
    bool convergedDone = false;  // the Beckmann cell, computed on first use (shared by all converged cells)
    DVec4 converged(0.0);
    auto beckmann = [&]() {
        if (!convergedDone)  // isotropic: the same for any θ
            for (const Piece& pc : pieces) converged += weighted(gaussianPolygonMoments(mAll.data() + pc.offset, pc.n), 1.0, 0.0);
        convergedDone = true;
        return converged;
    };
    auto finish = [&](const DVec4& acc) {
        out.integral = float(std::max(acc.x, 0.0));
        if (acc.w > 0.0) out.hCentroid = Vec3(glm::normalize(DVec3(-acc.y / acc.w, -acc.z / acc.w, 1.0)));
    };
    const Footprint fp = footprint(in.duvdx, in.duvdy, p.maxAniso);
    if (!fp.valid) {  // no footprint: the point evaluation reads P_B
        finish(beckmann());
        if (record) records.push_back({beckmann().x, -1, CellDraw{}});
        if (record) scratch.key = queryKey(p, in, wo, vertices, count, settings), scratch.valid = true;
        return true;
    }
    // The point evaluation's per-query constants (drawCell's) and, with GGAA (C21 §4.2), its kernel gradients: taken
    // for the light's centre direction (the pixel's change of h varies little over a light), they select the MIPs
    // each cell's marginals are integrated at, as textureGrad1D does for one direction.
    Vec3 wc(0.f);
    for (int i = 0; i < count; ++i) wc += glm::normalize(vertices[i]);
    wc = glm::normalize(Vec3(wc.x, wc.y, std::max(wc.z, 1e-3f * glm::length(wc))));
    const Vec3 hsum = wo + wc;
    const float hlen = glm::length(hsum);
    const Vec3 hc = hsum / hlen;
    Vec2 ddx(0.f), ddy(0.f);
    if (p.ggaa) {
        ddx = ggaaDerivative(in.diff, 0, p.mode, wo, wc, hc, hlen, std::numeric_limits<float>::infinity());
        ddy = ggaaDerivative(in.diff, 1, p.mode, wo, wc, hc, hlen, std::numeric_limits<float>::infinity());
    }
    const SdfQuery q = makeQuery(dict, p, shape, hc, ddx, ddy);

    rotated.resize(kMaxRegionVertices);
    // The EWA average of the cells' integrals at level l: the point evaluation's levelSdf with each SDF value
    // replaced by its integral over R (the weights do not depend on h~, so the average commutes with the integral).
    auto level = [&](int l, double levelWeight) {
        double sumW = 0.0;
        DVec4 acc(0.0);
        const size_t firstRecord = records.size();
        out.cells += forEachCell(l, in.uv, fp.a1, fp.a2, [&](int s, int t, float W) {
            sumW += W;
            const CellDraw d = drawCell(q, l, s, t);
            if (d.empty) return;
            if (d.converged) {
                acc += double(W) * beckmann();
                if (record) records.push_back({double(W) * beckmann().x, -1, d});
                return;
            }
            // Rot(-θ): m = (c x + s y, -s x + c y), as cellSdf.
            const double c = d.cosT, sn = d.sinT;
            MipBlend bx, by;  // GGAA: the MIPs of cellSdf's textureGrad1D calls (kernel gradients rotated by -θ)
            if (q.ggaa) {
                const float cf = d.cosT, sf = d.sinT;
                bx = textureGradLod(cf * q.gx.x + sf * q.gx.y, cf * q.gy.x + sf * q.gy.y);
                by = textureGradLod(-sf * q.gx.x + cf * q.gx.y, -sf * q.gy.x + cf * q.gy.y);
            }
            const FilteredMarginal X(dict, d.k, d.i, bx), Y(dict, d.k, d.j, by);
            for (const Piece& pc : pieces) {
                if (pc.missesAll) continue;
                const DVec2* mr = mAll.data() + pc.offset;
                double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
                for (int e = 0; e < pc.n; ++e) {
                    rotated[e] = DVec2(c * mr[e].x + sn * mr[e].y, -sn * mr[e].x + c * mr[e].y);
                    x0 = std::min(x0, rotated[e].x), x1 = std::max(x1, rotated[e].x);
                    y0 = std::min(y0, rotated[e].y), y1 = std::max(y1, rotated[e].y);
                }
                if (x0 >= kLim || x1 <= -kLim || y0 >= kLim || y1 <= -kLim) continue;  // outside the support square
                // The mass over the piece is at most that over its bounding box, the product of two CDF differences;
                // sparse marginals (few lobes at low k) leave most boxes empty: skip those (bound below 1e-12).
                if (!((X.cdf(x1) - X.cdf(x0)) * (Y.cdf(y1) - Y.cdf(y0)) > 1e-12)) continue;
                const DVec4 cell =
                    pc.constantFactor
                        ? double(W) * std::max(polygonMoments<false>(X, Y, rotated.data(), pc.n).x, 0.0) * pc.factor
                        : double(W) * weighted(polygonMoments<true>(X, Y, rotated.data(), pc.n), c, sn);
                acc += cell;
                if (record && cell.x > 0.0) records.push_back({cell.x, int(&pc - pieces.data()), d});
            }
        });
        for (size_t r = firstRecord; r < records.size(); ++r) records[r].weight *= sumW > 0.0 ? levelWeight / sumW : 0.0;
        return sumW > 0.0 ? acc / sumW : DVec4(0.0);
    };
    // The LOD blend of patchSdf (C20 Eq. 3).
    const float i0f = std::floor(fp.lodP);
    const int l0 = int(i0f);
    const double w = fp.lodP - i0f;
    DVec4 r = level(l0, 1.0 - w);
    if (w > 0.0) r = (1.0 - w) * r + w * level(std::min(l0 + 1, kLevels - 1), w);
    finish(r);
    if (record) scratch.key = queryKey(p, in, wo, vertices, count, settings), scratch.valid = true;
    return true;
}

}  // namespace

bool glintPolygonIntegral(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                          const GlintEvalInputs& in, const Vec3& wo, const Vec3* vertices, int count,
                          GlintAreaResult& out, const GlintAreaSettings& settings) {
    return integrateImpl(dict, p, shape, in, wo, vertices, count, out, settings, true);
}

bool glintSamplePolygon(const Vec3* vertices, int count, const Vec2& u, uint64_t seed, Vec3& wi) {
    return ltc::samplePolygon(ltc::Ltc{}, vertices, count, u, seed, wi);
}

namespace {

inline uint64_t splitMix(uint64_t& state) {
    uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}
inline double unit(uint64_t bits) { return double(bits >> 11) * 0x1.0p-53; }

bool insidePolygon(const DVec2* q, int n, DVec2 pt) {  // crossing number (R may be slightly non-convex)
    bool in = false;
    for (int e = 0; e < n; ++e) {
        const DVec2 a = q[e], b = q[(e + 1) % n];
        if ((a.y > pt.y) != (b.y > pt.y) && pt.x < a.x + (pt.y - a.y) * (b.x - a.x) / (b.y - a.y)) in = !in;
    }
    return in;
}

// N(0, σ_o²) restricted to [lo, hi], by inversion of its CDF erf(x / (σ_o √2)) / 2 at v in [0, 1) (erfinvF).
double truncatedGaussianInverse(double lo, double hi, double v) {
    const double ir = 1.0 / (kSigmaO * std::sqrt(2.0));
    const double fl = 0.5 * std::erf(lo * ir), fh = 0.5 * std::erf(hi * ir);
    const double t = std::clamp(2.0 * (fl + v * (fh - fl)), -0.9999999, 0.9999999);
    return double(erfinvF(float(t))) / ir;
}

// The direction wo reflects to about the half vector of half slope hs; false below the horizon.
bool reflectAboutHalfSlope(const Vec3& wo, DVec2 hs, Vec3& wi) {
    const DVec3 h = glm::normalize(DVec3(-hs.x, -hs.y, 1.0));
    const DVec3 o(wo);
    const DVec3 w = 2.0 * glm::dot(o, h) * h - o;
    if (!(w.z > 0.0)) return false;
    wi = Vec3(glm::normalize(w));
    return true;
}

}  // namespace

bool glintSamplePolygonByCells(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                               const GlintEvalInputs& in, const Vec3& wo, const Vec3* vertices, int count,
                               const Vec2& u, uint64_t seed, Vec3& wi, const GlintAreaSettings& settings) {
    GlintAreaResult r;
    const bool cached = scratch.valid && scratch.key == queryKey(p, in, wo, vertices, count, settings);
    if (!cached && !integrateImpl(dict, p, shape, in, wo, vertices, count, r, settings, true)) return false;
    const auto& records = scratch.records;
    const auto& pieces = scratch.pieces;
    double total = 0.0;
    for (const CellRecord& c : records) total += c.weight;
    if (!(total > 0.0) || pieces.empty()) return glintSamplePolygon(vertices, count, u, seed, wi);
    // The cell, by inversion of the cumulative weights with u.x; u.x is then rescaled to [0, 1) for reuse.
    double target = double(u.x) * total, acc = 0.0, ux = u.x;
    size_t pick = records.size() - 1;
    for (size_t c = 0; c < records.size(); ++c) {
        if (target < acc + records[c].weight) {
            pick = c;
            ux = std::clamp((target - acc) / records[c].weight, 0.0, 1.0 - 1e-12);
            break;
        }
        acc += records[c].weight;
    }
    const CellRecord& rec = records[pick];
    const double m00 = 1.0 / shape.mi00, m01 = -shape.mi01 / (shape.mi00 * shape.mi11), m11 = 1.0 / shape.mi11;
    uint64_t state = seed ^ 0xA5A5F00DULL;
    // A point of the cell's distribution restricted to its piece: each coordinate by inversion of its marginal's CDF
    // over the piece's bounding box (MIP 0; the GGAA MIPs only blur it), kept if inside the piece (rejection).
    for (int attempt = 0; attempt < 32; ++attempt) {
        const double a = attempt == 0 ? ux : unit(splitMix(state));
        const double b = attempt == 0 ? double(u.y) : unit(splitMix(state));
        int pieceIndex = rec.piece;
        double c = 1.0, sn = 0.0;
        if (rec.piece < 0) {  // converged: the Gaussian is isotropic; choose a piece by the next uniform
            pieceIndex = int(std::min(unit(splitMix(state)) * pieces.size(), double(pieces.size() - 1)));
        } else {
            c = rec.draw.cosT, sn = rec.draw.sinT;
        }
        const Piece& pc = pieces[pieceIndex];
        if (pc.missesAll && rec.piece >= 0) break;
        const DVec2* mr = scratch.mAll.data() + pc.offset;
        auto& rot = scratch.rotated;
        double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
        for (int e = 0; e < pc.n; ++e) {
            rot[e] = DVec2(c * mr[e].x + sn * mr[e].y, -sn * mr[e].x + c * mr[e].y);
            x0 = std::min(x0, rot[e].x), x1 = std::max(x1, rot[e].x);
            y0 = std::min(y0, rot[e].y), y1 = std::max(y1, rot[e].y);
        }
        DVec2 m;
        if (rec.piece < 0) {  // N(0, σ_o²) per axis restricted to the box
            m = DVec2(truncatedGaussianInverse(x0, x1, a), truncatedGaussianInverse(y0, y1, b));
        } else {
            const CellDraw& d = rec.draw;
            auto inv = [&](int marginal, double lo, double hi, double v) {
                lo = std::max(lo, -kLim), hi = std::min(hi, kLim);
                const double fl = dict.marginalCdf(d.k, marginal, float(lo)), fh = dict.marginalCdf(d.k, marginal, float(hi));
                const double t = fl + v * (fh - fl);
                return (t < 0.0 ? -1.0 : 1.0) * double(dict.sampleMarginal(d.k, marginal, float(2.0 * std::abs(t))));
            };
            m = DVec2(inv(d.i, x0, x1, a), inv(d.j, y0, y1, b));
        }
        if (!insidePolygon(rot.data(), pc.n, m)) continue;
        const DVec2 mu(c * m.x - sn * m.y, sn * m.x + c * m.y);  // Rot(θ): back to M^-1 space
        if (reflectAboutHalfSlope(wo, DVec2(m00 * mu.x + m01 * mu.y, m11 * mu.y), wi)) return true;
    }
    return glintSamplePolygon(vertices, count, u, seed, wi);  // no try landed inside: the cosine-weighted fallback
}

// ---- explicit flakes under quad lights -------------------------------------------------------------------------

namespace {

// The light's pieces and their half-slope regions (h~), shared by every flake of the footprint, and the masses of the
// last flake set's flakes per piece (for the sampler).
struct FlakeRegions {
    std::vector<std::array<Vec3, 4>> lightPieces;
    std::vector<int> lightCounts;
    std::vector<double> lightSpreads;
    std::vector<DVec2> h;      // every piece's region in h~, one after the other
    std::vector<int> offsets;  // piece k: h[offsets[k] .. offsets[k + 1])
    std::vector<DVec2> m;      // one piece mapped to a flake's m'
};
thread_local FlakeRegions flakeScratch;

// Builds flakeScratch's regions; returns the number of visible pieces.
int flakeRegions(float sigmaF, const Vec3& wo, const Vec3* vertices, int count, const GlintAreaSettings& settings) {
    FlakeRegions& r = flakeScratch;
    r.lightPieces.clear(), r.lightCounts.clear(), r.lightSpreads.clear(), r.h.clear(), r.offsets.assign(1, 0);
    if (count < 3 || count > 4 || wo.z <= 0.f || !(sigmaF > 0.f)) return 0;
    splitLight(wo, vertices, count, settings.splitTolerance, 0, std::clamp(settings.maxSplitDepth, 0, 3), r.lightPieces,
               r.lightCounts, r.lightSpreads);
    // The chords' tolerance is measured in the flakes' own space (scale σ_o / σ_f: GlintShape's M^-1 of an isotropic
    // lobe of RMS slope σ_f; make() keeps σ >= 0.01, a finer tolerance below that).
    // The tolerance is the cells' relative to their lobes' width σ_l, here relative to the flake's σ_o in m'.
    const GlintShape flakeShape = GlintShape::make(sigmaF, sigmaF, 0.f);
    GlintAreaSettings chords = settings;
    chords.chordTolerance = settings.chordTolerance * float(kSigmaO / kSigmaL);
    DVec2 region[kMaxRegionVertices];
    for (size_t k = 0; k < r.lightPieces.size(); ++k) {
        const int n = halfSlopeRegion(wo, r.lightPieces[k].data(), r.lightCounts[k], flakeShape, chords, region);
        if (n < 3) continue;
        r.h.insert(r.h.end(), region, region + n);
        r.offsets.push_back(int(r.h.size()));
    }
    return int(r.offsets.size()) - 1;
}

// Piece k of the regions in flake m's space m' = (h~ - m) σ_o / σ_f (into flakeScratch.m).
const DVec2* pieceInFlakeSpace(int k, Vec2 slope, float sigmaF, int& n) {
    FlakeRegions& r = flakeScratch;
    const double scale = kSigmaO / double(sigmaF);
    n = r.offsets[k + 1] - r.offsets[k];
    r.m.resize(size_t(n));
    for (int e = 0; e < n; ++e) r.m[size_t(e)] = (r.h[size_t(r.offsets[k] + e)] - DVec2(slope)) * scale;
    return r.m.data();
}

// The moments of N(0, σ_o² I) over one piece in m' (gaussianPolygonMoments), with two exact-to-1e-9 shortcuts for the
// usual case of a flake far narrower than the light: a piece whose boundary is more than 6.5 σ_o from the origin
// holds all of the mass (moments (1, 0, 0)) or none of it, without the edge integrals.
DVec3 flakePieceMoments(const DVec2* q, int n) {
    double minDist2 = 1e300;
    for (int e = 0; e < n; ++e) {
        const DVec2 a = q[e], d = q[(e + 1) % n] - a;
        const double len2 = glm::dot(d, d);
        const double t = len2 > 0.0 ? std::clamp(-glm::dot(a, d) / len2, 0.0, 1.0) : 0.0;
        const DVec2 c = a + t * d;
        minDist2 = std::min(minDist2, glm::dot(c, c));
    }
    const double far = 6.5 * kSigmaO;  // the mass beyond 6.5 σ_o of an isotropic 2D Gaussian: exp(-6.5^2 / 2) = 6e-10
    if (minDist2 > far * far) return insidePolygon(q, n, DVec2(0.0)) ? DVec3(1.0, 0.0, 0.0) : DVec3(0.0);
    return gaussianPolygonMoments(q, n);
}

// One flake's (A1) integral without F over the pieces, and its mass-weighted centroid sum (h~).
double flakeIntegral(const Flake& flake, float sigmaF, const Vec3& wo, int pieces, DVec2& centroidSum, double& mass) {
    const double back = double(sigmaF) / kSigmaO;  // m' -> h~ - m
    double integral = 0.0;
    for (int k = 0; k < pieces; ++k) {
        int n;
        const DVec2* q = pieceInFlakeSpace(k, flake.slope, sigmaF, n);
        const DVec3 mo = flakePieceMoments(q, n);
        if (!(mo.x > 0.0)) continue;
        const DVec2 hs = DVec2(flake.slope) + DVec2(mo.y / mo.x, mo.z / mo.x) * back;
        Vec3 h;
        integral += mo.x * smoothFactor(wo, hs, h);
        centroidSum += mo.x * hs, mass += mo.x;
    }
    return integral;
}

}  // namespace

bool flakePolygonIntegral(const FlakeSet& flakes, float sigmaF, const Vec3& wo, const Vec3* vertices, int count,
                          GlintAreaResult& out, const GlintAreaSettings& settings) {
    out = GlintAreaResult{};
    const int pieces = flakeRegions(sigmaF, wo, vertices, count, settings);
    if (pieces == 0) return false;
    double integral = 0.0, mass = 0.0;
    DVec2 centroid(0.0);
    for (int f = 0; f < flakes.count; ++f) {
        DVec2 c(0.0);
        double m = 0.0;
        integral += double(flakes.weight[f]) * flakeIntegral(flakes.flakes[f], sigmaF, wo, pieces, c, m);
        centroid += double(flakes.weight[f]) * c, mass += double(flakes.weight[f]) * m;
    }
    out.integral = float(std::max(integral, 0.0));
    out.cells = flakes.count;
    if (mass > 0.0) out.hCentroid = Vec3(glm::normalize(DVec3(-centroid.x / mass, -centroid.y / mass, 1.0)));
    else out.hCentroid = Vec3(glm::normalize(DVec3(-flakeScratch.h[0].x, -flakeScratch.h[0].y, 1.0)));
    return true;
}

bool flakeSamplePolygon(const FlakeSet& flakes, float sigmaF, const Vec3& wo, const Vec3* vertices, int count,
                        const Vec2& u, uint64_t seed, Vec3& wi, const GlintAreaSettings& settings) {
    const int pieces = flakeRegions(sigmaF, wo, vertices, count, settings);
    if (pieces == 0) return false;
    // The flake and the piece by inversion of their cumulative masses (flake weight x its mass in the piece) with u.x,
    // rescaled to [0, 1) for reuse; then a point of N(0, σ_o²) per axis restricted to the piece's bounding box in m'
    // (CDF erf(x / (σ_o √2)) / 2 inverted with erfinvF), kept if inside the piece.
    constexpr int kMaxPieces = 64;
    const int kept = std::min(pieces, kMaxPieces);
    double masses[FlakeSet::kMaxFlakes * kMaxPieces], total = 0.0;
    for (int f = 0; f < flakes.count; ++f)
        for (int k = 0; k < kept; ++k) {
            int n;
            const DVec2* q = pieceInFlakeSpace(k, flakes.flakes[f].slope, sigmaF, n);
            const double mk = double(flakes.weight[f]) * std::max(flakePieceMoments(q, n).x, 0.0);
            masses[f * kept + k] = mk;
            total += mk;
        }
    if (!(total > 0.0)) return glintSamplePolygon(vertices, count, u, seed, wi);
    double target = double(u.x) * total, acc = 0.0, ux = u.x;
    int pick = flakes.count * kept - 1;
    for (int c = 0; c < flakes.count * kept; ++c) {
        if (target < acc + masses[c]) {
            pick = c;
            ux = std::clamp((target - acc) / masses[c], 0.0, 1.0 - 1e-12);
            break;
        }
        acc += masses[c];
    }
    const Flake& flake = flakes.flakes[pick / kept];
    int n;
    const DVec2* q = pieceInFlakeSpace(pick % kept, flake.slope, sigmaF, n);
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (int e = 0; e < n; ++e) {
        x0 = std::min(x0, q[e].x), x1 = std::max(x1, q[e].x);
        y0 = std::min(y0, q[e].y), y1 = std::max(y1, q[e].y);
    }
    const double back = double(sigmaF) / kSigmaO;
    uint64_t state = seed ^ 0x5EEDF1A4EULL;
    for (int attempt = 0; attempt < 32; ++attempt) {
        const double a = attempt == 0 ? ux : unit(splitMix(state));
        const double b = attempt == 0 ? double(u.y) : unit(splitMix(state));
        const DVec2 m(truncatedGaussianInverse(x0, x1, a), truncatedGaussianInverse(y0, y1, b));
        if (!insidePolygon(q, n, m)) continue;
        if (reflectAboutHalfSlope(wo, DVec2(flake.slope) + m * back, wi)) return true;
    }
    return glintSamplePolygon(vertices, count, u, seed, wi);
}

// ---- GlintLobe's polygon entries (declared in glint_bsdf.h) ----------------------------------------------------

const GlintPolygonShares& GlintLobe::polygonShares(const Vec3& wo, const Vec3* vertices, int count) const {
    GlintPolygonShares& s = polygonShares_;
    if (s.matches(wo, vertices, count)) return s;
    s = GlintPolygonShares{};
    const float we = flakeWeight_;
    GlintAreaResult r;
    if (we < 1.f && glintPolygonIntegral(dict_, p_, shape_, in_, wo, vertices, count, r)) {
        s.visible = true;
        s.glint = (1.0 - we) * r.integral;
        s.hGlint = r.hCentroid;
    }
    if (we > 0.f && flakes_.count > 0 && flakePolygonIntegral(flakes_, flakeSigma_, wo, vertices, count, r)) {
        s.visible = true;
        s.flake = double(we) * r.integral;
        s.hFlake = r.hCentroid;
    }
    s.valid = count >= 0 && count <= 4;
    s.wo = wo;
    s.count = count;
    for (int k = 0; k < count && k < 4; ++k) s.vertices[k] = vertices[k];
    return s;
}

bool GlintLobe::integratePolygon(const LobeQuery& q, const Vec3* vertices, int count, Color3& result) const {
    if (!p_.integrateQuadLights) return false;  // bsdf.glint quad_lights = "sampled": the integrator samples the light
    result = Color3(0.f);
    const GlintPolygonShares& s = polygonShares(q.wo, vertices, count);
    // F at each part's centroid (A1); invisible lights integrate to 0, as LtcLobe.
    if (s.glint > 0.0) result += fresnel_.eval(glm::dot(q.wo, s.hGlint)) * float(s.glint);
    if (s.flake > 0.0) result += fresnel_.eval(glm::dot(q.wo, s.hFlake)) * float(s.flake);
    return true;
}

bool GlintLobe::samplePolygon(const LobeQuery& q, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                              Vec3& wi) const {
    if (!p_.integrateQuadLights || q.wo.z <= 0.f) return false;
    if (!(flakeWeight_ > 0.f && flakes_.count > 0))  // the counted cells alone, as before the flakes
        return glintSamplePolygonByCells(dict_, p_, shape_, in_, q.wo, vertices, count, u, seed, wi);
    // Flakes and cells: the part by its share of the integral, u.x rescaled for reuse.
    const GlintPolygonShares& s = polygonShares(q.wo, vertices, count);
    const double total = s.glint + s.flake;
    if (!(total > 0.0)) return s.visible && glintSamplePolygon(vertices, count, u, seed, wi);
    const double pFlake = s.flake / total;
    if (double(u.x) < pFlake) {
        const Vec2 uu(float(std::min(double(u.x) / pFlake, 0.99999994)), u.y);
        return flakeSamplePolygon(flakes_, flakeSigma_, q.wo, vertices, count, uu, seed, wi);
    }
    const Vec2 uu(float(std::min((double(u.x) - pFlake) / (1.0 - pFlake), 0.99999994)), u.y);
    return glintSamplePolygonByCells(dict_, p_, shape_, in_, q.wo, vertices, count, uu, seed, wi);
}

}  // namespace specula::glint
