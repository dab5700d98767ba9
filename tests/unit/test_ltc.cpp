// LTC polygon integration (ltc-filtering.md §3, invariants T3, T5, T7): the edge formulas, horizon clipping, the cap
// form factor, polygon-restricted sampling and the one-LTC lobe, against closed forms and independent Monte Carlo.
#include "core/ltc/ltc.h"
#include "core/render/lights.h"
#include "core/render/sampler.h"
#include "core/render/sampling.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace specula;
using namespace specula::ltc;

namespace {

struct Rng {
    uint64_t s;
    double next() { return double(mix64(++s) >> 11) * 0x1.0p-53; }
    Vec2 next2() {
        float a = float(next());
        return {a, float(next())};
    }
};

// A quad (counter-clockwise seen from the origin, i.e. a positive form factor) centred at c with half-edges a, b.
std::array<Vec3, 4> quadFacingOrigin(const Vec3& c, const Vec3& a, const Vec3& b) {
    std::array<Vec3, 4> q = {c - a - b, c + a - b, c + a + b, c - a + b};
    DVec3 n = glm::cross(DVec3(q[1] - q[0]), DVec3(q[2] - q[0]));
    if (glm::dot(n, DVec3(c)) < 0.0) std::swap(q[1], q[3]);
    return q;
}

// Does the ray from the origin along w hit the convex planar polygon?
bool rayHitsPolygon(const Vec3& w, const Vec3* v, int n) {
    DVec3 nrm = glm::cross(DVec3(v[1] - v[0]), DVec3(v[2] - v[0]));
    double den = glm::dot(DVec3(w), nrm);
    if (den == 0.0) return false;
    double t = glm::dot(DVec3(v[0]), nrm) / den;
    if (t <= 0.0) return false;
    DVec3 p = DVec3(w) * t;
    double sgn = 0.0;
    for (int i = 0; i < n; ++i) {
        double s = glm::dot(glm::cross(DVec3(v[(i + 1) % n] - v[i]), p - DVec3(v[i])), nrm);
        if (sgn == 0.0) sgn = s;
        else if (s * sgn < 0.0) return false;
    }
    return true;
}

// Monte Carlo of ∫_P D_o: uniform sphere directions (independent of the edge formulas).
double mcClampedCosine(const Vec3* v, int n, int samples, uint64_t seed) {
    Rng r{seed};
    double sum = 0;
    for (int i = 0; i < samples; ++i) {
        Vec3 w = sampleUniformSphere(r.next2());
        if (w.z > 0.f && rayHitsPolygon(w, v, n)) sum += w.z / kPi;
    }
    return sum * 4.0 * kPi / samples;
}

Ltc shearedLtc() {
    Ltc l;
    // A glossy, tilted, anisotropic lobe (rows (a,0,b),(0,c,0),(d,0,e) like the GGX fits, plus a y coupling).
    Mat3 m(1.f);
    m[0][0] = 3.2f, m[2][0] = -1.1f, m[1][1] = 2.4f, m[0][2] = 0.35f, m[2][2] = 1.f, m[1][0] = 0.3f;
    l.invM = m;
    l.magnitude = 0.8f;
    return l;
}

}  // namespace

TEST(LtcEdges, RationalEdgeFactorMatchesAcosOverSine) {  // T5
    double worst = 0;
    for (int i = 0; i <= 200000; ++i) {
        double x = -0.9999 + 1.9998 * i / 200000.0;
        double exact = std::acos(x) / std::sqrt(1.0 - x * x) / (2.0 * M_PI);
        worst = std::max(worst, std::abs(rationalEdgeFactor(x) - exact) / exact);
    }
    std::printf("T5: worst relative error of the rational edge factor %.2e (limit 2e-6)\n", worst);
    EXPECT_LT(worst, 2e-6);
}

