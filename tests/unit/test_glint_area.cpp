// Glints under quad lights (issue 11 item 2, nodes/bsdf/glint/glint_area.h): the per-cell polygon integral against
// Monte Carlo integration of the exact point evaluation, its tiny-light and converged limits, the exactness of the
// per-cell mass (Green's theorem on the dictionary marginals), the Jacobians, and the render-level noise goal.
#include "core/render/renderer.h"
#include "core/scene/scene_loader.h"
#include "nodes/bsdf/glint/glint_area.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

using namespace specula;
using namespace specula::glint;

constexpr double kPiD = 3.14159265358979323846;

namespace {

// A quad light in the lobe frame: centre direction dir at distance dist, side 'size', tilted by 'tilt' radians about
// one of its axes; vertices relative to the shading point, oriented counter-clockwise as seen from it.
struct Quad {
    Vec3 v[4];
    Vec3 centre, e1, e2, normal;  // e1, e2: half sides
};
Quad makeQuad(const Vec3& dir, float dist, float size, float tilt) {
    Quad q;
    q.centre = glm::normalize(dir) * dist;
    const Vec3 n = -glm::normalize(dir);
    const Vec3 a = std::abs(n.z) < 0.9f ? Vec3(0, 0, 1) : Vec3(1, 0, 0);
    Vec3 t = glm::normalize(glm::cross(a, n)), b = glm::cross(n, t);
    const Vec3 tt = std::cos(tilt) * t + std::sin(tilt) * n;  // tilt about b
    q.e1 = 0.5f * size * glm::normalize(tt);
    q.e2 = 0.5f * size * b;
    q.normal = glm::normalize(glm::cross(q.e1, q.e2));
    q.v[0] = q.centre - q.e1 - q.e2, q.v[1] = q.centre + q.e1 - q.e2;
    q.v[2] = q.centre + q.e1 + q.e2, q.v[3] = q.centre - q.e1 + q.e2;
    // Counter-clockwise seen from the origin: the Newell normal points to the origin's side (ltc.cpp facing()).
    Vec3 nrm(0.f);
    for (int i = 0; i < 4; ++i) nrm += glm::cross(q.v[i], q.v[(i + 1) % 4]);
    if (glm::dot(nrm, q.centre) < 0.f) std::swap(q.v[1], q.v[3]);
    return q;
}

// ∫_quad fcos(wi) dω by stratified uniform sampling of the quad's area (pdf_ω = d² / (A |cos_l|)), n x n strata.
template <class F>
double monteCarlo(const Quad& q, int n, uint32_t seed, F&& fcos) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.f, 1.f);
    const float area = 4.f * glm::length(glm::cross(q.e1, q.e2));
    double sum = 0.0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const float s = (a + U(rng)) / n * 2.f - 1.f, t = (b + U(rng)) / n * 2.f - 1.f;
            const Vec3 p = q.centre + s * q.e1 + t * q.e2;
            const float d2 = glm::dot(p, p);
            const Vec3 wi = p / std::sqrt(d2);
            const float cosl = std::abs(glm::dot(wi, q.normal));
            if (wi.z <= 0.f || cosl <= 0.f) continue;
            sum += double(fcos(wi)) * area * cosl / d2;
        }
    return sum / (double(n) * n);
}

// Solid angle of a planar convex polygon (Van Oosterom & Strackee per fan triangle).
double solidAngle(const Vec3* v, int n) {
    double total = 0;
    const DVec3 a = glm::normalize(DVec3(v[0]));
    for (int i = 1; i + 1 < n; ++i) {
        const DVec3 b = glm::normalize(DVec3(v[i])), c = glm::normalize(DVec3(v[i + 1]));
        const double num = glm::dot(a, glm::cross(b, c));
        const double den = 1 + glm::dot(a, b) + glm::dot(b, c) + glm::dot(c, a);
        total += 2 * std::abs(std::atan2(num, den));
    }
    return total;
}

struct Case {
    GlintParams p;
    GlintEvalInputs in;
    Vec3 wo;
    Quad quad;
    const char* size;
};

