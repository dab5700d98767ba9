// Tests for LEAN mapping (core/texture/lean_moments, nodes/bsdf/beckmann_lean): exact moment pyramids, PSD
// covariances, footprint lookups, ρ recovery, and the Beckmann-LEAN lobe against closed-form Beckmann.
#include "core/texture/lean_moments.h"
#include "core/texture/normal_map_gen.h"
#include "nodes/bsdf/beckmann_lean/beckmann_lean.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace specula;

namespace {

constexpr double kPiD = 3.14159265358979323846;

// Map whose slopes are iid draws of a correlated Gaussian: x~ = σx z1, y~ = σy (ρ z1 + sqrt(1-ρ²) z2).
NormalMap correlatedMap(int n, double sx, double sy, double rho, uint32_t seed) {
    std::mt19937_64 rng(seed);  // raw engine output is fixed by the standard; Box-Muller below is ours
    auto u = [&] { return (double(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0); };
    NormalMap m;
    m.size = n;
    m.normals.resize(size_t(n) * n);
    for (auto& v : m.normals) {
        double r = std::sqrt(-2 * std::log(u())), p = 2 * kPiD * u();
        double z1 = r * std::cos(p), z2 = r * std::sin(p);
        double x = sx * z1, y = sy * (rho * z1 + std::sqrt(1 - rho * rho) * z2);
        glm::dvec3 nn(-x, -y, 1);
        v = Vec3(glm::normalize(nn));
    }
    return m;
}

struct DMoments {
    double x = 0, y = 0, xx = 0, yy = 0, xy = 0;
};
DMoments imageMean(const NormalMap& m) {
    DMoments d;
    for (const Vec3& n : m.normals) {
        LeanMoments t = leanTexelMoments(n);
        d.x += t.x, d.y += t.y, d.xx += t.xx, d.yy += t.yy, d.xy += t.xy;
    }
    double k = 1.0 / double(m.normals.size());
    d.x *= k, d.y *= k, d.xx *= k, d.yy *= k, d.xy *= k;
    return d;
}

// Plain Beckmann (Walter et al. 2007, Eqs. 25 and 27 with Heitz 2014's Λ), f·cos with height-correlated G2.
double beckmannD(const glm::dvec3& h, double a) {
    if (h.z <= 0) return 0;
    double c2 = h.z * h.z, t2 = (1 - c2) / c2;
    return std::exp(-t2 / (a * a)) / (kPiD * a * a * c2 * c2);
}
double beckmannLambda(const glm::dvec3& w, double a) {
    double t = std::sqrt(std::max(0.0, 1 - w.z * w.z)) / w.z;
    if (t == 0) return 0;
    double x = 1 / (a * t);
    return 0.5 * (std::erf(x) - 1) + std::exp(-x * x) / (2 * x * std::sqrt(kPiD));
}

Vec3 randomDir(std::mt19937& rng, float minZ) {
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (;;) {
        Vec3 v(2 * u(rng) - 1, 2 * u(rng) - 1, u(rng));
        float l = glm::length(v);
        if (l > 0.1f && l <= 1.f && v.z / l > minZ) return v / l;
    }
}

}  // namespace

// ---- moments and pyramids ------------------------------------------------------------------------------

TEST(LeanMoments, ConstantNormalMapHasZeroVarianceEverywhere) {
    NormalMap m;
    m.size = 40;
    m.normals.assign(40 * 40, glm::normalize(Vec3(0.3f, -0.2f, 1.f)));
    LeanPyramid P = LeanPyramid::fromNormalMap(m);
    ASSERT_EQ(P.levels(), 6);  // 40, 20, 10, 5, 2, 1
    for (int l = 0; l < P.levels(); ++l)
        for (int y = 0; y < P.level(l).height; ++y)
            for (int x = 0; x < P.level(l).width; ++x) {
                LeanStats s = leanStats(P.texel(l, x, y));
                EXPECT_NEAR(s.mean.x, -0.3f, 1e-6f);
                EXPECT_NEAR(s.mean.y, 0.2f, 1e-6f);
                EXPECT_LE(s.varX, 1e-7f);
                EXPECT_LE(s.varY, 1e-7f);
                EXPECT_LE(std::abs(s.covXY), 1e-7f);
            }
    LeanStats s = leanStats(P.lookup(Vec2(0.3f, 0.7f), Vec2(0.2f, 0.05f), Vec2(-0.01f, 0.04f), LeanFilter::Anisotropic));
    EXPECT_LE(s.varX + s.varY, 2e-7f);
}

TEST(LeanMoments, CoarsestLevelIsTheExactImageMean) {
    for (auto [kind, size] : {std::pair{NormalMapKind::Stone, 128}, std::pair{NormalMapKind::Flakes, 96},
                              std::pair{NormalMapKind::Brushed, 75}}) {
        NormalMap m = generateNormalMap(kind, size, 3);
        LeanPyramid P = LeanPyramid::fromNormalMap(m);
        const LeanLevel& top = P.level(P.levels() - 1);
        ASSERT_EQ(top.width, 1);
        ASSERT_EQ(top.height, 1);
        DMoments d = imageMean(m);
        LeanMoments t = P.texel(P.levels() - 1, 0, 0);
        // One float rounding of a double-accumulated mean: within 1 ulp-ish relative (plus an absolute floor).
        auto near = [](double got, double want) { return std::abs(got - want) <= 1.2e-7 * std::abs(want) + 1e-9; };
        EXPECT_TRUE(near(t.x, d.x)) << t.x << " vs " << d.x;
        EXPECT_TRUE(near(t.y, d.y)) << t.y << " vs " << d.y;
        EXPECT_TRUE(near(t.xx, d.xx)) << t.xx << " vs " << d.xx;
        EXPECT_TRUE(near(t.yy, d.yy)) << t.yy << " vs " << d.yy;
        EXPECT_TRUE(near(t.xy, d.xy)) << t.xy << " vs " << d.xy;
        // Every level has the same mean (exact box reduction, also for odd sizes such as 75 -> 37 -> 18 ...).
        for (int l = 0; l < P.levels(); ++l) {
            const LeanLevel& L = P.level(l);
            EXPECT_EQ(L.width, leanLevelSize(size, l));
            double sxx = 0;
            for (int i = 0; i < L.width * L.height; ++i) sxx += L.rgba[size_t(i) * 4 + 2];
            EXPECT_NEAR(sxx / (L.width * L.height), d.xx, 2e-6 * d.xx) << "level " << l;
        }
    }
}

TEST(LeanMoments, CovarianceIsPsdAtEveryLevel) {
    for (NormalMapKind k : allNormalMapKinds()) {
        LeanPyramid P = LeanPyramid::fromNormalMap(generateNormalMap(k, 64, 12));
        for (int l = 0; l < P.levels(); ++l)
            for (int y = 0; y < P.level(l).height; ++y)
                for (int x = 0; x < P.level(l).width; ++x) {
                    LeanMoments t = P.texel(l, x, y);
                    // Raw (unprojected) covariance from the stored floats: PSD up to float rounding of the moments.
                    double vx = double(t.xx) - double(t.x) * t.x, vy = double(t.yy) - double(t.y) * t.y;
                    double c = double(t.xy) - double(t.x) * t.y;
                    double eps = 4e-7 * (t.xx + t.yy) + 1e-12;
                    ASSERT_GE(vx, -eps) << normalMapKindName(k) << " level " << l;
                    ASSERT_GE(vy, -eps);
                    ASSERT_GE(vx * vy - c * c, -eps * (t.xx + t.yy)) << normalMapKindName(k) << " level " << l;
                    // The projected statistics are PSD exactly.
                    LeanStats s = leanStats(t);
                    ASSERT_GE(s.varX, 0.f);
                    ASSERT_LE(s.covXY * s.covXY, s.varX * s.varY * (1 + 1e-6f));
                    ASSERT_LE(std::abs(s.rho), 1.f);
                }
    }
}

TEST(LeanMoments, ZeroFootprintLookupReproducesTheTexel) {
    NormalMap m = generateNormalMap(NormalMapKind::Flakes, 64, 4);
    LeanPyramid P = LeanPyramid::fromNormalMap(m);
    for (LeanFilter f : {LeanFilter::None, LeanFilter::Trilinear, LeanFilter::Anisotropic})
        for (int y = 0; y < 64; y += 7)
            for (int x = 0; x < 64; x += 5) {
                Vec2 uv((x + 0.5f) / 64, (y + 0.5f) / 64);  // texel (x, y), y = 0 the bottom row
                LeanMoments a = P.lookup(uv, Vec2(0.f), Vec2(0.f), f), t = P.texel(0, x, y);
                ASSERT_EQ(a.x, t.x);
                ASSERT_EQ(a.y, t.y);
                ASSERT_EQ(a.xx, t.xx);
                ASSERT_EQ(a.yy, t.yy);
                ASSERT_EQ(a.xy, t.xy);
                // And the texel is the map's normal: the generator's row y counts from the top.
                Vec3 n = m.at(x, 63 - y);
                ASSERT_NEAR(t.x, -n.x / n.z, 1e-6f);
                ASSERT_NEAR(t.y, -n.y / n.z, 1e-6f);
            }
    // A footprint smaller than a texel (λ < 0) stays on level 0.
    LeanMoments a = P.lookup(Vec2(10.5f / 64, 20.5f / 64), Vec2(0.3f / 64, 0), Vec2(0, 0.3f / 64), LeanFilter::Trilinear);
    EXPECT_EQ(a.xx, P.texel(0, 10, 20).xx);
}

TEST(LeanMoments, FootprintSelectsTheMatchingLevel) {
    LeanPyramid P = LeanPyramid::fromNormalMap(generateNormalMap(NormalMapKind::Bumps, 128, 6));
    for (int l = 1; l < P.levels(); ++l) {
        const int w = P.level(l).width;
        float d = float(1 << l) / 128.f;  // one level-l texel per pixel: λ = l exactly
        Vec2 uv((3 % w + 0.5f) / w, (5 % w + 0.5f) / w);
        LeanMoments a = P.lookup(uv, Vec2(d, 0), Vec2(0, d), LeanFilter::Trilinear);
        LeanMoments b = P.lookup(uv, Vec2(d, 0), Vec2(0, d), LeanFilter::Anisotropic);
        LeanMoments t = P.texel(l, 3 % w, 5 % w);
        EXPECT_NEAR(a.xx, t.xx, 1e-6f * t.xx) << "level " << l;
        EXPECT_NEAR(b.xx, t.xx, 1e-6f * t.xx) << "level " << l;  // isotropic footprint: one probe
    }
    // Anisotropic 4:1 footprint along u: 4 probes at λ = log2(16/4) = 2, spaced one level-2 texel apart.
    Vec2 uv(17.f / 128, 33.f / 128);
    LeanMoments an = P.lookup(uv, Vec2(16.f / 128, 0), Vec2(0, 4.f / 128), LeanFilter::Anisotropic);
    LeanMoments want;
    for (int i = 0; i < 4; ++i) want += P.trilinear(2.f, uv + Vec2(16.f / 128, 0) * ((i + 0.5f) / 4 - 0.5f)) * 0.25f;
    EXPECT_FLOAT_EQ(an.xx, want.xx);
    EXPECT_FLOAT_EQ(an.xy, want.xy);
    // Trilinear over-blurs: λ = log2(16) = 4, so its variance is at least the anisotropic one's (on average).
    double vt = 0, va = 0;
    for (int i = 0; i < 200; ++i) {
        Vec2 q((i * 37 % 128 + 0.25f) / 128, (i * 91 % 128 + 0.75f) / 128);
        LeanStats st = leanStats(P.lookup(q, Vec2(16.f / 128, 0), Vec2(0, 4.f / 128), LeanFilter::Trilinear));
        LeanStats sa = leanStats(P.lookup(q, Vec2(16.f / 128, 0), Vec2(0, 4.f / 128), LeanFilter::Anisotropic));
        vt += st.varX + st.varY, va += sa.varX + sa.varY;
    }
    EXPECT_GT(vt, va);
}

TEST(LeanMoments, RecoversKnownCorrelation) {
    for (double rho : {-0.8, 0.0, 0.6}) {
        NormalMap m = correlatedMap(256, 0.3, 0.12, rho, 99);
        LeanPyramid P = LeanPyramid::fromNormalMap(m);
        LeanStats s = leanStats(P.texel(P.levels() - 1, 0, 0));
        // 65536 iid samples: sampling error of ρ ~ (1-ρ²)/256 < 0.004, of σ ~ 0.3%.
        EXPECT_NEAR(s.rho, rho, 0.012) << "rho " << rho;
        EXPECT_NEAR(s.sigmaX, 0.3, 0.006);
        EXPECT_NEAR(s.sigmaY, 0.12, 0.0025);
        // Also from a mid-level footprint lookup (16x16 texels per pixel, averaged over the tile).
        double c = 0;
        for (int i = 0; i < 64; ++i) {
            Vec2 uv((i % 8 + 0.5f) / 8, (i / 8 + 0.5f) / 8);
            c += leanStats(P.lookup(uv, Vec2(32.f / 256, 0), Vec2(0, 32.f / 256), LeanFilter::Trilinear)).rho;
        }
        EXPECT_NEAR(c / 64, rho, 0.03) << "rho " << rho;
        LeanStats d = leanStats(P.texel(P.levels() - 1, 0, 0), 1.f, false, true);
        EXPECT_EQ(d.rho, 0.f);
        EXPECT_EQ(d.covXY, 0.f);
    }
    // The brushed generator's correlation is what the pyramid reports at the top.
    NormalMap b = generateNormalMap(NormalMapKind::Brushed, 128, 1);
    LeanPyramid P = LeanPyramid::fromNormalMap(b);
    EXPECT_NEAR(leanStats(P.texel(P.levels() - 1, 0, 0)).rho, slopeStats(b).rho(), 1e-4);
}

TEST(LeanMoments, StrengthAndHandednessTransformTheStatistics) {
    LeanMoments m{0.1f, -0.2f, 0.05f, 0.09f, -0.01f};
    LeanStats a = leanStats(m), b = leanStats(m, 2.f), c = leanStats(m, 1.f, true);
    EXPECT_FLOAT_EQ(b.mean.x, 2 * a.mean.x);
    EXPECT_FLOAT_EQ(b.varX, 4 * a.varX);
    EXPECT_FLOAT_EQ(b.covXY, 4 * a.covXY);
    EXPECT_FLOAT_EQ(b.rho, a.rho);
    EXPECT_FLOAT_EQ(c.mean.y, -a.mean.y);
    EXPECT_FLOAT_EQ(c.covXY, -a.covXY);
    EXPECT_FLOAT_EQ(c.varY, a.varY);
    // E[x²] − E[x]² etc. (Olano & Baker 2010): 0.05 − 0.01, 0.09 − 0.04, −0.01 + 0.02.
    EXPECT_NEAR(a.varX, 0.04f, 1e-7f);
    EXPECT_NEAR(a.varY, 0.05f, 1e-7f);
    EXPECT_NEAR(a.covXY, 0.01f, 1e-7f);
    EXPECT_NEAR(a.rho, 0.01f / std::sqrt(0.04f * 0.05f), 1e-6f);
    Vec3 n = a.meanNormal();
    EXPECT_NEAR(-n.x / n.z, 0.1f, 1e-6f);
    EXPECT_NEAR(-n.y / n.z, -0.2f, 1e-6f);
}

TEST(LeanMoments, MemoryIsFiveFloatsPerTexelPlusTheChain) {
    LeanPyramid P = LeanPyramid::fromNormalMap(generateNormalMap(NormalMapKind::Bumps, 256, 1));
    EXPECT_EQ(P.baseBytes(), size_t(256 * 256 * 20));
    size_t texels = 0;
    for (int l = 0; l < P.levels(); ++l) texels += size_t(P.level(l).width) * P.level(l).height;
    EXPECT_EQ(texels, size_t(87381));  // (4^9 - 1)/3
    EXPECT_EQ(P.memoryBytes(), texels * 20);
}

// ---- Beckmann-LEAN lobe --------------------------------------------------------------------------------

TEST(BeckmannLean, ZeroCovarianceEqualsClosedFormBeckmann) {
    std::mt19937 rng(5);
    double worst = 0;
    for (float alpha : {0.05f, 0.2f, 0.5f, 1.0f}) {
        lean::SlopeGaussian g = lean::makeSlopeGaussian(Vec2(0.f), Vec3(0.f), alpha);
        BeckmannLeanLobe lobe(g, Fresnel::one());
        for (int i = 0; i < 2000; ++i) {
            Vec3 wo = randomDir(rng, 0.05f), wi = randomDir(rng, 0.05f);
            if (i % 3 == 0) {  // near-specular pairs so that D is large
                Vec3 h = glm::normalize(Vec3(0, 0, 1) + alpha * 0.7f * (randomDir(rng, 0.f) - Vec3(0, 0, 1)));
                wi = 2.f * glm::dot(wo, h) * h - wo;
                if (wi.z <= 0.05f) continue;
            }
            glm::dvec3 o(wo), in(wi), h = glm::normalize(o + in);
            double want = beckmannD(h, alpha) / (1 + beckmannLambda(o, alpha) + beckmannLambda(in, alpha)) / (4 * o.z);
            double got = lobe.eval(wo, wi).x;
            if (want < 1e-30) continue;
            worst = std::max(worst, std::abs(got - want) / want);
        }
    }
    std::printf("  max relative difference to closed-form Beckmann: %.3g\n", worst);
    EXPECT_LT(worst, 2e-4);
}

TEST(BeckmannLean, ProjectedNdfIntegratesToOne) {
    // ∫ D(h) cos θh dω = 1 for non-centred, correlated lobes (midpoint rule in (θ, φ), 1500 x 1500).
    struct Case {
        Vec2 mean;
        Vec3 cov;
        float alpha;
    };
    for (const Case& c : {Case{{0.f, 0.f}, {0.f, 0.f, 0.f}, 0.3f}, Case{{0.15f, -0.1f}, {0.02f, 0.006f, -0.009f}, 0.05f},
                          Case{{-0.3f, 0.2f}, {0.08f, 0.01f, 0.02f}, 0.2f}}) {
        lean::SlopeGaussian g = lean::makeSlopeGaussian(c.mean, c.cov, c.alpha);
        const int n = 1500;
        double sum = 0;
        for (int i = 0; i < n; ++i) {
            double th = (i + 0.5) / n * kPiD / 2, st = std::sin(th), ct = std::cos(th);
            for (int j = 0; j < n; ++j) {
                double ph = (j + 0.5) / n * 2 * kPiD;
                Vec3 h(float(st * std::cos(ph)), float(st * std::sin(ph)), float(ct));
                sum += lean::ndf(g, h) * ct * st;
            }
        }
        sum *= (kPiD / 2 / n) * (2 * kPiD / n);
        std::printf("  ∫D cos = %.5f (mean %.2f %.2f, alpha %.2f)\n", sum, c.mean.x, c.mean.y, c.alpha);
        EXPECT_NEAR(sum, 1.0, 0.02);
    }
}

TEST(BeckmannLean, SamplingMatchesPdfAndEnergyIsBounded) {
    lean::SlopeGaussian g = lean::makeSlopeGaussian(Vec2(0.12f, -0.05f), Vec3(0.03f, 0.01f, -0.012f), 0.15f);
    BeckmannLeanLobe lobe(g, Fresnel::one());
    const Vec3 wo = glm::normalize(Vec3(0.3f, 0.1f, 1.f));
    // Estimate ∫ f cos by importance sampling and by a hemisphere quadrature; each must agree and be <= 1.
    const int ns = 200000;
    double est = 0;
    for (int i = 0; i < ns; ++i) {
        Vec2 u((i + 0.5f) / ns, float((uint64_t(i) * 2654435769ULL % ns) + 0.5) / ns);
        Vec3 wi;
        if (!lobe.sample(wo, u, wi)) continue;
        float p = lobe.pdf(wo, wi);
        ASSERT_GT(p, 0.f);
        est += lobe.eval(wo, wi).x / p;
    }
    est /= ns;
    const int n = 800;
    double quad = 0, pdfInt = 0;
    for (int i = 0; i < n; ++i) {
        double th = (i + 0.5) / n * kPiD / 2, st = std::sin(th), ct = std::cos(th);
        for (int j = 0; j < n; ++j) {
            double ph = (j + 0.5) / n * 2 * kPiD;
            Vec3 wi(float(st * std::cos(ph)), float(st * std::sin(ph)), float(ct));
            quad += lobe.eval(wo, wi).x * st;
            pdfInt += lobe.pdf(wo, wi) * st;
        }
    }
    quad *= (kPiD / 2 / n) * (2 * kPiD / n);
    pdfInt *= (kPiD / 2 / n) * (2 * kPiD / n);
    std::printf("  albedo: sampled %.4f, quadrature %.4f, pdf mass %.4f\n", est, quad, pdfInt);
    EXPECT_NEAR(est, quad, 0.01);
    EXPECT_LE(quad, 1.0 + 1e-3);
    EXPECT_GT(quad, 0.85);
    EXPECT_LE(pdfInt, 1.0 + 1e-3);
}

TEST(BeckmannLean, SmithLambdaReducesToBeckmannAndGrowsTowardsTheMean) {
    for (float alpha : {0.1f, 0.4f, 0.9f})
        for (float z : {0.2f, 0.5f, 0.9f}) {
            Vec3 w(std::sqrt(1 - z * z), 0.f, z);
            lean::SlopeGaussian g = lean::makeSlopeGaussian(Vec2(0.f), Vec3(0.f), alpha);
            EXPECT_NEAR(lean::lambda(g, w), beckmannLambda(glm::dvec3(w), alpha), 2e-6 + 1e-5 * beckmannLambda(glm::dvec3(w), alpha));
        }
    // Facets tilted towards w (mean slope −x for w along +x: normals ∝ (0.3, 0, 1)) present more projected area
    // than cos θ, so the Smith normalisation G1 = cos θ / A⁺ masks more (Λ grows); tilted away, Λ shrinks.
    Vec3 w = glm::normalize(Vec3(1.f, 0.f, 0.6f));
    lean::SlopeGaussian c = lean::makeSlopeGaussian(Vec2(0.f), Vec3(0.f), 0.3f);
    lean::SlopeGaussian toward = lean::makeSlopeGaussian(Vec2(-0.3f, 0.f), Vec3(0.f), 0.3f);
    lean::SlopeGaussian away = lean::makeSlopeGaussian(Vec2(0.3f, 0.f), Vec3(0.f), 0.3f);
    EXPECT_GT(lean::lambda(toward, w), lean::lambda(c, w));
    EXPECT_LT(lean::lambda(away, w), lean::lambda(c, w));
}