TEST(LtcEdges, CosineLtcOfHugeAndTinyQuads) {  // T3
    const Ltc cosine;
    auto huge = quadFacingOrigin({0, 0, 1}, {1e4f, 0, 0}, {0, 1e4f, 0});
    for (Horizon h : {Horizon::Clip, Horizon::Clipless})
        EXPECT_NEAR(integrate(cosine, huge.data(), 4, false, h, nullptr), 1.0, 1e-5) << int(h);
    auto tiny = quadFacingOrigin({0, 0, 1}, {1e-3f, 0, 0}, {0, 1e-3f, 0});
    double area = 2e-3 * 2e-3;
    EXPECT_NEAR(integrate(cosine, tiny.data(), 4, false, Horizon::Clip, nullptr) / (area / M_PI), 1.0, 1e-5);
    // Seen from behind: zero one-sided, the same magnitude two-sided.
    std::array<Vec3, 4> back = {tiny[0], tiny[3], tiny[2], tiny[1]};
    EXPECT_EQ(integrate(cosine, back.data(), 4, false, Horizon::Clip, nullptr), 0.0);
    EXPECT_EQ(integrate(cosine, back.data(), 4, false, Horizon::Clipless, nullptr), 0.0);
    EXPECT_NEAR(integrate(cosine, back.data(), 4, true, Horizon::Clip, nullptr) / (area / M_PI), 1.0, 1e-5);
}

TEST(LtcEdges, QuadLightPolygonIsOrientedForAPositiveFormFactor) {
    // The renderer's lights hand out polygons counter-clockwise seen from the shading point (lights.h).
    QuadLight light(Vec3(-0.5f, -0.5f, 2.f), Vec3(1, 0, 0), Vec3(0, 1, 0), Color3(1.f), false);
    Vec3 v[4];
    Color3 L;
    // cross(edgeU, edgeV) = +z: the light emits upwards, so only a point above it sees the front.
    ASSERT_EQ(light.polygon(Vec3(0, 0, 3), v, L), 4);
    for (auto& p : v) p = p - Vec3(0, 0, 3);
    for (auto& p : v) p.z = -p.z, p.x = -p.x;  // flip the local frame so the light is overhead (z > 0), keeping orientation
    EXPECT_GT(integrate(Ltc{}, v, 4, false, Horizon::Clip, nullptr), 0.0);
    EXPECT_EQ(light.polygon(Vec3(0, 0, 1), v, L), 0);  // behind a one-sided light
}

TEST(LtcEdges, ClippedIntegralMatchesMonteCarloAcrossTheHorizon) {
    Rng r{7};
    for (int k = 0; k < 12; ++k) {
        Vec3 c(float(r.next() * 2 - 1), float(r.next() * 2 - 1), float(r.next() * 1.2 - 0.5));
        Vec3 a(float(0.3 + r.next()), float(r.next() - 0.5), float(r.next() - 0.5));
        Vec3 b(float(r.next() - 0.5), float(0.3 + r.next()), float(r.next()));
        auto q = quadFacingOrigin(c, a, b);
        double exact = clampedCosineIntegral(std::array<DVec3, 4>{DVec3(q[0]), DVec3(q[1]), DVec3(q[2]), DVec3(q[3])}.data(),
                                             4, false, Horizon::Clip, nullptr);
        double mc = mcClampedCosine(q.data(), 4, 400000, 100 + k);
        EXPECT_NEAR(exact, mc, 4e-3 + 0.02 * mc) << k;
    }
}

TEST(LtcEdges, CapFormFactorMatchesMonteCarloAndIsContinuous) {  // T7 (cap formula within 5e-3 of MC)
    Rng r{11};
    for (int k = 0; k < 16; ++k) {
        double sigma = 0.05 + 1.2 * r.next(), omega = M_PI * r.next();
        DVec3 axis(std::sin(omega), 0.0, std::cos(omega));
        double cs = std::cos(sigma), sum = 0;
        const int n = 400000;
        for (int i = 0; i < n; ++i) {
            Vec3 w = sampleUniformSphere(r.next2());
            if (w.z > 0.f && glm::dot(DVec3(w), axis) >= cs) sum += w.z / M_PI;
        }
        EXPECT_NEAR(capFormFactor(omega, sigma), sum * 4.0 * M_PI / n, 5e-3) << sigma << " " << omega;
    }
    for (double sigma : {0.1, 0.6, 1.2}) {
        for (double edge : {0.5 * M_PI - sigma, 0.5 * M_PI, 0.5 * M_PI + sigma}) {
            EXPECT_NEAR(capFormFactor(edge - 1e-9, sigma), capFormFactor(edge + 1e-9, sigma), 1e-6) << sigma << " " << edge;
        }
        double prev = 1e9;  // monotonic in the elevation of the axis
        for (int i = 0; i <= 100; ++i) {
            double f = capFormFactor(M_PI * i / 100.0, sigma);
            EXPECT_LE(f, prev + 1e-12);
            prev = f;
        }
    }
}