// Random glint materials, footprints and views, with a light around the mirror direction of a slope drawn from the
// lobe (so most lights catch glints), small (~0.03 rad), medium (~0.2) or large (~0.8) in angle, tilted, at 1-5 units.
// ggaa: GGAA on, with per-pixel frame rotations (t.dN, b.dN) of up to 0.1 (curved surfaces), which select MIPs 1-6.
std::vector<Case> randomCases(int count, uint32_t seed, bool ggaa = false) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.f, 1.f);
    std::normal_distribution<float> N(0.f, 1.f);
    std::vector<Case> cases;
    const char* sizes[3] = {"small", "medium", "large"};
    const float angles[3] = {0.03f, 0.2f, 0.8f};
    while (int(cases.size()) < count) {
        Case c;
        const int kind = int(cases.size()) % 3;
        c.size = sizes[kind];
        c.p.sigmaX = 0.06f + 0.3f * U(rng);
        c.p.sigmaY = 0.06f + 0.3f * U(rng);
        c.p.rho = 0.8f * U(rng) - 0.4f;
        c.p.logDensity = 8.f + 14.f * U(rng);
        c.p.ggaa = ggaa;
        if (ggaa) {
            // Draws sequenced in gcc's former right-to-left argument order (the order of a call's arguments is
            // unspecified: clang's differs, and a test's inputs must not depend on the compiler).
            const float dxY = 0.2f * U(rng) - 0.1f, dxX = 0.2f * U(rng) - 0.1f;
            c.in.diff.dnx = Vec2(dxX, dxY);
            const float dyY = 0.2f * U(rng) - 0.1f, dyX = 0.2f * U(rng) - 0.1f;
            c.in.diff.dny = Vec2(dyX, dyY);
        }
        const float th = 1.2f * U(rng), ph = 2 * kPi * U(rng);
        c.wo = Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
        // Footprint: |duv| from 2e-4 to 2e-2 (LOD ~3 to ~10), anisotropic up to 4:1.
        const float len = 2e-4f * std::pow(100.f, U(rng)), an = 1.f + 3.f * U(rng), rot = kPi * U(rng);
        const float uvY = U(rng), uvX = U(rng);  // (sequenced as above)
        c.in.uv = Vec2(uvX, uvY);
        c.in.duvdx = len * Vec2(std::cos(rot), std::sin(rot));
        c.in.duvdy = len / an * Vec2(-std::sin(rot), std::cos(rot));
        const Vec3 h = glm::normalize(Vec3(-c.p.sigmaX * N(rng), -c.p.sigmaY * N(rng), 1.f));
        const Vec3 wi = 2.f * glm::dot(c.wo, h) * h - c.wo;
        if (wi.z < 0.1f) continue;
        const float dist = 1.f + 4.f * U(rng);
        const float angle = angles[kind] * (0.6f + 0.8f * U(rng));
        c.quad = makeQuad(wi, dist, 2.f * dist * std::tan(0.5f * angle), 0.8f * (U(rng) - 0.5f));
        cases.push_back(c);
    }
    return cases;
}

double pointFCos(const Case& c, const Vec3& wi) {
    const GlintShape shape = GlintShape::make(c.p.sigmaX, c.p.sigmaY, c.p.rho);
    return glintFCosScalar(Dictionary::instance(), c.p, shape, c.in, c.wo, wi);
}

double areaIntegral(const Case& c, const GlintAreaSettings& settings = {}) {
    const GlintShape shape = GlintShape::make(c.p.sigmaX, c.p.sigmaY, c.p.rho);
    GlintAreaResult r;
    glintPolygonIntegral(Dictionary::instance(), c.p, shape, c.in, c.wo, c.quad.v, 4, r, settings);
    return r.integral;
}

}  // namespace

TEST(GlintArea, JacobiansOfTheHalfSlopeMap) {
    // dω_i = 4 (wo·h) dω_h and dω_h = h_z³ dh~: a small square of half slopes maps to a spherical quad of wi whose
    // solid angle is 4 (wo·h) h_z³ times the square's area.
    const Vec3 wo = glm::normalize(Vec3(0.3f, -0.2f, 0.9f));
    for (Vec2 hs : {Vec2(0.f), Vec2(0.2f, -0.1f), Vec2(-0.4f, 0.3f)}) {
        const float e = 1e-3f;
        Vec3 w[4];
        const Vec2 corner[4] = {{-e, -e}, {e, -e}, {e, e}, {-e, e}};
        for (int k = 0; k < 4; ++k) {
            const Vec2 s = hs + corner[k];
            const Vec3 h = glm::normalize(Vec3(-s.x, -s.y, 1.f));
            w[k] = 2.f * glm::dot(wo, h) * h - wo;
        }
        const Vec3 h = glm::normalize(Vec3(-hs.x, -hs.y, 1.f));
        const double predicted = 4.0 * glm::dot(wo, h) * std::pow(h.z, 3.0) * (4.0 * e * e);
        EXPECT_NEAR(solidAngle(w, 4) / predicted, 1.0, 2e-3) << hs.x << " " << hs.y;
    }
}

