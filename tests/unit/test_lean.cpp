// Tests for LEAN mapping (core/texture/lean_moments, nodes/bsdf/beckmann_lean): exact moment pyramids, PSD
// covariances, footprint lookups, ρ recovery, and the Beckmann-LEAN lobe against closed-form Beckmann.
#include "core/texture/lean_moments.h"
#include "core/texture/normal_map_gen.h"
#include "nodes/bsdf/beckmann_lean/beckmann_lean.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
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

// ∫ f cos dωi by importance sampling the lobe with a fixed stratified sequence; 'zeroPdf' counts samples whose pdf is 0.
double sampledAlbedo(const BeckmannLeanLobe& lobe, const Vec3& wo, int ns, int* zeroPdf = nullptr) {
    double est = 0;
    for (int i = 0; i < ns; ++i) {
        Vec2 u((i + 0.5f) / ns, float((uint64_t(i) * 2654435769ULL % ns) + 0.5) / ns);
        Vec3 wi;
        if (!lobe.sample(wo, u, wi)) continue;
        float p = lobe.pdf(wo, wi);
        if (p > 0.f) est += lobe.eval(wo, wi).x / p;
        else if (zeroPdf) ++*zeroPdf;
    }
    return est / ns;
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
    // Non-finite and huge uvs (fuzz_scene: an infinite uv reached int(inf), undefined behaviour that UBSan aborts on)
    // read some texel of the map instead.
    const float inf = std::numeric_limits<float>::infinity();
    for (Vec2 uv : {Vec2(inf, 0.5f), Vec2(-inf, inf), Vec2(std::nanf(""), 0.2f), Vec2(3e9f, -3e9f)}) {
        LeanStats t = leanStats(P.bilinear(0, uv, LeanWrap::Repeat));
        EXPECT_NEAR(t.mean.x, -0.3f, 1e-6f);
    }
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

// A footprint within kGlAnisoRatioSlack of isotropic takes one probe: derivative sources that differ by rounding (the
// CPU's quad partners, a GPU's dFdx) must not flip a camera-facing surface between one probe at λ and two at λ − 1.
TEST(LeanMoments, NearIsotropicFootprintTakesOneProbe) {
    LeanPyramid P = LeanPyramid::fromNormalMap(generateNormalMap(NormalMapKind::Bumps, 128, 6));
    const float d = 5.3f / 128;
    double worst = 0, step = 0;
    for (int i = 0; i < 50; ++i) {
        Vec2 uv((i * 37 % 128 + 0.3f) / 128, (i * 91 % 128 + 0.6f) / 128);
        LeanMoments iso = P.lookup(uv, Vec2(d, 0), Vec2(0, d), LeanFilter::Anisotropic);
        for (float r : {1.f + 2e-4f, 1.f - 2e-4f, 1.f + 9e-4f}) {
            LeanMoments near = P.lookup(uv, Vec2(d, 0), Vec2(0, d * r), LeanFilter::Anisotropic);
            worst = std::max(worst, double(std::abs(near.xx - iso.xx) / iso.xx));
        }
        // Past the slack the EXT rule's step is back: two probes one level finer.
        LeanMoments two = P.lookup(uv, Vec2(d, 0), Vec2(0, d * 1.01f), LeanFilter::Anisotropic);
        step = std::max(step, double(std::abs(two.xx - iso.xx) / iso.xx));
    }
    EXPECT_LT(worst, 2e-3) << "a footprint 2e-4 from isotropic changed the filtered moments";
    EXPECT_GT(step, 1e-2) << "the 1 -> 2 probe step disappeared";
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
    int zeroPdf = 0;
    double est = sampledAlbedo(lobe, wo, 200000, &zeroPdf);
    ASSERT_EQ(zeroPdf, 0);
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

TEST(BeckmannLean, SmithLambdaReducesToBeckmannAndIsMeasuredAgainstTheMeanPlane) {
    for (float alpha : {0.1f, 0.4f, 0.9f})
        for (float z : {0.2f, 0.5f, 0.9f}) {
            Vec3 w(std::sqrt(1 - z * z), 0.f, z);
            lean::SlopeGaussian g = lean::makeSlopeGaussian(Vec2(0.f), Vec3(0.f), alpha);
            EXPECT_NEAR(lean::lambda(g, w), beckmannLambda(glm::dvec3(w), alpha), 2e-6 + 1e-5 * beckmannLambda(glm::dvec3(w), alpha));
        }
    // Facets tilted towards w (mean slope −x for w along +x: mean normal ∝ (0.3, 0, 1)) make w less grazing with
    // respect to the mean plane, so Λ shrinks; tilted away, w is more grazing and Λ grows.
    Vec3 w = glm::normalize(Vec3(1.f, 0.f, 0.6f));
    lean::SlopeGaussian c = lean::makeSlopeGaussian(Vec2(0.f), Vec3(0.f), 0.3f);
    lean::SlopeGaussian toward = lean::makeSlopeGaussian(Vec2(-0.3f, 0.f), Vec3(0.f), 0.3f);
    lean::SlopeGaussian away = lean::makeSlopeGaussian(Vec2(0.3f, 0.f), Vec3(0.f), 0.3f);
    EXPECT_LT(lean::lambda(toward, w), lean::lambda(c, w));
    EXPECT_GT(lean::lambda(away, w), lean::lambda(c, w));
    // A pure tilt of an isotropic Gaussian seen along the tilt axis' normal plane: for w ⟂ μ in xy, e(w) = wz and
    // the variance along wxy is the material's, so Λ equals plain Beckmann's.
    lean::SlopeGaussian side = lean::makeSlopeGaussian(Vec2(0.f, 0.3f), Vec3(0.f), 0.3f);
    EXPECT_NEAR(lean::lambda(side, w), beckmannLambda(glm::dvec3(w), 0.3), 1e-5);
}

// The closed-form Λ against a quadrature of the NDF itself: 1 + Λ(w) = ∫ (w·m)⁺ D(m) dω_m / e(w), and the signed
// projected area ∫ (w·m) D(m) dω_m is the mean plane's, e(w) = wz − wxy·μ (the identity Smith's G1 normalises to).
TEST(BeckmannLean, MaskingMatchesAQuadratureOfTheNdf) {
    struct C {
        Vec2 mean;
        Vec3 cov;
        float alpha;
        Vec3 w;
    };
    const C cases[] = {{Vec2(0.f), Vec3(0.f), 0.5f, glm::normalize(Vec3(0.8f, 0.1f, 0.5f))},
                       {Vec2(0.3f, -0.1f), Vec3(0.f), 0.5f, glm::normalize(Vec3(0.8f, 0.1f, 0.5f))},
                       {Vec2(-0.25f, 0.2f), Vec3(0.04f, 0.02f, 0.01f), 0.4f, glm::normalize(Vec3(-0.5f, 0.6f, 0.3f))},
                       {Vec2(0.4f, 0.f), Vec3(0.02f, 0.f, 0.f), 0.6f, glm::normalize(Vec3(1.f, 0.f, 0.45f))},  // e ≈ 0.05
                       {Vec2(0.1f, 0.1f), Vec3(0.01f, 0.03f, -0.01f), 0.3f, glm::normalize(Vec3(0.2f, -0.9f, 0.2f))}};
    const int n = 1000;
    for (const C& c : cases) {
        lean::SlopeGaussian g = lean::makeSlopeGaussian(c.mean, c.cov, c.alpha);
        double pos = 0, sgn = 0;
        for (int i = 0; i < n; ++i) {
            double th = (i + 0.5) / n * kPiD / 2, st = std::sin(th), ct = std::cos(th);
            for (int j = 0; j < 2 * n; ++j) {
                double ph = (j + 0.5) / (2 * n) * 2 * kPiD;
                glm::dvec3 m(st * std::cos(ph), st * std::sin(ph), ct);
                double d = lean::ndf(g, Vec3(m)) * st, wm = glm::dot(m, glm::dvec3(c.w));
                pos += std::max(wm, 0.0) * d, sgn += wm * d;
            }
        }
        const double dA = (kPiD / 2 / n) * (2 * kPiD / (2 * n));
        pos *= dA, sgn *= dA;
        double e = lean::meanPlaneCosine(g, c.w);
        double want = 1 + lean::lambda(g, c.w);
        std::printf("  mean (%.2f %.2f) w.z %.3f e %.4f: quadrature 1+Λ %.5f, closed form %.5f; signed area %.5f\n",
                    c.mean.x, c.mean.y, c.w.z, e, pos / e, want, sgn);
        EXPECT_NEAR(sgn, e, 2e-3);
        EXPECT_NEAR(pos / e, want, 3e-3 * want);
    }
}

// The grazing case: a viewer (or light) below the mean microsurface plane (e ≤ 0 while wz > 0) sees nothing, and G1
// goes to 0 continuously as the view approaches that plane from above (A⁺ → s φ(0) while e → 0).
TEST(BeckmannLean, ViewBelowTheMeanPlaneIsFullyMasked) {
    lean::SlopeGaussian g = lean::makeSlopeGaussian(Vec2(0.5f, 0.f), Vec3(0.01f, 0.01f, 0.f), 0.3f);
    // e(w) = wz − 0.5 wx: zero at θ = atan(2) ≈ 63.4° towards +x.
    const double th0 = std::atan(2.0);
    double prevG1 = 1;
    for (double dth : {-0.4, -0.2, -0.1, -0.03, -0.01, -0.001}) {
        double th = th0 + dth;
        Vec3 w(float(std::sin(th)), 0.f, float(std::cos(th)));
        double e = lean::meanPlaneCosine(g, w), g1 = 1 / (1 + double(lean::lambda(g, w)));
        double s = std::sqrt(double(w.x) * w.x * g.a);
        EXPECT_LT(g1, prevG1) << "G1 must fall towards the mean plane";
        EXPECT_LE(g1, e / (0.3989422804 * s) * 1.0001) << "G1 = e / A⁺ with A⁺ ≥ s φ(0)";
        prevG1 = g1;
    }
    EXPECT_LT(prevG1, 0.02);
    BeckmannLeanLobe lobe(g, Fresnel::one());
    const Vec3 wi = glm::normalize(Vec3(-0.3f, 0.1f, 1.f));
    for (double dth : {0.001, 0.05, 0.3}) {
        double th = th0 + dth;
        Vec3 w(float(std::sin(th)), 0.f, float(std::cos(th)));  // above the geometric plane, below the mean plane
        ASSERT_GT(w.z, 0.f);
        EXPECT_LE(lean::meanPlaneCosine(g, w), 0.f);
        EXPECT_GE(lean::lambda(g, w), 1e29f);
        EXPECT_EQ(lobe.eval(w, wi), Color3(0.f)) << "viewer below the mean plane";
        EXPECT_EQ(lobe.eval(wi, w), Color3(0.f)) << "light below the mean plane";
    }
}

// A tilted mirror (Σ = 0, α → 0, mean slope μ) reflects all it receives (albedo → 1 with F = 1) for a view well
// above its mean plane, as the same mirror shaded in its own frame does; the lobe is reciprocal in the mean-plane
// measure f·cos(wo, wi) / e(wi).
TEST(BeckmannLean, TiltedMirrorKeepsItsRadianceAndIsReciprocalOverTheMeanPlane) {
    lean::SlopeGaussian g = lean::makeSlopeGaussian(Vec2(0.3f, -0.2f), Vec3(0.f), 0.02f);
    BeckmannLeanLobe lobe(g, Fresnel::one());
    for (Vec3 wo : {glm::normalize(Vec3(0.2f, 0.1f, 1.f)), glm::normalize(Vec3(-0.6f, 0.3f, 1.f))}) {
        double est = sampledAlbedo(lobe, wo, 100000);
        std::printf("  tilted mirror, wo.z %.3f, e(wo) %.3f: albedo %.4f\n", wo.z, lean::meanPlaneCosine(g, wo), est);
        EXPECT_NEAR(est, 1.0, 0.01);
    }
    std::mt19937 rng(5);
    lean::SlopeGaussian rough = lean::makeSlopeGaussian(Vec2(0.3f, -0.2f), Vec3(0.02f, 0.01f, 0.005f), 0.3f);
    BeckmannLeanLobe rl(rough, Fresnel::one());
    for (int k = 0; k < 200; ++k) {
        Vec3 a = randomDir(rng, 0.05f), b = randomDir(rng, 0.05f);
        double ea = lean::meanPlaneCosine(rough, a), eb = lean::meanPlaneCosine(rough, b);
        if (ea <= 0 || eb <= 0) continue;
        double x = rl.eval(a, b).x / eb, y = rl.eval(b, a).x / ea;
        EXPECT_NEAR(x, y, 1e-4 * std::max(x, y) + 1e-9);
    }
}