TEST(LtcEdges, ClipFreeAgreesWithExactClipping) {  // T7
    Rng r{3};
    std::vector<double> straddling;
    double worstAbove = 0;
    int above = 0;
    for (int k = 0; k < 4000; ++k) {
        Vec3 c(float(r.next() * 4 - 2), float(r.next() * 4 - 2), float(r.next() * 2.5 - 0.8));
        Vec3 a(float(0.05 + r.next()), float(r.next() - 0.5), float(r.next() - 0.5));
        Vec3 b(float(r.next() - 0.5), float(0.05 + r.next()), float(r.next() - 0.5));
        auto q = quadFacingOrigin(c, a, b);
        DVec3 d[4] = {DVec3(q[0]), DVec3(q[1]), DVec3(q[2]), DVec3(q[3])};
        double clip = clampedCosineIntegral(d, 4, false, Horizon::Clip, nullptr);
        double free = clampedCosineIntegral(d, 4, false, Horizon::Clipless, nullptr);
        // |F|: the form-factor vector length of the unclipped polygon.
        DVec3 F(0.0);
        for (int i = 0; i < 4; ++i) F += edgeVectorRational(glm::normalize(d[i]), glm::normalize(d[(i + 1) % 4]));
        double len = glm::length(F);
        if (len < 1e-4) continue;
        bool allAbove = std::all_of(d, d + 4, [](const DVec3& p) { return p.z > 0.0; });
        if (allAbove) {
            worstAbove = std::max(worstAbove, std::abs(clip - free) / len);
            ++above;
            // The equivalent cap fully above the horizon: the sphere path returns F_z itself.
            double sigma = std::asin(std::sqrt(std::min(len, 1.0))), omega = std::acos(F.z / len);
            if (omega <= 0.5 * M_PI - sigma) EXPECT_NEAR(free, F.z, 1e-9);
        } else {
            straddling.push_back(std::abs(clip - free) / len);
        }
    }
    ASSERT_GT(above, 500);
    ASSERT_GT(straddling.size(), 500u);
    EXPECT_LE(worstAbove, 0.02);
    std::sort(straddling.begin(), straddling.end());
    std::printf("T7: above the horizon worst %.4f|F| (%d quads); straddling (%zu) median %.4f p95 %.4f max %.4f |F|\n",
                worstAbove, above, straddling.size(), straddling[straddling.size() / 2],
                straddling[size_t(0.95 * straddling.size())], straddling.back());
    EXPECT_LE(straddling[straddling.size() / 2], 0.015);
    EXPECT_LE(straddling[size_t(0.95 * straddling.size())], 0.07);
    EXPECT_LE(straddling.back(), 0.13);
}

TEST(LtcDistribution, DensityIntegratesToOneAndSamplingFollowsIt) {
    const Ltc l = shearedLtc();
    // ∫ D dω = 1 (importance sampled by D itself: E[1] over samples mapped back gives the density identity check).
    Rng r{5};
    double sum = 0;
    const int n = 400000;
    for (int i = 0; i < n; ++i) {  // MIS-free: uniform sphere estimate of ∫ D with D's own samples as a control
        Vec3 w = sampleUniformSphere(r.next2());
        sum += l.density(w);
    }
    EXPECT_NEAR(sum * 4.0 * M_PI / n, 1.0, 0.03);
    // Sampling: the fraction of samples hitting a polygon equals ∫_P D (exact).
    auto q = quadFacingOrigin({0.3f, -0.2f, 1.f}, {0.4f, 0.1f, 0}, {0, 0.3f, 0.1f});
    double p = integrate(l, q.data(), 4, false, Horizon::Clip, nullptr);
    int hits = 0;
    for (int i = 0; i < n; ++i) hits += rayHitsPolygon(l.sample(r.next2()), q.data(), 4);
    double f = double(hits) / n, sigma = std::sqrt(p * (1 - p) / n);
    EXPECT_GT(p, 0.05);
    EXPECT_NEAR(f, p, 5 * sigma);
}

Ltc sharpLtc() {
    // A very glossy GGX-like lobe (α ≈ 0.01 at normal view): lights away from the peak become thin crescents near the
    // horizon of cosine space, where the disk-projection rejection would almost never hit (the spherical-triangle path).
    Ltc l;
    Mat3 m(1.f);
    m[0][0] = 80.f, m[1][1] = 80.f, m[2][0] = -3.f;
    l.invM = m;
    return l;
}