TEST(GlintArea, CellMassIsExactOverPolygons) {
    // Green's theorem with Simpson between breakpoints (A2) against a fine midpoint rule of p_i(|x|) p_j(|y|) over a
    // triangle and a quad in m-space (partly outside the support square).
    const Dictionary& dict = Dictionary::instance();
    const float lim = float(4.0 * kSigmaO);
    auto brute = [&](int k, int i, int j, const DVec2* q, int n) {
        const int N = 1200;
        double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
        for (int e = 0; e < n; ++e) x0 = std::min(x0, q[e].x), x1 = std::max(x1, q[e].x), y0 = std::min(y0, q[e].y), y1 = std::max(y1, q[e].y);
        double sum = 0;
        for (int a = 0; a < N; ++a)
            for (int b = 0; b < N; ++b) {
                const double x = x0 + (a + 0.5) * (x1 - x0) / N, y = y0 + (b + 0.5) * (y1 - y0) / N;
                bool inside = true;
                for (int e = 0; e < n && inside; ++e) {
                    const DVec2 u = q[e], v = q[(e + 1) % n];
                    inside = (v.x - u.x) * (y - u.y) - (v.y - u.y) * (x - u.x) >= 0;
                }
                if (!inside || std::abs(x) >= lim || std::abs(y) >= lim) continue;
                sum += double(sampleLinear(dict.row(k, i), kRes, float(std::abs(x) / lim))) *
                       sampleLinear(dict.row(k, j), kRes, float(std::abs(y) / lim));
            }
        return sum * (x1 - x0) * (y1 - y0) / (double(N) * N);
    };
    const DVec2 tri[3] = {{-0.3, -0.2}, {0.5, 0.1}, {0.05, 0.6}};
    const DVec2 quad[4] = {{0.9, -1.0}, {1.8, -0.8}, {1.6, 0.3}, {1.0, 0.2}};
    const DVec2 big[4] = {{-3, -3}, {3, -3}, {3, 3}, {-3, 3}};
    for (int k : {2, 7, 12}) {
        const double mt = cellPolygonMass(dict, k, 5, 77, tri, 3), bt = brute(k, 5, 77, tri, 3);
        const double mq = cellPolygonMass(dict, k, 130, 9, quad, 4), bq = brute(k, 130, 9, quad, 4);
        EXPECT_NEAR(mt, bt, 2e-3 * std::max(bt, 1e-2)) << "k " << k;
        EXPECT_NEAR(mq, bq, 2e-3 * std::max(bq, 1e-2)) << "k " << k;
        EXPECT_NEAR(cellPolygonMass(dict, k, 5, 77, big, 4), 1.0, 2e-3) << "a marginal pair has unit mass";
        // GGAA MIPs: box-filtered, so still unit mass; and a triangle against the brute force of textureGrad1D.
        for (float g : {0.03f, 0.1f, 0.4f}) {
            const MipBlend b = textureGradLod(g, 0.5f * g);
            EXPECT_NEAR(cellPolygonMass(dict, k, 5, 77, big, 4, b, b), 1.0, 2e-3) << "MIP " << b.m0 << " + " << b.f;
            const double bruteMip = [&] {
                const int N = 800;
                double sum = 0;
                for (int a = 0; a < N; ++a)
                    for (int c = 0; c < N; ++c) {
                        const double x = -0.3 + (a + 0.5) * 0.8 / N, y = -0.2 + (c + 0.5) * 0.8 / N;
                        bool inside = true;
                        for (int e = 0; e < 3 && inside; ++e)
                            inside = (tri[(e + 1) % 3].x - tri[e].x) * (y - tri[e].y) -
                                         (tri[(e + 1) % 3].y - tri[e].y) * (x - tri[e].x) >= 0;
                        if (inside)
                            sum += double(textureGrad1D(dict.row(k, 5), float(std::abs(x) / lim), g, 0.5f * g)) *
                                   textureGrad1D(dict.row(k, 77), float(std::abs(y) / lim), g, 0.5f * g);
                    }
                return sum * 0.64 / (double(N) * N);
            }();
            EXPECT_NEAR(cellPolygonMass(dict, k, 5, 77, tri, 3, b, b), bruteMip, 3e-3 * std::max(bruteMip, 1e-2));
        }
    }
    EXPECT_NEAR(gaussianPolygonMass(big, 4), 1.0 - 4 * 0.5 * std::erfc(3.0 / (kSigmaO * std::sqrt(2.0))), 1e-6);
    const double gaussTri = [&] {
        double s = 0;
        const int N = 1500;
        for (int a = 0; a < N; ++a)
            for (int b = 0; b < N; ++b) {
                const double x = -0.3 + (a + 0.5) * 0.8 / N, y = -0.2 + (b + 0.5) * 0.8 / N;
                bool inside = true;
                for (int e = 0; e < 3 && inside; ++e)
                    inside = (tri[(e + 1) % 3].x - tri[e].x) * (y - tri[e].y) - (tri[(e + 1) % 3].y - tri[e].y) * (x - tri[e].x) >= 0;
                if (inside) s += std::exp(-(x * x + y * y) / (2 * kSigmaO * kSigmaO));
            }
        return s * 0.64 / (double(N) * N) / (2 * kPiD * kSigmaO * kSigmaO);
    }();
    EXPECT_NEAR(gaussianPolygonMass(tri, 3), gaussTri, 1e-4);
}

// integratePolygon's glint integral against 256² stratified samples of the quad's area with the exact point
// evaluation (glintFCosScalar). Errors are relative to each query's reference (those with a non-negligible one), the
// bias is Σ analytic / Σ reference − 1 per size class.
void compareWithMonteCarlo(bool ggaa) {
    const auto cases = randomCases(36, 7, ggaa);
    double sumA[3] = {0, 0, 0}, sumR[3] = {0, 0, 0}, maxRel[3] = {0, 0, 0}, sumRel[3] = {0, 0, 0};
    int counted[3] = {0, 0, 0};
    for (size_t n = 0; n < cases.size(); ++n) {
        const Case& c = cases[n];
        const int kind = int(n % 3);
        const double ref = monteCarlo(c.quad, 256, 100 + n, [&](const Vec3& wi) { return pointFCos(c, wi); });
        const double ana = areaIntegral(c);
        sumA[kind] += ana, sumR[kind] += ref;
        if (ref > 1e-4) {
            const double rel = std::abs(ana / ref - 1.0);
            maxRel[kind] = std::max(maxRel[kind], rel);
            sumRel[kind] += rel;
            ++counted[kind];
        }
        std::printf("  %-6s case %2zu: analytic %.5g  MC %.5g  ratio %.4f  (lambda %.1f, sigma %.2f/%.2f)\n", c.size, n,
                    ana, ref, ref > 0 ? ana / ref : 0.0, c.p.logDensity, c.p.sigmaX, c.p.sigmaY);
    }
    const char* names[3] = {"small", "medium", "large"};
    for (int k = 0; k < 3; ++k) {
        const double bias = sumA[k] / sumR[k] - 1.0;
        std::printf("GGAA %d, %s lights: %d queries, mean |rel err| %.4f, max %.4f, bias %+.4f\n", int(ggaa), names[k],
                    counted[k], sumRel[k] / std::max(counted[k], 1), maxRel[k], bias);
        EXPECT_GE(counted[k], 8);
        // Measured: bias <= 0.05 %, mean <= 0.09 %, max 0.76 % (medium, a glint on the light's edge).
        EXPECT_LT(std::abs(bias), 0.01) << names[k];
        EXPECT_LT(sumRel[k] / counted[k], 0.01) << names[k];
        EXPECT_LT(maxRel[k], 0.03) << names[k];
    }
}

TEST(GlintArea, PolygonIntegralMatchesMonteCarloOfThePointEvaluation) { compareWithMonteCarlo(false); }

// With GGAA the area integral reads the MIPs the point evaluation selects for the light's centre direction; the point
// evaluation's MIPs follow wi across the light, which is the residual.
TEST(GlintArea, PolygonIntegralWithGgaaMatchesMonteCarloOfThePointEvaluation) { compareWithMonteCarlo(true); }

TEST(GlintArea, TinyLightTendsToThePointEvaluation) {
    // A light of 1e-3 rad: integral / solid angle -> f cos at the centre direction (the glint lobes are ~0.02 rad
    // wide in wi, so the residual is the variation of f across the light).
    const auto cases = randomCases(60, 11);
    double maxRel = 0, sumRel = 0;
    int counted = 0;
    for (const Case& base : cases) {
        Case c = base;
        const Vec3 dir = glm::normalize(c.quad.centre);
        c.quad = makeQuad(dir, 2.f, 2e-3f, 0.f);
        const double point = pointFCos(c, dir);
        if (point < 1e-2) continue;
        const double ratio = areaIntegral(c) / solidAngle(c.quad.v, 4) / point;
        maxRel = std::max(maxRel, std::abs(ratio - 1));
        sumRel += std::abs(ratio - 1);
        ++counted;
    }
    std::printf("tiny lights: %d queries, mean |rel err| %.5f, max %.5f\n", counted, sumRel / counted, maxRel);
    EXPECT_GE(counted, 20);
    // Measured: mean 0.02 %, max 0.39 %.
    EXPECT_LT(sumRel / counted, 0.005);
    EXPECT_LT(maxRel, 0.02);
}