TEST(LtcDistribution, PolygonSamplingIsProportionalToTheLtcOverThePolygon) {
    // Sub-quads of a light: the share of samplePolygon's directions in each equals its share of ∫_P D (χ² test).
    // Overhead and straddling the horizon (the sheared lobe); near the peak and off it (the sharp lobe: the polygon
    // in cosine space contains the zenith, or is a thin crescent at the horizon).
    const std::pair<int, Vec3> configs[] = {{0, Vec3(0.3f, -0.2f, 1.f)}, {0, Vec3(1.2f, 0.4f, 0.15f)},
                                            {1, Vec3(0.3f, -0.2f, 1.f)}, {1, Vec3(0.6f, 0.5f, 1.f)}};
    for (const auto& [lobe, c] : configs) {
        const Ltc l = lobe == 0 ? shearedLtc() : sharpLtc();
        const Vec3 a(0.5f, 0.1f, 0.f), b(0.f, 0.4f, 0.2f);
        auto q = quadFacingOrigin(c, a, b);
        double total = integrate(l, q.data(), 4, false, Horizon::Clip, nullptr);
        ASSERT_GT(total, 1e-4);
        // 4×4 sub-quads (same orientation as the parent).
        std::vector<std::array<Vec3, 4>> cells;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                auto lerp = [&](float s, float t) { return q[0] + (q[1] - q[0]) * s + (q[3] - q[0]) * t; };
                float s0 = i / 4.f, s1 = (i + 1) / 4.f, t0 = j / 4.f, t1 = (j + 1) / 4.f;
                cells.push_back({lerp(s0, t0), lerp(s1, t0), lerp(s1, t1), lerp(s0, t1)});
            }
        std::vector<double> expect(cells.size());
        double sumExpect = 0;
        for (size_t k = 0; k < cells.size(); ++k) sumExpect += expect[k] = integrate(l, cells[k].data(), 4, false, Horizon::Clip, nullptr);
        EXPECT_NEAR(sumExpect, total, 1e-6 * std::max(1.0, total));
        const int n = 200000;
        std::vector<int> count(cells.size(), 0);
        Rng r{17};
        int failed = 0;
        for (int i = 0; i < n; ++i) {
            Vec3 w;
            if (!samplePolygon(l, q.data(), 4, r.next2(), mix64(i + 1), w)) {
                ++failed;
                continue;
            }
            for (size_t k = 0; k < cells.size(); ++k)
                if (rayHitsPolygon(w, cells[k].data(), 4)) {
                    ++count[k];
                    break;
                }
        }
        EXPECT_EQ(failed, 0);
        double chi2 = 0;
        int dof = -1;
        for (size_t k = 0; k < cells.size(); ++k) {
            double e = expect[k] / total * n;
            if (e < 5) continue;
            chi2 += (count[k] - e) * (count[k] - e) / e;
            ++dof;
        }
        ASSERT_GT(dof, 4);
        EXPECT_LT(chi2, dof + 5.0 * std::sqrt(2.0 * dof)) << "dof " << dof;  // about a 1e-4 false-alarm rate
    }
}

TEST(LtcLobe, AnswersQueriesConsistently) {
    const Ltc l = shearedLtc();
    LtcLobe lobe(l, LobeKind::Specular, Color3(1.f, 0.5f, 0.25f));
    const Vec3 wo = glm::normalize(Vec3(0.4f, 0.1f, 0.9f));
    // f·cos = tint·mag·D, pdf = D; the polygon integral equals the MC integral of f·cos over the polygon.
    auto q = quadFacingOrigin({0.3f, -0.2f, 1.f}, {0.4f, 0.1f, 0}, {0, 0.3f, 0.1f});
    Color3 exact;
    ASSERT_TRUE(lobe.integratePolygon(LobeQuery{wo, wo}, q.data(), 4, exact));
    Rng r{23};
    double sum = 0;
    const int n = 400000;
    for (int i = 0; i < n; ++i) {
        Vec3 wi;
        if (!lobe.sample(wo, r.next2(), wi)) continue;
        LobeValue v = lobe.evalPdf(LobeQuery{wo, wi});
        ASSERT_NEAR(v.f.x, 0.8f * v.pdf, 1e-6f * std::max(1.f, v.pdf));
        if (rayHitsPolygon(wi, q.data(), 4)) sum += v.f.y / v.pdf;
    }
    EXPECT_NEAR(sum / n, exact.y, 0.01 * exact.y + 1e-4);
    EXPECT_NEAR(lobe.albedo(wo).z, 0.25f * 0.8f, 1e-6f);
}