TEST(GlintArea, ConvergedLimitIsTheBeckmannLobeIntegral) {
    // log_density 70: every cell converged (k = L) -> the Cook-Torrance Beckmann lobe with the V-cavity G; against
    // 256² stratified samples of beckmannFCosScalar. The smooth factor at the region's centroid is the only
    // approximation, so this measures it for each light size.
    auto cases = randomCases(36, 5);
    double maxRel[3] = {0, 0, 0}, sumRel[3] = {0, 0, 0};
    int counted[3] = {0, 0, 0};
    for (size_t n = 0; n < cases.size(); ++n) {
        Case& c = cases[n];
        c.p.logDensity = 70.f;
        const GlintShape shape = GlintShape::make(c.p.sigmaX, c.p.sigmaY, c.p.rho);
        const double ref = monteCarlo(c.quad, 256, 300 + n, [&](const Vec3& wi) { return beckmannFCosScalar(shape, c.wo, wi); });
        const double point = monteCarlo(c.quad, 64, 900 + n, [&](const Vec3& wi) { return pointFCos(c, wi); });
        EXPECT_NEAR(point, ref, 0.02 * ref + 1e-6) << "the converged point evaluation is the Beckmann lobe";
        if (ref < 1e-4) continue;
        const double rel = std::abs(areaIntegral(c) / ref - 1);
        const int kind = int(n % 3);
        maxRel[kind] = std::max(maxRel[kind], rel), sumRel[kind] += rel, ++counted[kind];
    }
    const char* names[3] = {"small", "medium", "large"};
    for (int k = 0; k < 3; ++k) {
        std::printf("converged, %s lights: %d queries, mean |rel err| %.4f, max %.4f\n", names[k], counted[k],
                    sumRel[k] / std::max(counted[k], 1), maxRel[k]);
        EXPECT_GE(counted[k], 8);
        // Measured: mean <= 0.19 %, max 1.2 % (large light across G's kink).
        EXPECT_LT(sumRel[k] / counted[k], 0.01) << names[k];
        EXPECT_LT(maxRel[k], 0.03) << names[k];
    }
}

TEST(GlintArea, ChordSubdivisionErrorIsSmall) {
    // The curved image of the light's edges in half-slope space: integrals with the default chord tolerance (1e-4 in
    // M^-1 space) against 1e-5.
    auto cases = randomCases(24, 3);
    GlintAreaSettings fine;
    fine.chordTolerance = 1e-5f;
    fine.maxDepth = kMaxChordDepth;
    double maxRel = 0;
    for (Case& c : cases) {
        const double a = areaIntegral(c), b = areaIntegral(c, fine);
        const GlintShape shape = GlintShape::make(c.p.sigmaX, c.p.sigmaY, c.p.rho);
        DVec2 region[kMaxRegionVertices];
        const int na = halfSlopeRegion(c.wo, c.quad.v, 4, shape, {}, region);
        const int nb = halfSlopeRegion(c.wo, c.quad.v, 4, shape, fine, region);
        std::printf("  %-6s %.5g %.5g vertices %d %d\n", c.size, a, b, na, nb);
        if (b > 1e-4) maxRel = std::max(maxRel, std::abs(a / b - 1));
    }
    std::printf("chord tolerance 1e-4 vs 1e-5: max rel diff %.5f\n", maxRel);
    EXPECT_LT(maxRel, 0.005);  // measured 0.24 %
}

namespace {

// The corners of the part s in [s0, s1] (t in [-1, 1]) of a quad light, counter-clockwise seen from the origin.
Quad subQuad(const Quad& q, float s0, float s1) {
    Quad r = q;
    r.centre = q.centre + 0.5f * (s0 + s1) * q.e1;
    r.e1 = 0.5f * (s1 - s0) * q.e1;
    r.v[0] = r.centre - r.e1 - r.e2, r.v[1] = r.centre + r.e1 - r.e2, r.v[2] = r.centre + r.e1 + r.e2;
    r.v[3] = r.centre - r.e1 + r.e2;
    Vec3 nrm(0.f);
    for (int i = 0; i < 4; ++i) nrm += glm::cross(r.v[i], r.v[(i + 1) % 4]);
    if (glm::dot(nrm, r.centre) < 0.f) std::swap(r.v[1], r.v[3]);
    return r;
}

}  // namespace

TEST(GlintArea, ShadowRayDirectionsFollowTheGlintIntegrand) {
    // The ratio estimator's visibility is exact only for directions ∝ the integrand. Test: the fraction of
    // samplePolygon's directions hitting the left half of the light against that half's share of the integral
    // (integratePolygon on the half), over medium and large glinty lights; the cosine-weighted sampler for contrast.
    const auto cases = randomCases(30, 21);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> U(0.f, 1.f);
    double sumCells = 0, sumCos = 0, worstCells = 0, hit = 0, drawn = 0;
    int counted = 0;
    for (size_t n = 0; n < cases.size(); ++n) {
        const Case& c = cases[n];
        if (n % 3 == 0) continue;  // small lights: both samplers are fine
        const double total = areaIntegral(c);
        if (total < 1e-3) continue;
        Case left = c;
        left.quad = subQuad(c.quad, -1.f, 0.f);
        const double share = areaIntegral(left) / total;
        const GlintShape shape = GlintShape::make(c.p.sigmaX, c.p.sigmaY, c.p.rho);
        const int N = 1000;
        areaIntegral(c);  // the sampler reuses the cells of the last integral of the same query
        int inLeftCells = 0, inLeftCos = 0;
        for (int k = 0; k < N; ++k) {
            const float uY = U(rng), uX = U(rng);  // sequenced: gcc's former right-to-left argument order
            const Vec2 u(uX, uY);
            const uint64_t seed = rng();
            Vec3 w;
            auto side = [&](const Vec3& wi) {  // light-plane coordinate s of direction wi (|s| <= 1 on the light)
                const float den = glm::dot(wi, c.quad.normal);
                const Vec3 pt = wi * (glm::dot(c.quad.centre, c.quad.normal) / den);
                return glm::dot(pt - c.quad.centre, c.quad.e1) / glm::dot(c.quad.e1, c.quad.e1);
            };
            if (glintSamplePolygonByCells(Dictionary::instance(), c.p, shape, c.in, c.wo, c.quad.v, 4, u, seed, w)) {
                const float sw = side(w);
                const float tw = [&] {
                    const Vec3 pt = w * (glm::dot(c.quad.centre, c.quad.normal) / glm::dot(w, c.quad.normal));
                    return glm::dot(pt - c.quad.centre, c.quad.e2) / glm::dot(c.quad.e2, c.quad.e2);
                }();
                inLeftCells += sw < 0.f;
                hit += std::abs(sw) <= 1.01f && std::abs(tw) <= 1.01f;
            }
            drawn += 1;
            if (glintSamplePolygon(c.quad.v, 4, u, seed, w)) inLeftCos += side(w) < 0.f;
        }
        const double dCells = std::abs(double(inLeftCells) / N - share), dCos = std::abs(double(inLeftCos) / N - share);
        std::printf("  %-6s case %2zu: left share %.3f, cell sampling %.3f, cosine sampling %.3f\n", c.size, n, share,
                    double(inLeftCells) / N, double(inLeftCos) / N);
        sumCells += dCells, sumCos += dCos, worstCells = std::max(worstCells, dCells);
        ++counted;
    }
    std::printf("left-half share error: cell sampling mean %.4f max %.4f; cosine sampling mean %.4f; on the light %.4f\n",
                sumCells / counted, worstCells, sumCos / counted, hit / drawn);
    EXPECT_GE(counted, 10);
    EXPECT_LT(sumCells / counted, 0.03);
    EXPECT_LT(sumCells, 0.5 * sumCos);
    EXPECT_GT(hit / drawn, 0.99);
}

namespace {

// A glint torus under one quad light, nothing else (no environment): the specular AOV is the light's glints.
// 'crop' rows of the 64x36 frame keep CI time low.
std::string torusScene(int spp, const char* mode, int seed, bool ggaa, const char* footprintCentre = "sample") {
    return R"({
        "render": {"width": 32, "height": 18, "spp": )" + std::to_string(spp) + R"(, "integrator": "direct", "seed": )" +
           std::to_string(seed) + R"(, "area_lights": ")" + mode + R"("},
        "camera": {"position": [0, -2.2, 1.3], "look_at": [0, 0, 0.1], "fov": 40},
        "materials": {"glint": {"nodes": {"g": {"type": "bsdf.glint", "inputs": {"sigma_x": 0.2, "sigma_y": 0.2,
            "log_density": 13, "f0": [0.95, 0.64, 0.54], "uv_scale": 4, "quad_lights": "integrated", "ggaa": ")" + std::string(ggaa ? "on" : "off") +
           R"(", "footprint_centre": ")" + footprintCentre + R"("}}}, "output": "@g.bsdf"}},
        "shapes": [{"type": "torus", "major_radius": 1.0, "minor_radius": 0.4, "material": "glint"}],
        "lights": [{"type": "quad", "position": [0.6, 0.8, 2.2], "look_at": [0, 0, 0], "size": [0.6, 0.4], "power": 30}]})";
}

std::vector<float> specularAov(const std::string& json, bool pixelCentres, double* seconds) {
    Scene s = loadSceneFromString(json, test::sourcePath("examples"));
    s.render.pixelCenter = pixelCentres;
    const auto t0 = std::chrono::steady_clock::now();
    RenderOutput r = renderScene(s);
    *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r.images.find("specular")->pixels;
}

double rmseOf(const std::vector<float>& a, const std::vector<float>& b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    return std::sqrt(s / a.size());
}

double meanOf(const std::vector<float>& a) {
    double s = 0;
    for (float v : a) s += v;
    return s / a.size();
}

struct RenderComparison {
    double ratio, bias;  // RMSE(ltc 16) / RMSE(sampled 16) against the reference; mean(ltc 16) / mean(ref) - 1
};

// The glint torus at 16 spp with analytic ("ltc") and sampled lights against a refSpp sampled reference.
RenderComparison compareAt16Spp(bool pixelCentres, bool ggaa, int refSpp, const char* footprintCentre = "sample") {
    double tRef = 0, tLtc = 0, tSampled = 0;
    const auto ref = specularAov(torusScene(refSpp, "sampled", 1, ggaa, footprintCentre), pixelCentres, &tRef);
    const auto ltc = specularAov(torusScene(16, "ltc", 2, ggaa, footprintCentre), pixelCentres, &tLtc);
    const auto sampled = specularAov(torusScene(16, "sampled", 2, ggaa, footprintCentre), pixelCentres, &tSampled);
    const double eLtc = rmseOf(ltc, ref), eSampled = rmseOf(sampled, ref);
    const double mRef = meanOf(ref), mLtc = meanOf(ltc), mSampled = meanOf(sampled);
    std::printf("pixel centres %d, GGAA %d: specular mean ref %.5f ltc16 %.5f sampled16 %.5f; RMSE ltc16 %.5f "
                "sampled16 %.5f ratio %.3f; bias ltc %+.4f; time ref %.1fs ltc16 %.2fs sampled16 %.2fs\n",
                int(pixelCentres), int(ggaa), mRef, mLtc, mSampled, eLtc, eSampled, eLtc / eSampled, mLtc / mRef - 1,
                tRef, tLtc, tSampled);
    return {eLtc / eSampled, mRef > 0.0 ? mLtc / mRef - 1.0 : 1.0};
}

}  // namespace

TEST(GlintAreaRender, AnalyticGlintsAt16SppHaveAThirdOfTheSampledErrorWithoutBias) {
    // Issue 11 item 2's goal, at pixel centres as the glint validation scenes (tests/validation/glint), so that what
    // differs between the methods is the light integration alone (plus the ratio estimator's shadow rays).
    // Measured: RMSE ratio 0.068, bias -0.02 % (area integral without GGAA: 0.077 / +0.07 % against GGAA-off renders,
    // but RMSE 0.040 and bias -1.3 % against these GGAA renders: why the integral reads GGAA's MIPs).
    const RenderComparison c = compareAt16Spp(true, true, 4096);
    EXPECT_LE(c.ratio, 0.3);
    EXPECT_LE(std::abs(c.bias), 0.03);
}

TEST(GlintAreaRender, JitteredPixelSamplesKeepTheirCoverageNoise) {
    // Jittered pixel samples (the renderer's default): each sample shades another point of the glint pattern, and that
    // coverage noise is common to both methods (it did not change with 8 shadow rays instead of 2), so the ratio is
    // higher. Measured 0.50 and bias +0.7 % against a 1024-spp reference (its noise, 1/8 of sampled's at 16 spp, keeps
    // CI time and raises the ratio by < 1 %); asserted with a margin.
    const RenderComparison c = compareAt16Spp(false, true, 1024);
    EXPECT_LE(c.ratio, 0.7);
    EXPECT_LE(std::abs(c.bias), 0.03);
}

TEST(GlintAreaRender, PixelCentredGlintsKeepTheirThirdOfTheSampledErrorWithJitteredPixels) {
    // footprint_centre "pixel" (issue 38 item 2): each sample of a pixel shades with the pixel centre's footprint and
    // frame, so the coverage noise above leaves the glints and the analytic light keeps its advantage with jittered
    // pixels. Measured ratio 0.252 (0.510 with "sample", the test above), bias +0.12 % against a 1024-spp sampled
    // reference of the same mode; asserted with a margin.
    const RenderComparison c = compareAt16Spp(false, true, 1024, "pixel");
    EXPECT_LE(c.ratio, 0.33);
    EXPECT_LE(std::abs(c.bias), 0.03);
}

// ---- explicit flakes under quad lights (issue 38 item 3) ----------------------------------------------------------
namespace {

// Flake cases: the random materials and views above with flakes of 0.002 UV (RMS slope 0.02-0.06), at a zero footprint
// (explicit flakes only) or halfway to the counted cells (footprint 0.75 flake, w_e = 1/2), on a point with a flake,
// the light around the mirror direction of a slope drawn from that flake's lobe.
struct FlakeCase {
    Case c;
    GlintLobe lobe;
};
std::vector<FlakeCase> flakeCases(int count, uint32_t seed, bool halfway) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.f, 1.f);
    std::normal_distribution<float> N(0.f, 1.f);
    std::vector<FlakeCase> out;
    for (Case c : randomCases(4 * count, seed)) {
        if (int(out.size()) == count) break;
        c.p.flakeSize = 0.002f;
        c.p.flakeRoughness = 0.02f + 0.04f * U(rng);
        c.p.logDensity = flakeLogDensity(c.p.flakeSize);
        c.p.integrateQuadLights = true;
        const float fp = halfway ? 0.75f * c.p.flakeSize : 0.f;
        c.in.duvdx = Vec2(fp, 0.f), c.in.duvdy = Vec2(0.f, fp);
        GlintLobe lobe(Dictionary::instance(), c.p, c.in, Fresnel::one());
        if (lobe.flakes().count == 0) continue;
        const Vec2 s = lobe.flakes().flakes[0].slope + lobe.flakeSigma() * Vec2(N(rng), N(rng));
        const Vec3 h = glm::normalize(Vec3(-s.x, -s.y, 1.f));
        const Vec3 wi = 2.f * glm::dot(c.wo, h) * h - c.wo;
        if (wi.z < 0.1f || glm::dot(c.wo, h) <= 0.f) continue;
        const float dist = 1.f + 4.f * U(rng), angle = 0.05f + 0.3f * U(rng);
        c.quad = makeQuad(wi, dist, 2.f * dist * std::tan(0.5f * angle), 0.8f * (U(rng) - 0.5f));
        out.push_back({c, lobe});
    }
    return out;
}

}  // namespace

// The flake's share of the polygon integral (flakePolygonIntegral: its Gaussian over the light's half-slope region,
// the smooth factor at its centroid per piece) against Monte Carlo of the lobe's own point evaluation, explicit flakes
// only and halfway to the counted cells (whose share is glintPolygonIntegral's).
TEST(GlintArea, FlakePolygonIntegralMatchesMonteCarloOfThePointEvaluation) {
    for (bool halfway : {false, true}) {
        const auto cases = flakeCases(24, halfway ? 41 : 43, halfway);
        ASSERT_EQ(cases.size(), 24u);
        double sumA = 0, sumR = 0, sumRel = 0, maxRel = 0;
        int counted = 0;
        for (size_t n = 0; n < cases.size(); ++n) {
            const FlakeCase& f = cases[n];
            if (halfway) ASSERT_NEAR(f.lobe.flakeWeight(), 0.5f, 1e-6f);
            const double ref = monteCarlo(f.c.quad, 256, 300 + n, [&](const Vec3& wi) {
                return f.lobe.evalPdf(LobeQuery{f.c.wo, wi}).f.x;
            });
            Color3 ana(0.f);
            ASSERT_TRUE(f.lobe.integratePolygon(LobeQuery{f.c.wo, f.c.wo}, f.c.quad.v, 4, ana));
            sumA += ana.x, sumR += ref;
            if (ref > 1e-3) {
                const double rel = std::abs(ana.x / ref - 1.0);
                sumRel += rel, maxRel = std::max(maxRel, rel);
                ++counted;
            }
        }
        std::printf("flakes under quad lights (%s): %d queries, mean |rel err| %.4f, max %.4f, bias %+.4f\n",
                    halfway ? "halfway" : "flakes only", counted, sumRel / std::max(counted, 1), maxRel, sumA / sumR - 1);
        EXPECT_GE(counted, 16);
        EXPECT_LT(std::abs(sumA / sumR - 1.0), 0.01);
        EXPECT_LT(sumRel / counted, 0.01);
        EXPECT_LT(maxRel, 0.03);
    }
}

// The shadow-ray directions of a flake lobe follow its integrand: the share of samplePolygon's directions on the left
// half of the light against integratePolygon's share of that half.
TEST(GlintArea, FlakeShadowRayDirectionsFollowTheFlakeIntegrand) {
    const auto cases = flakeCases(20, 47, false);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> U(0.f, 1.f);
    double sumErr = 0, worst = 0;
    int counted = 0;
    for (const FlakeCase& f : cases) {
        Color3 total(0.f), left(0.f);
        const Quad half = subQuad(f.c.quad, -1.f, 0.f);
        f.lobe.integratePolygon(LobeQuery{f.c.wo, f.c.wo}, f.c.quad.v, 4, total);
        f.lobe.integratePolygon(LobeQuery{f.c.wo, f.c.wo}, half.v, 4, left);
        if (total.x < 1e-3f) continue;
        const double share = left.x / total.x;
        const int N = 1000;
        int inLeft = 0;
        for (int k = 0; k < N; ++k) {
            const float uY = U(rng), uX = U(rng);
            Vec3 w;
            if (!f.lobe.samplePolygon(LobeQuery{f.c.wo, f.c.wo}, f.c.quad.v, 4, Vec2(uX, uY), rng(), w)) continue;
            const Vec3 pt = w * (glm::dot(f.c.quad.centre, f.c.quad.normal) / glm::dot(w, f.c.quad.normal));
            inLeft += glm::dot(pt - f.c.quad.centre, f.c.quad.e1) < 0.f;
        }
        const double err = std::abs(double(inLeft) / N - share);
        sumErr += err, worst = std::max(worst, err);
        ++counted;
    }
    std::printf("flake shadow rays: left-half share error mean %.4f, max %.4f over %d lights\n", sumErr / counted,
                worst, counted);
    EXPECT_GE(counted, 12);
    EXPECT_LT(sumErr / counted, 0.03);
    EXPECT_LT(worst, 0.08);
}
