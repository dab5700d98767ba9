// Glint BRDF (nodes/bsdf/glint): the testable properties of spec glint-brdf.md §4, items 1-10, with the spec's
// tolerances, plus sampling/pdf consistency. Reference values are analytic or independent quadrature/Monte Carlo.
#include "nodes/bsdf/glint/glint_bsdf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <thread>

using namespace specula;
using namespace specula::glint;

namespace {

const Dictionary& dict() { return Dictionary::instance(); }

constexpr double kSo = kSigmaO;
constexpr double kPiD = 3.14159265358979323846;

// ∫_0^{4σo} x^n p(x) dx of the mirrored, linearly interpolated row (midpoint rule, 64 sub-steps per texel).
double rowMoment(const float* row, int n) {
    const int steps = kRes * 64;
    double s = 0;
    for (int i = 0; i < steps; ++i) {
        double u = (i + 0.5) / steps;
        double x = u * 4.0 * kSo;
        s += std::pow(x, n) * sampleLinear(row, kRes, float(u));
    }
    return s * 4.0 * kSo / steps;
}

// L1 distance of the (mirrored) row to N(0, σo² + σl²), over the whole line (tail beyond 4σo included).
double rowL1(const float* row) {
    const double s2 = kSo * kSo + kSigmaL * kSigmaL;
    const int steps = kRes * 64;
    double l1 = 0;
    for (int i = 0; i < steps; ++i) {
        double u = (i + 0.5) / steps, x = u * 4.0 * kSo;
        double g = std::exp(-x * x / (2 * s2)) / std::sqrt(2 * kPiD * s2);
        l1 += std::abs(sampleLinear(row, kRes, float(u)) - g);
    }
    l1 *= 2.0 * 4.0 * kSo / steps;
    l1 += std::erfc(4.0 * kSo / std::sqrt(2 * s2));  // truncated tail mass
    return l1;
}

// ---- 1. Dictionary normalisation --------------------------------------------------------------------------
TEST(GlintDictionary, EveryRowAndMipIsNormalisedAndNonNegative) {
    const Dictionary& d = dict();
    double worst = 0, worstTop = 0;
    for (int k = 0; k < kLevels; ++k)
        for (int m = 0; m < kMarginals; ++m)
            for (int mip = 0; mip < kMips; ++mip) {
                const float* t = d.mip(k, m, mip);
                double s = 0;
                for (int i = 0; i < mipRes(mip); ++i) {
                    ASSERT_GE(t[i], 0.f);
                    s += t[i];
                }
                const double delta = kDelta * (1 << mip);
                worst = std::max(worst, std::abs(2.0 * delta * s - 1.0));
                if (mip == kMips - 1) worstTop = std::max(worstTop, std::abs(double(t[0]) - 1.0 / (8.0 * kSo)));
            }
    std::printf("dictionary: max |2 Δ Σp - 1| = %.3g, max |top - 1/(8σo)| = %.3g, %s in %.2f s, %zu B (float32, all MIPs)\n",
                worst, worstTop, d.fromCache() ? "cache" : "generated", d.generationSeconds(), d.bytesCpu());
    EXPECT_LT(worst, 1e-6);
    EXPECT_LT(worstTop, 1e-6);
}

// The cumulative tables: the CDF matches midpoint quadrature of the interpolated row, ends at 1/2, and sampling
// inverts it (the mass below the sampled x is the requested fraction).
TEST(GlintDictionary, MarginalCdfIntegratesTheRowAndSamplingInvertsIt) {
    const Dictionary& d = dict();
    double worstCdf = 0, worstEnd = 0, worstInv = 0;
    const float lim = float(4.0 * kSo);
    for (int k : {0, 3, 8, 15})
        for (int m : {0, 17, 101, 191}) {
            const float* row = d.row(k, m);
            const int steps = kRes * 32;
            double acc = 0;
            for (int i = 0; i < steps; ++i) {
                const double u0 = double(i) / steps, u1 = double(i + 1) / steps;
                acc += sampleLinear(row, kRes, float(0.5 * (u0 + u1))) * (u1 - u0) * lim;
                if (i % 37 == 0) {
                    const float x = float(u1 * lim);
                    worstCdf = std::max(worstCdf, std::abs(double(d.marginalCdf(k, m, x)) - acc));
                    EXPECT_EQ(d.marginalCdf(k, m, -x), -d.marginalCdf(k, m, x));
                }
            }
            worstEnd = std::max(worstEnd, std::abs(double(d.marginalCdf(k, m, 2.f * lim)) - 0.5));
            for (float u : {0.001f, 0.1f, 0.37f, 0.5f, 0.73f, 0.999f}) {
                const float x = d.sampleMarginal(k, m, u);
                ASSERT_GE(x, 0.f);
                ASSERT_LE(x, lim);
                worstInv = std::max(worstInv, std::abs(2.0 * d.marginalCdf(k, m, x) - u));
            }
        }
    std::printf("marginal CDF: max |cdf - quadrature| = %.3g, max |cdf(end) - 1/2| = %.3g, max |2 cdf(sample(u)) - u| = %.3g\n",
                worstCdf, worstEnd, worstInv);
    EXPECT_LT(worstCdf, 2e-4);  // midpoint rule on the level-0 spikes (sigma_l = 0.9 texel) errs by ~1e-5
    EXPECT_LT(worstEnd, 1e-6);
    EXPECT_LT(worstInv, 1e-5);
}

TEST(GlintDictionary, MemoryFigures) {
    EXPECT_EQ(Dictionary::bytesBaseRgb16f(), 393216u);                 // 384 KiB, spec §2.2
    EXPECT_EQ(Dictionary::bytesChainRgb16f(), 780288u);                // 127/64 of base: the real 1D chain
    EXPECT_EQ(dict().bytesCpu(), size_t(kLevels) * kMarginals * 127 * 4);  // 1,560,576 B float32
}

// ---- 2. Dictionary statistics -------------------------------------------------------------------------------
TEST(GlintDictionary, StatisticsFollowTheMonteCarloLaw) {
    const Dictionary& d = dict();
    const double target = std::sqrt(kSo * kSo + kSigmaL * kSigmaL);  // 0.354118
    double maxStdErr = 0, maxL1_15 = 0, meanL1[kLevels] = {};
    for (int m = 0; m < kMarginals; ++m) {
        const double var = 2.0 * rowMoment(d.row(15, m), 2);
        maxStdErr = std::max(maxStdErr, std::abs(std::sqrt(var) / target - 1.0));
        for (int k : {8, 12, 15}) {
            double l1 = rowL1(d.row(k, m));
            meanL1[k] += l1 / kMarginals;
            if (k == 15) maxL1_15 = std::max(maxL1_15, l1);
        }
    }
    const double ratio = meanL1[8] / meanL1[12];
    std::printf("level 15: max std error %.4f, max L1 %.4f; mean L1 at 8/12/15: %.4f %.4f %.4f; ratio 8/12 = %.2f\n",
                maxStdErr, maxL1_15, meanL1[8], meanL1[12], meanL1[15], ratio);
    EXPECT_LT(maxStdErr, 0.02);
    EXPECT_LE(maxL1_15, 0.04);
    EXPECT_GE(ratio, 2.5);
    EXPECT_LE(ratio, 6.0);
}

TEST(GlintDictionary, LevelZeroIsOneMirroredLobePair) {
    const Dictionary& d = dict();
    const double peak = 1.0 / (2.0 * kSigmaL * std::sqrt(2.0 * kPiD));  // 9.97
    int tested = 0;
    for (int m = 0; m < kMarginals; ++m) {
        const double mu = std::abs(dictionaryMeans(m, 1)[0]);
        if (mu <= 4 * kSigmaL || mu >= 4 * kSo - 4 * kSigmaL) continue;
        const float* row = d.row(0, m);
        float mx = *std::max_element(row, row + kRes);
        EXPECT_GE(mx, 0.85 * peak) << m;
        EXPECT_LE(mx, 1.0 * peak) << m;
        // The maximum sits at the texel nearest to |mu| (a single lobe).
        int arg = int(std::max_element(row, row + kRes) - row);
        EXPECT_LE(std::abs((arg + 0.5) * kDelta - mu), 0.5 * kDelta + 1e-9) << m;
        ++tested;
    }
    EXPECT_GT(tested, 150);
}

TEST(GlintDictionary, NormalDeviatesAreStandard) {
    NormalStream ns(42);
    double s = 0, s2 = 0, s4 = 0;
    const int n = 400000;
    for (int i = 0; i < n; ++i) {
        double z = ns.next();
        s += z, s2 += z * z, s4 += z * z * z * z;
    }
    EXPECT_NEAR(s / n, 0.0, 5.0 / std::sqrt(n));
    EXPECT_NEAR(s2 / n, 1.0, 5.0 * std::sqrt(2.0 / n));
    EXPECT_NEAR(s4 / n, 3.0, 5.0 * std::sqrt(96.0 / n));
}

// ---- 3. Determinism -------------------------------------------------------------------------------------------
TEST(GlintDictionary, GenerationIsDeterministicWithGoldenHash) {
    Dictionary a = Dictionary::generate();
    EXPECT_EQ(0, std::memcmp(a.data().data(), dict().data().data(), a.bytesCpu()));
    std::printf("dictionary hash 0x%016llx (generated in %.2f s)\n", (unsigned long long)a.hash(), a.generationSeconds());
    EXPECT_EQ(a.hash(), 0xd5af54e6810c46b7ULL) << "golden hash of the float32 table (Debian 12 glibc libm)";
}

TEST(GlintCell, SeedIsCoherentAcrossLevels) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> di(-100000, 100000);
    for (int n = 0; n < 1000; ++n) {
        int l = n % kLevels, s = di(rng), t = di(rng);
        EXPECT_EQ(cellSeed(l, s, t), cellSeed(0, int(uint32_t(s) << l), int(uint32_t(t) << l)));
    }
}

TEST(GlintCell, CellSdfIsBitIdenticalAcrossCallsThreadsAndFootprints) {
    GlintParams p;
    p.logDensity = 27.f;
    GlintShape shape = GlintShape::make(0.2f, 0.3f, 0.4f);
    Vec3 h = glm::normalize(Vec3(0.05f, -0.03f, 1.f));
    SdfQuery q = makeQuery(dict(), p, shape, h, Vec2(0.01f, 0.02f), Vec2(-0.02f, 0.01f));
    auto run = [&](std::vector<float>& out) {
        out.clear();
        for (int l = 0; l < kLevels; ++l)
            for (int s = -20; s < 20; ++s)
                for (int t = -5; t < 5; ++t) out.push_back(cellSdf(q, l, s, t));
    };
    std::vector<float> a, b, c;
    run(a);
    std::thread th([&] { run(b); });
    th.join();
    run(c);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * 4));
    EXPECT_EQ(0, std::memcmp(a.data(), c.data(), a.size() * 4));
    // Footprint independence: the level SDF of a single-cell footprint equals the cell value.
    int nonzero = 0;
    for (float v : a) nonzero += v > 0.f;
    EXPECT_GT(nonzero, 0);
}

// ---- 4. Matrix identities (C21 Eqs. 16-18), double precision ----------------------------------------------------
struct M2 {
    double a, b, c, d;  // [[a b][c d]]
    M2 operator*(const M2& o) const { return {a * o.a + b * o.c, a * o.b + b * o.d, c * o.a + d * o.c, c * o.b + d * o.d}; }
    M2 T() const { return {a, c, b, d}; }
};

TEST(GlintMatrix, CovarianceDeterminantAndRotationIdentities) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> us(0.01, 1.0), ur(-0.99, 0.99), ua(0, 2 * kPiD);
    double worstCov = 0, worstPdf = 0, worstRot = 0, worstFloat = 0;
    for (int n = 0; n < 2000; ++n) {
        double sx = us(rng), sy = us(rng), rho = ur(rng), q = std::sqrt(1 - rho * rho);
        M2 M{sx * q / kSo, rho * sx / kSo, 0, sy / kSo};
        M2 So{kSo * kSo, 0, 0, kSo * kSo};
        M2 Sigma{sx * sx, rho * sx * sy, rho * sx * sy, sy * sy};
        M2 C = M * So * M.T();
        worstCov = std::max({worstCov, std::abs(C.a - Sigma.a), std::abs(C.b - Sigma.b), std::abs(C.d - Sigma.d)});
        double th = ua(rng);
        M2 R{std::cos(th), -std::sin(th), std::sin(th), std::cos(th)};
        M2 C2 = M * R * So * R.T() * M.T();
        worstRot = std::max({worstRot, std::abs(C2.a - Sigma.a), std::abs(C2.b - Sigma.b), std::abs(C2.d - Sigma.d)});
        // det(M^-1) φ_σo(M^-1 h) = P_B(h)
        M2 Mi{kSo / (sx * q), -kSo * rho / (sy * q), 0, kSo / sy};
        double detMi = kSo * kSo / (sx * sy * q);
        std::normal_distribution<double> nd(0, 1);
        double hx = 2 * sx * nd(rng), hy = 2 * sy * nd(rng);
        double mx = Mi.a * hx + Mi.b * hy, my = Mi.d * hy;
        double lhs = detMi * std::exp(-(mx * mx + my * my) / (2 * kSo * kSo)) / (2 * kPiD * kSo * kSo);
        double qq = (hx * hx / (sx * sx) - 2 * rho * hx * hy / (sx * sy) + hy * hy / (sy * sy)) / (1 - rho * rho);
        double rhs = std::exp(-qq / 2) / (2 * kPiD * sx * sy * q);
        worstPdf = std::max(worstPdf, std::abs(lhs / rhs - 1));
        // The float implementation (GlintShape + beckmannSdf) against the double truth.
        GlintShape s = GlintShape::make(float(sx), float(sy), float(rho));
        float pf = beckmannSdf(Vec2(float(hx), float(hy)), s);
        double sxf = s.sx, syf = s.sy, rf = s.rho;  // the same rounded inputs in double
        double qf = (hx * hx / (sxf * sxf) - 2 * rf * hx * hy / (sxf * syf) + hy * hy / (syf * syf)) / (1 - rf * rf);
        double pd = std::exp(-qf / 2) / (2 * kPiD * sxf * syf * std::sqrt(1 - rf * rf));
        if (qf < 30) worstFloat = std::max(worstFloat, std::abs(pf / pd - 1));
    }
    std::printf("matrix: cov %.3g, rotation %.3g, det·φ vs P_B %.3g, float P_B %.3g\n", worstCov, worstRot, worstPdf, worstFloat);
    EXPECT_LT(worstCov, 1e-12);
    EXPECT_LT(worstRot, 1e-12);
    EXPECT_LT(worstPdf, 1e-6);
    EXPECT_LT(worstFloat, 2e-5);
}

// ---- 5. Per-cell normalisation ---------------------------------------------------------------------------------
// ∫ P_cell dh~ = ∫ P_cell(M Rot(θ) m) |det M| dm (Jacobian of C21 Eq. 5), on a grid finer than σl in m space.
TEST(GlintCell, PerCellIntegralIsOne) {
    const struct {
        float sx, sy, rho;
    } shapes[] = {{0.1f, 0.25f, 0.f}, {0.3f, 0.15f, 0.7f}, {0.5f, 0.5f, -0.9f}};
    double worst = 0;
    int tested = 0;
    for (auto sh : shapes) {
        GlintParams p;
        p.jitter = 0.f;
        p.ggaa = false;
        for (int kd : {3, 9}) {
            p.logDensity = float(kd + 15) * 1.38629436f;  // l_c = kd at level 0
            GlintShape shape = GlintShape::make(sh.sx, sh.sy, sh.rho);
            for (int cell = 0; cell < 3; ++cell) {
                int s = 17 * cell + 3, t = -11 * cell + 5;
                CellRandom r = cellRandom(cellSeed(0, s, t));
                if (r.uA > p.relArea) continue;
                float th = 2.f * kPi * r.uTheta;
                const double M00 = sh.sx * shape.sq / kSo, M01 = shape.rho * sh.sx / kSo, M11 = sh.sy / kSo;
                const double detM = 1.0 / shape.detMinv;
                const int n = 800;
                const double lim = 4 * kSo, step = 2 * lim / n;
                double sum = 0;
                for (int a = 0; a < n; ++a)
                    for (int b = 0; b < n; ++b) {
                        double mx = -lim + (a + 0.5) * step, my = -lim + (b + 0.5) * step;
                        double rx = std::cos(th) * mx - std::sin(th) * my, ry = std::sin(th) * mx + std::cos(th) * my;
                        Vec2 hs(float(M00 * rx + M01 * ry), float(M11 * ry));
                        Vec3 h = glm::normalize(Vec3(-hs.x, -hs.y, 1.f));
                        SdfQuery q = makeQuery(dict(), p, shape, h, Vec2(0.f), Vec2(0.f));
                        q.hs = hs;
                        q.mh = shape.applyInv(hs);
                        sum += cellSdf(q, 0, s, t);
                    }
                double integral = sum * step * step * detM;
                worst = std::max(worst, std::abs(integral - 1));
                ++tested;
            }
        }
    }
    std::printf("per-cell normalisation: worst |∫P_cell - 1| = %.4f over %d cells\n", worst, tested);
    EXPECT_GT(tested, 10);
    EXPECT_LT(worst, 0.01);
}

// ---- 6. Patch normalisation ------------------------------------------------------------------------------------
// Independent re-implementation of the S3 weights, for the kept-weight fraction when A < 1.
double keptFraction(int l, Vec2 uv, Vec2 a1, Vec2 a2, float A) {
    double n = double(1 << (kLevels - 1 - l));
    double cs = uv.x * n - 0.5, ct = uv.y * n - 0.5;
    double b1x = a1.x * n, b1y = a1.y * n, b2x = a2.x * n, b2y = a2.y * n;
    double Aq = b1y * b1y + b2y * b2y + 1, Bq = -2 * (b1x * b1y + b2x * b2y), Cq = b1x * b1x + b2x * b2x + 1;
    double F = Aq * Cq - Bq * Bq / 4;
    Aq /= F, Bq /= F, Cq /= F;
    double sw = 0, kw = 0;
    for (int t = int(ct) - 40; t <= int(ct) + 40; ++t)
        for (int s = int(cs) - 40; s <= int(cs) + 40; ++s) {
            double ds = s - cs, dt = t - ct, r2 = Aq * ds * ds + Bq * ds * dt + Cq * dt * dt;
            if (r2 >= 1) continue;
            double W = std::exp(-2 * r2) - std::exp(-2.0);
            sw += W;
            if (cellRandom(cellSeed(l, s, t)).uA <= A) kw += W;
        }
    return kw / sw;
}

double patchIntegral(const GlintParams& p, Vec2 uv, const Footprint& fp, Vec2 dslope) {
    GlintShape shape = GlintShape::make(float(kSo), float(kSo), 0.f);  // M = I: lobes of width σl in h~
    const int n = 700;
    const double lim = 2.0, step = 2 * lim / n;
    double sum = 0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            Vec2 hs(float(-lim + (a + 0.5) * step), float(-lim + (b + 0.5) * step));
            Vec3 h = glm::normalize(Vec3(-hs.x, -hs.y, 1.f));
            SdfQuery q = makeQuery(dict(), p, shape, h, Vec2(0.f), Vec2(0.f));
            q.hs = hs;
            q.mh = shape.applyInv(hs);
            if (p.ggaa) {  // a fixed kernel: half-slope derivative dslope along x, dslope.yx along y
                const float k = p.kernelScale / float(4.0 * kSo);
                q.gx = shape.applyInv(dslope) * k;
                q.gy = shape.applyInv(Vec2(dslope.y, dslope.x)) * k;
            }
            sum += patchSdf(q, uv, fp);
        }
    return sum * step * step;
}

TEST(GlintPatch, PatchIntegralIsOneWithAndWithoutGgaa) {
    GlintParams p;
    p.logDensity = 20.f;
    const Vec2 uv(0.3127f, 0.7291f);
    const float cell = 1.f / 4096.f;  // level 3 cells
    Footprint fp = footprint(Vec2(1.3f * cell, 0.4f * cell), Vec2(-0.2f * cell, 1.1f * cell), 8.f);
    p.ggaa = false;
    double i0 = patchIntegral(p, uv, fp, Vec2(0.f));
    p.ggaa = true;
    p.kernelScale = 0.5f;
    double i1 = patchIntegral(p, uv, fp, Vec2(0.08f, 0.03f));
    p.kernelScale = 1.f;
    double i2 = patchIntegral(p, uv, fp, Vec2(0.08f, 0.03f));
    std::printf("patch integral: no GGAA %.4f, GGAA s_K 0.5 %.4f, s_K 1 %.4f (l_P = %.3f)\n", i0, i1, i2, fp.lodP);
    EXPECT_NEAR(i0, 1.0, 0.01);
    EXPECT_NEAR(i1, 1.0, 0.02);
    EXPECT_NEAR(i2, 1.0, 0.02);
}

TEST(GlintPatch, SparsePatchIntegralIsTheKeptWeightFraction) {
    GlintParams p;
    p.logDensity = 20.f;
    p.relArea = 0.4f;
    p.ggaa = false;
    const Vec2 uv(0.61f, 0.27f);
    const float cell = 1.f / 8192.f;  // level 2 exactly: w = 0
    Footprint fp = footprint(Vec2(8.f * cell, 0.f), Vec2(0.f, cell), 8.f);
    ASSERT_EQ(fp.lodP, 2.f);
    double expect = keptFraction(2, uv, fp.a1, fp.a2, p.relArea);
    double got = patchIntegral(p, uv, fp, Vec2(0.f));
    std::printf("sparse patch: ∫P = %.4f, kept-weight fraction %.4f\n", got, expect);
    EXPECT_GT(expect, 0.05);
    EXPECT_LT(expect, 0.95);
    EXPECT_NEAR(got, expect, 0.01);
}

TEST(GlintPatch, LimitNdfIntegratesToOneOverTheHemisphere) {
    GlintParams p;
    p.logDensity = 64.f;
    GlintShape shape = GlintShape::make(0.3f, 0.2f, 0.5f);
    Footprint fp = footprint(Vec2(1e-3f, 0.f), Vec2(0.f, 5e-4f), 8.f);
    const int nt = 600, np = 600;
    double sum = 0;
    for (int a = 0; a < nt; ++a)
        for (int b = 0; b < np; ++b) {
            double th = (a + 0.5) / nt * kPiD / 2, ph = (b + 0.5) / np * 2 * kPiD;
            Vec3 h(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th)));
            SdfQuery q = makeQuery(dict(), p, shape, h, Vec2(0.f), Vec2(0.f));
            double P = patchSdf(q, Vec2(0.4f, 0.6f), fp);
            double D = P / std::pow(double(h.z), 4);
            sum += D * std::cos(th) * std::sin(th);
        }
    double integral = sum * (kPiD / 2 / nt) * (2 * kPiD / np);
    std::printf("∫ D cos dω (limit) = %.5f\n", integral);
    EXPECT_NEAR(integral, 1.0, 0.01);
}

// ---- 7. Exact limit --------------------------------------------------------------------------------------------
TEST(GlintLimit, InfiniteDensityIsCookTorranceWithCorrelatedBeckmann) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    double worst = 0;
    int nonzero = 0;
    for (int n = 0; n < 4000; ++n) {
        GlintParams p;
        p.logDensity = 64.f;
        p.relArea = 1.f;
        p.sigmaX = 0.02f + 0.8f * u(rng);
        p.sigmaY = 0.02f + 0.8f * u(rng);
        p.rho = -0.95f + 1.9f * u(rng);
        p.ggaa = n % 2 == 0;
        p.mode = n % 4 < 2 ? DerivMode::ProjectedHalf : DerivMode::HalfSlope;
        GlintShape shape = GlintShape::make(p.sigmaX, p.sigmaY, p.rho);
        Vec3 wo = glm::normalize(Vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) + 0.05f));
        Vec3 wi = glm::normalize(Vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) + 0.05f));
        GlintEvalInputs in;
        in.uv = Vec2(u(rng) * 4.f - 2.f, u(rng) * 4.f - 2.f);
        float scale = std::exp2(-16.f * u(rng));
        in.duvdx = Vec2(u(rng) - 0.5f, u(rng) - 0.5f) * scale;
        in.duvdy = Vec2(u(rng) - 0.5f, u(rng) - 0.5f) * scale;
        in.diff.dnx = Vec2(u(rng) - 0.5f, u(rng) - 0.5f) * 0.1f;
        in.diff.dny = Vec2(u(rng) - 0.5f, u(rng) - 0.5f) * 0.1f;
        float g = glintFCosScalar(dict(), p, shape, in, wo, wi);
        float ref = beckmannFCosScalar(shape, wo, wi);
        if (ref > 1e-30f) {
            worst = std::max(worst, double(std::abs(g - ref) / ref));
            ++nonzero;
        } else {
            EXPECT_LT(g, 1e-29f);  // the reference underflowed
        }
    }
    std::printf("exact limit: worst relative error %.3g over %d configurations\n", worst, nonzero);
    EXPECT_GT(nonzero, 1000);
    EXPECT_LT(worst, 1e-5);
}

// ---- 8. Statistical convergence --------------------------------------------------------------------------------
TEST(GlintConvergence, AveragedLevel15CellsTendToTheWidenedBeckmannLobe) {
    GlintParams p;
    p.jitter = 0.f;
    p.ggaa = false;
    p.logDensity = 30.f * 1.38629436f;  // l_c = 15 at level 0: every cell uses dictionary level 15
    const float sx = 0.2f, sy = 0.12f, rho = 0.6f;
    GlintShape shape = GlintShape::make(sx, sy, rho);
    // Per-marginal variance of the level-15 rows (interpolant), exact in the table's terms.
    std::vector<double> var(kMarginals);
    for (int m = 0; m < kMarginals; ++m) var[m] = 2.0 * rowMoment(dict().row(15, m), 2);
    const int cells = 20000;
    double c00 = 0, c01 = 0, c11 = 0;
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> di(-1000000, 1000000);
    std::vector<std::pair<int, int>> ids;
    const double M00 = sx * shape.sq / kSo, M01 = rho * sx / kSo, M11 = sy / kSo;
    for (int n = 0; n < cells; ++n) {
        int s = di(rng), t = di(rng);
        ids.push_back({s, t});
        CellRandom r = cellRandom(cellSeed(0, s, t));
        ASSERT_EQ(int(std::floor(p.logDensity / 1.38629436f - 15.f + 0.5f)), 15);
        int i = std::min(int(kMarginals * r.uI), kMarginals - 1), j = std::min(int(kMarginals * r.uJ), kMarginals - 1);
        double th = 2 * kPiD * double(r.uTheta), c = std::cos(th), sn = std::sin(th);
        // cov = M R diag(v_i, v_j) R^T M^T
        double R00 = c, R01 = -sn, R10 = sn, R11 = c;
        double A00 = M00 * R00 + M01 * R10, A01 = M00 * R01 + M01 * R11, A10 = M11 * R10, A11 = M11 * R11;
        c00 += A00 * A00 * var[i] + A01 * A01 * var[j];
        c01 += A00 * A10 * var[i] + A01 * A11 * var[j];
        c11 += A10 * A10 * var[i] + A11 * A11 * var[j];
    }
    c00 /= cells, c01 /= cells, c11 /= cells;
    const double w = 1.0 + kSigmaL * kSigmaL / (kSo * kSo);
    std::printf("second moments / target: %.4f %.4f %.4f\n", c00 / (w * sx * sx), c01 / (w * rho * sx * sy), c11 / (w * sy * sy));
    EXPECT_NEAR(c00 / (w * sx * sx), 1.0, 0.03);
    EXPECT_NEAR(c11 / (w * sy * sy), 1.0, 0.03);
    EXPECT_NEAR(c01 / (w * rho * sx * sy), 1.0, 0.03);
    // Pointwise: the average of P_cell over the cells vs the widened P_B, |h~| < 2σ.
    GlintShape wide = GlintShape::make(float(sx * std::sqrt(w)), float(sy * std::sqrt(w)), rho);
    const float peak = beckmannSdf(Vec2(0.f), wide);
    double worst = 0;
    for (int a = -4; a <= 4; ++a)
        for (int b = -4; b <= 4; ++b) {
            Vec2 hs(0.5f * a * sx * 0.9f, 0.5f * b * sy * 0.9f);
            if (std::hypot(hs.x / sx, hs.y / sy) > 2.f) continue;
            Vec3 h = glm::normalize(Vec3(-hs.x, -hs.y, 1.f));
            SdfQuery q = makeQuery(dict(), p, shape, h, Vec2(0.f), Vec2(0.f));
            q.hs = hs;
            q.mh = shape.applyInv(hs);
            double avg = 0;
            for (auto [s, t] : ids) avg += cellSdf(q, 0, s, t);
            avg /= cells;
            worst = std::max(worst, std::abs(avg - beckmannSdf(hs, wide)) / peak);
        }
    std::printf("pointwise: worst |avg P_cell - P_B| / peak = %.4f\n", worst);
    EXPECT_LT(worst, 0.10);
}

// ---- 9. GGAA consistency ---------------------------------------------------------------------------------------
TEST(GlintGgaa, ZeroKernelScaleReproducesTheUnfilteredPath) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int nonzero = 0;
    for (int n = 0; n < 3000; ++n) {
        GlintParams p;
        p.logDensity = 10.f + 30.f * u(rng);
        p.sigmaX = 0.05f + 0.5f * u(rng);
        p.sigmaY = 0.05f + 0.5f * u(rng);
        p.rho = u(rng) - 0.5f;
        GlintShape shape = GlintShape::make(p.sigmaX, p.sigmaY, p.rho);
        Vec3 wo = glm::normalize(Vec3(u(rng) - 0.5f, u(rng) - 0.5f, 1.f));
        Vec3 wi = glm::normalize(Vec3(-wo.x + 0.3f * (u(rng) - 0.5f), -wo.y + 0.3f * (u(rng) - 0.5f), wo.z));
        GlintEvalInputs in;
        in.uv = Vec2(u(rng), u(rng));
        in.duvdx = Vec2(1e-3f * u(rng), 0.f);
        in.duvdy = Vec2(0.f, 1e-3f * u(rng));
        in.diff.dnx = Vec2(0.3f * u(rng), 0.f);
        in.diff.dny = Vec2(0.f, 0.3f * u(rng));
        p.ggaa = false;
        float a = glintFCosScalar(dict(), p, shape, in, wo, wi);
        p.ggaa = true;
        p.kernelScale = 0.f;
        float b = glintFCosScalar(dict(), p, shape, in, wo, wi);
        p.kernelScale = 0.5f;
        in.diff = GlintDifferentials{};
        float c = glintFCosScalar(dict(), p, shape, in, wo, wi);
        EXPECT_EQ(a, b);
        EXPECT_EQ(a, c);
        nonzero += a > 0.f;
    }
    EXPECT_GT(nonzero, 100);
}

TEST(GlintGgaa, FilteredMarginalKeepsMassLowersMaxAndIsSymmetric) {
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int n = 0; n < 200; ++n) {
        const float* row = dict().row(n % kLevels, (n * 37) % kMarginals);
        const float g = std::exp2(-7.f + 8.f * u(rng));  // from magnification to beyond the top MIP
        const float mx = *std::max_element(row, row + kRes);
        const int steps = 8192;
        double base = 0, filt = 0, fmax = 0;
        for (int i = 0; i < steps; ++i) {
            float x = (i + 0.5f) / steps;
            base += sampleLinear(row, kRes, x);
            float f = textureGrad1D(row, x, g, 0.3f * g);
            filt += f;
            fmax = std::max(fmax, double(f));
        }
        EXPECT_NEAR(filt / steps, base / steps, 1e-5 * base / steps + 1e-6);
        EXPECT_LE(fmax, mx * (1 + 1e-6));
        // Symmetry about 0 (mirrored repeat): f(-u) = f(u); at u = 0 and an integer MIP m the value is the
        // symmetric average of the base texels [0, 2^m).
        float x = 0.03f * u(rng);
        EXPECT_FLOAT_EQ(textureGrad1D(row, -x, g, 0.f), textureGrad1D(row, x, g, 0.f));
    }
    const float* row = dict().row(4, 17);
    for (int m = 1; m < kMips; ++m) {
        double avg = 0;
        for (int i = 0; i < (1 << m); ++i) avg += row[i];
        avg /= (1 << m);
        EXPECT_NEAR(textureGrad1D(row, 0.f, float(1 << m) / kRes, 0.f), avg, 1e-6 * avg + 1e-7) << m;
    }
    // A huge kernel returns the row mean 1/(8σo).
    for (int k = 0; k < kLevels; ++k)
        EXPECT_NEAR(textureGrad1D(dict().row(k, 5), 0.37f, 50.f, 1.f), 1.0 / (8.0 * kSo), 1e-6);
}

// The per-pixel half-vector derivative used by GGAA matches finite differences of a rotated frame.
TEST(GlintGgaa, HalfVectorDerivativeMatchesFiniteDifferences) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (int n = 0; n < 200; ++n) {
        Vec3 wo = glm::normalize(Vec3(u(rng), u(rng), 1.5f)), wi = glm::normalize(Vec3(u(rng), u(rng), 1.5f));
        Vec2 a(u(rng), u(rng));
        const double eps = 1e-4;
        // Frame n' = n + eps (a.x t + a.y b), tangent Gram-Schmidt; world = old local.
        DVec3 np = glm::normalize(DVec3(eps * a.x, eps * a.y, 1.0));
        DVec3 tp = glm::normalize(DVec3(1, 0, 0) - np * np.x);
        DVec3 bp = glm::cross(np, tp);
        auto loc = [&](Vec3 w) { DVec3 d(w); return DVec3(glm::dot(d, tp), glm::dot(d, bp), glm::dot(d, np)); };
        DVec3 h0 = glm::normalize(DVec3(wo) + DVec3(wi)), h1 = glm::normalize(loc(wo) + loc(wi));
        DVec3 fd = (h1 - h0) / eps;
        Vec3 hs = wo + wi;
        float len = glm::length(hs);
        Vec3 an = halfDerivative(hs / len, len, frameRotation(a, wo) + frameRotation(a, wi));
        EXPECT_NEAR(an.x, fd.x, 1e-3);
        EXPECT_NEAR(an.y, fd.y, 1e-3);
        EXPECT_NEAR(an.z, fd.z, 1e-3);
    }
}

// ---- 10. LOD --------------------------------------------------------------------------------------------------
TEST(GlintLod, MinorAxisSelectsTheLevelExactlyAndAnisotropyIsClamped) {
    for (int l = 0; l < kLevels; ++l) {
        float a2 = std::exp2(-float(kLevels - 1 - l));
        Footprint fp = footprint(Vec2(0.f, 2.f * a2), Vec2(a2, 0.f), 8.f);
        EXPECT_EQ(fp.lodP, float(l));
        EXPECT_EQ(fp.lodP - std::floor(fp.lodP), 0.f);
    }
    Footprint fp = footprint(Vec2(1e-2f, 0.f), Vec2(0.f, 1e-6f), 8.f);
    EXPECT_NEAR(glm::length(fp.a2), 1e-2f / 8.f, 1e-9f);
    EXPECT_NEAR(fp.lodP, 15.f + std::log2(1e-2f / 8.f), 1e-5f);
    fp = footprint(Vec2(1e-2f, 0.f), Vec2(0.f, 1e-6f), 4.f);
    EXPECT_NEAR(glm::length(fp.a2), 1e-2f / 4.f, 1e-9f);
    EXPECT_FALSE(footprint(Vec2(1e-2f, 0.f), Vec2(0.f), 8.f).valid);
}

TEST(GlintLod, PatchSdfIsContinuousInTheLod) {
    GlintParams p;
    p.logDensity = 40.f;
    p.ggaa = false;
    GlintShape shape = GlintShape::make(0.3f, 0.3f, 0.f);
    double worst = 0;
    int tested = 0;
    for (int l = 1; l < kLevels - 1; ++l)
        for (float frac : {0.f, 0.37f}) {
            for (int v = 0; v < 4; ++v) {
                Vec3 h = glm::normalize(Vec3(0.05f * v, -0.04f * v, 1.f));
                SdfQuery q = makeQuery(dict(), p, shape, h, Vec2(0.f), Vec2(0.f));
                Vec2 uv(0.123f + 0.1f * v, 0.456f);
                auto at = [&](float lod) {
                    float a2 = std::exp2(lod - float(kLevels - 1));
                    return patchSdf(q, uv, footprint(Vec2(3.f * a2, 0.f), Vec2(0.f, a2), 8.f));
                };
                float c = float(l) + frac;
                float lo = at(c - 5e-5f), hi = at(c + 5e-5f);
                if (!(lo > 0.f) || !(hi > 0.f)) continue;
                worst = std::max(worst, double(std::abs(hi - lo) / std::max(lo, hi)));
                ++tested;
            }
        }
    std::printf("LOD continuity: worst relative change %.3g over %d steps of 1e-4\n", worst, tested);
    EXPECT_GT(tested, 50);
    EXPECT_LT(worst, 1e-3);
}

// ---- the lobe: sampling pdf consistency and an independent Monte Carlo of the albedo ------------------------------
TEST(GlintLobe, SamplingMatchesItsPdfAndEstimatesTheAlbedo) {
    GlintParams p;
    p.logDensity = 18.f;
    p.sigmaX = 0.25f, p.sigmaY = 0.15f, p.rho = 0.4f;
    GlintEvalInputs in;
    in.uv = Vec2(0.3f, 0.4f);
    in.duvdx = Vec2(2e-3f, 0.f);
    in.duvdy = Vec2(0.f, 2e-3f);
    GlintLobe lobe(dict(), p, in, Fresnel::one());
    Vec3 wo = glm::normalize(Vec3(0.3f, -0.2f, 1.f));
    // (a) ∫ pdf dω (quadrature) = fraction of successful samples.
    const int nt = 400, np = 800;
    double ipdf = 0, ifcos = 0;
    for (int a = 0; a < nt; ++a)
        for (int b = 0; b < np; ++b) {
            double th = (a + 0.5) / nt * kPiD / 2, ph = (b + 0.5) / np * 2 * kPiD;
            Vec3 wi(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th)));
            double dw = std::sin(th) * (kPiD / 2 / nt) * (2 * kPiD / np);
            ipdf += lobe.pdf(wo, wi) * dw;
            ifcos += lobe.eval(wo, wi).x * dw;
        }
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    const int N = 400000;
    int ok = 0;
    double est = 0;
    for (int n = 0; n < N; ++n) {
        Vec3 wi;
        if (!lobe.sample(wo, Vec2(u(rng), u(rng)), wi)) continue;
        ++ok;
        float pdf = lobe.pdf(wo, wi);
        ASSERT_GT(pdf, 0.f);
        est += lobe.eval(wo, wi).x / pdf;
    }
    est /= N;
    std::printf("lobe: ∫pdf = %.4f vs accepted %.4f; ∫f cos: quadrature %.4f, importance MC %.4f\n", ipdf, double(ok) / N,
                ifcos, est);
    EXPECT_NEAR(ipdf, double(ok) / N, 0.01);
    EXPECT_NEAR(est, ifcos, 0.03 * ifcos);
    EXPECT_LE(ifcos, 1.02);
}

// ---- the per-shading-point cell set (issue 11 item 4) -------------------------------------------------------------
// The lobe's path (GlintCellSet: cells, random numbers and weights computed once, then one pass per query) against the
// per-query pipeline of spec §3 (patchSdf over cellSdf), over random materials, footprints, GGAA on/off, A < 1 and
// point-light distances.
TEST(GlintCells, CellSetEqualsThePerQueryPipeline) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    double worst = 0;
    int nonzero = 0;
    for (int n = 0; n < 6000; ++n) {
        GlintParams p;
        p.logDensity = 8.f + 40.f * u(rng);
        p.relArea = n % 3 == 0 ? 0.05f + 0.9f * u(rng) : 1.f;
        p.sigmaX = 0.03f + 0.5f * u(rng);
        p.sigmaY = 0.03f + 0.5f * u(rng);
        p.rho = 1.8f * (u(rng) - 0.5f);
        p.ggaa = n % 2 == 0;
        p.kernelScale = n % 4 == 0 ? 1.f : 0.5f;
        GlintShape shape = GlintShape::make(p.sigmaX, p.sigmaY, p.rho);
        Vec3 wo = glm::normalize(Vec3(u(rng) - 0.5f, u(rng) - 0.5f, 1.f));
        Vec3 wi = glm::normalize(Vec3(-wo.x + 0.6f * (u(rng) - 0.5f), -wo.y + 0.6f * (u(rng) - 0.5f), wo.z));
        GlintEvalInputs in;
        in.uv = Vec2(u(rng), u(rng));
        float s = std::exp2(-4.f - 10.f * u(rng));
        in.duvdx = Vec2(s, 0.3f * s * (u(rng) - 0.5f));
        in.duvdy = Vec2(0.3f * s * (u(rng) - 0.5f), s * (0.3f + u(rng)));
        in.diff.dnx = Vec2(0.05f * u(rng), 0.02f * (u(rng) - 0.5f));
        in.diff.dny = Vec2(0.02f * (u(rng) - 0.5f), 0.05f * u(rng));
        const float a = glintFCosCells(dict(), p, shape, in, wo, wi, n % 5 == 0 ? 2.f : std::numeric_limits<float>::infinity());
        const float b = glintFCosReference(dict(), p, shape, in, wo, wi, n % 5 == 0 ? 2.f : std::numeric_limits<float>::infinity());
        if (b > 1e-6f) ++nonzero;
        worst = std::max(worst, double(std::abs(a - b)) / std::max(double(b), 1e-6));
    }
    std::printf("cell set vs per-query pipeline: worst relative difference %.3g (%d nonzero)\n", worst, nonzero);
    EXPECT_GT(nonzero, 1500);
    // Bit-identical: the same terms summed in the same order (the skipped cells add exact zeros).
    EXPECT_EQ(worst, 0.0);
}

// The lobe answers every query of its shading point from one cell set: many queries on one lobe equal fresh
// single-query evaluations, in any order.
TEST(GlintCells, LobeCacheGivesTheSameAnswerForEveryQueryOrder) {
    GlintParams p;
    p.logDensity = 16.f;
    p.sigmaX = 0.2f, p.sigmaY = 0.12f, p.rho = 0.3f;
    GlintEvalInputs in;
    in.uv = Vec2(0.61f, 0.27f);
    in.duvdx = Vec2(1.5e-3f, 2e-4f);
    in.duvdy = Vec2(-3e-4f, 1.1e-3f);
    in.diff.dnx = Vec2(0.03f, 0.01f);
    in.diff.dny = Vec2(-0.01f, 0.02f);
    const Fresnel F = Fresnel::schlick(Color3(0.9f, 0.6f, 0.5f));
    GlintShape shape = GlintShape::make(p.sigmaX, p.sigmaY, p.rho);
    GlintLobe cached(dict(), p, in, F);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    Vec3 wo = glm::normalize(Vec3(0.2f, -0.3f, 1.f));
    int nonzero = 0;
    for (int n = 0; n < 500; ++n) {
        Vec3 wi = glm::normalize(Vec3(-wo.x + 0.8f * (u(rng) - 0.5f), -wo.y + 0.8f * (u(rng) - 0.5f), 1.f));
        const float lightDistance = n % 2 ? 3.f : std::numeric_limits<float>::infinity();
        LobeValue a = cached.evalPdf(LobeQuery{wo, wi, lightDistance});
        GlintLobe fresh(dict(), p, in, F);
        LobeValue b = fresh.evalPdf(LobeQuery{wo, wi, lightDistance});
        EXPECT_EQ(a.f.x, b.f.x);
        EXPECT_EQ(a.f.z, b.f.z);
        EXPECT_EQ(a.pdf, b.pdf);
        Vec3 h;
        const float ref = glintFCosReference(dict(), p, shape, in, wo, wi, lightDistance);
        glintFCosScalar(dict(), p, shape, in, wo, wi, &h, lightDistance);
        EXPECT_NEAR(a.f.x, F.eval(glm::dot(wo, h)).x * ref, 1e-5f * std::max(ref, 1e-3f));
        nonzero += ref > 0.f;
    }
    EXPECT_GT(nonzero, 100);
}

// ---- glint-aware importance sampling (issue 11 item 3) ------------------------------------------------------------
// A sparkly footprint: level ~6, dictionary LODs 0-8, a few narrow lobes, GGAA on.
GlintLobe sparklyLobe(float relArea = 1.f) {
    GlintParams p;
    p.logDensity = 15.f;
    p.sigmaX = 0.18f, p.sigmaY = 0.12f, p.rho = -0.35f;
    p.relArea = relArea;
    GlintEvalInputs in;
    in.uv = Vec2(0.37f, 0.81f);
    in.duvdx = Vec2(2e-3f, 3e-4f);
    in.duvdy = Vec2(-2e-4f, 1.6e-3f);
    in.diff.dnx = Vec2(0.02f, 0.005f);
    in.diff.dny = Vec2(0.f, 0.02f);
    return GlintLobe(dict(), p, in, Fresnel::one());
}

// χ² of sample() against the quadrature of evalPdf().pdf over (θ, φ) bins of the hemisphere. The pdf is a sum of
// narrow lobes (σ_l σ / σ_o ≈ 0.007 in slope), so each bin is integrated on a 24 × 24 sub-grid (0.003 rad).
struct ChiSquare {
    double chi2 = 0, z = 0, total = 0, accepted = 0;
    int dof = 0;
};
ChiSquare lobeChiSquare(const GlintLobe& lobe, const Vec3& wo, const char* what) {
    const int nt = 24, np = 48, sub = 24, N = 1000000;
    std::vector<double> expected(nt * np, 0.0), observed(nt * np, 0.0);
    ChiSquare r;
    for (int a = 0; a < nt; ++a)
        for (int b = 0; b < np; ++b) {
            double s = 0;
            for (int i = 0; i < sub; ++i)
                for (int j = 0; j < sub; ++j) {
                    double th = (a + (i + 0.5) / sub) / nt * kPiD / 2, ph = (b + (j + 0.5) / sub) / np * 2 * kPiD;
                    Vec3 wi(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th)));
                    s += lobe.pdf(wo, wi) * std::sin(th);
                }
            expected[a * np + b] = s * (kPiD / 2 / nt / sub) * (2 * kPiD / np / sub);
            r.total += expected[a * np + b];
        }
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int ok = 0;
    for (int n = 0; n < N; ++n) {
        Vec3 wi;
        if (!lobe.sample(wo, Vec2(u(rng), u(rng)), wi)) continue;
        ++ok;
        double th = std::acos(std::clamp(double(wi.z), 0.0, 1.0)), ph = std::atan2(double(wi.y), double(wi.x));
        if (ph < 0) ph += 2 * kPiD;
        int a = std::min(int(th / (kPiD / 2) * nt), nt - 1), b = std::min(int(ph / (2 * kPiD) * np), np - 1);
        observed[a * np + b] += 1;
    }
    // Bins expecting < 5 samples are pooled (standard χ² practice).
    double pooledE = 0, pooledO = 0;
    for (size_t k = 0; k < expected.size(); ++k) {
        double e = expected[k] * N;
        if (e < 5) {
            pooledE += e, pooledO += observed[k];
            continue;
        }
        r.chi2 += (observed[k] - e) * (observed[k] - e) / e;
        ++r.dof;
    }
    if (pooledE >= 5) r.chi2 += (pooledO - pooledE) * (pooledO - pooledE) / pooledE, ++r.dof;
    // Normal approximation of the χ² quantile: mean dof, std sqrt(2 dof); 4 sigma is p ≈ 3e-5.
    r.z = (r.chi2 - r.dof) / std::sqrt(2.0 * r.dof);
    r.accepted = double(ok) / N;
    std::printf("%s sampling χ²: %.1f for %d bins (z = %.2f); ∫pdf (quadrature) %.4f, accepted %.4f\n", what, r.chi2,
                r.dof, r.z, r.total, r.accepted);
    return r;
}

TEST(GlintSampling, SampledDirectionsFollowThePdfChiSquare) {
    const GlintLobe lobe = sparklyLobe();
    ASSERT_GT(lobe.cells().count, 3);
    const ChiSquare r = lobeChiSquare(lobe, glm::normalize(Vec3(0.25f, 0.1f, 1.f)), "glint");
    EXPECT_GT(r.dof, 200);
    EXPECT_LT(r.z, 4.0);
    EXPECT_NEAR(r.total, r.accepted, 0.005);
}

// The pdf of the glint part alone is a probability density: ∫ pdf = 1 over the sphere of wi (MC with uniform
// directions on the sphere, where wi.z <= 0 counts the samples sample() rejects) and E[f/pdf] = ∫ f cos (quadrature).
// ---- explicit flakes (issue 38 item 3, glint_flakes.h) ----------------------------------------------------------
// The sparkly lobe's material with flakes of size 0.002 (UV) and a footprint of `footprint` flake sizes (isotropic).
GlintLobe flakyLobe(float footprint, Vec2 uv, float relArea = 0.7f) {
    GlintParams p;
    p.sigmaX = 0.18f, p.sigmaY = 0.12f, p.rho = -0.35f;
    p.relArea = relArea;
    p.flakeSize = 0.002f;
    p.flakeRoughness = 0.04f;
    p.logDensity = flakeLogDensity(p.flakeSize);
    GlintEvalInputs in;
    in.uv = uv;
    in.duvdx = Vec2(footprint * p.flakeSize, 0.f);
    in.duvdy = Vec2(0.f, footprint * p.flakeSize);
    in.diff.dnx = Vec2(0.02f, 0.005f);
    in.diff.dny = Vec2(0.f, 0.02f);
    return GlintLobe(dict(), p, in, Fresnel::one());
}

TEST(GlintFlakes, WeightHandsOverFromFlakesToCountingBetweenHalfAFlakeAndOne) {
    EXPECT_EQ(flakeWeight(0.5f, 1.f), 1.f);
    EXPECT_EQ(flakeWeight(0.1f, 1.f), 1.f);
    EXPECT_EQ(flakeWeight(1.f, 1.f), 0.f);
    EXPECT_EQ(flakeWeight(3.f, 1.f), 0.f);
    EXPECT_FLOAT_EQ(flakeWeight(0.75f, 1.f), 0.5f);
    EXPECT_EQ(flakeWeight(0.f, 0.002f), 1.f);  // no footprint: the flake the ray hit
    EXPECT_EQ(flakeWeight(0.5f, 0.f), 0.f);    // flakes off
    EXPECT_NEAR(flakeLogDensity(0.002f), std::log(1.f / (0.002f * 0.002f)), 1e-5f);
    // From one flake per footprint on, the lobe is C20's counting at one microfacet per flake: the same bits.
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int n = 0; n < 200; ++n) {
        const Vec2 uv(u(rng), u(rng));
        const GlintLobe flaky = flakyLobe(1.f + 3.f * u(rng), uv);
        ASSERT_EQ(flaky.flakeWeight(), 0.f);
        GlintParams p = flaky.params();
        p.flakeSize = 0.f;
        const GlintLobe counted(dict(), p, flaky.inputs(), Fresnel::one());
        const Vec3 wo = glm::normalize(Vec3(u(rng) - 0.5f, u(rng) - 0.5f, 1.f));
        const Vec3 wi = glm::normalize(Vec3(-wo.x + 0.6f * (u(rng) - 0.5f), -wo.y + 0.6f * (u(rng) - 0.5f), 1.f));
        const LobeValue a = flaky.evalPdf(LobeQuery{wo, wi}), b = counted.evalPdf(LobeQuery{wo, wi});
        EXPECT_EQ(a.f.x, b.f.x);
        EXPECT_EQ(a.pdf, b.pdf);
        Vec3 sa(0.f), sb(0.f);
        const Vec2 us(u(rng), u(rng));
        EXPECT_EQ(flaky.sample(wo, us, sa), counted.sample(wo, us, sb));
        EXPECT_EQ(sa, sb);
    }
}

// The flakes' mean over the surface is the converged lobe times the occupancy (glint_flakes.h): f of the zero-footprint
// lobe (explicit flakes only) averaged over 200,000 random points of a 2000-flake-wide square, against A times
// Cook-Torrance with the correlated Beckmann lobe, within 4 standard errors and 3 %; the share of points on a flake
// is A within 4 binomial standard errors.
TEST(GlintFlakes, SurfaceMeanOfTheFlakesIsTheConvergedLobe) {
    const float relArea = 0.7f;
    const GlintShape shape = GlintShape::make(0.18f, 0.12f, -0.35f);
    const Vec3 wo = glm::normalize(Vec3(0.3f, -0.2f, 1.f));
    const Vec3 wis[3] = {glm::normalize(Vec3(-0.3f, 0.2f, 1.f)), glm::normalize(Vec3(-0.5f, 0.25f, 1.f)),
                         glm::normalize(Vec3(-0.2f, 0.45f, 1.f))};
    const int N = 200000;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 4.f);
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    int present = 0;
    for (int n = 0; n < N; ++n) {
        const GlintLobe lobe = flakyLobe(0.f, Vec2(u(rng), u(rng)), relArea);
        ASSERT_EQ(lobe.flakeWeight(), 1.f);
        present += lobe.flakes().count > 0;
        for (int k = 0; k < 3; ++k) {
            const double f = lobe.evalPdf(LobeQuery{wo, wis[k]}).f.x;
            sum[k] += f, sum2[k] += f * f;
        }
    }
    const double share = double(present) / N;
    std::printf("flakes: share on a flake %.4f (A = %.2f)\n", share, relArea);
    EXPECT_NEAR(share, relArea, 4.0 * std::sqrt(relArea * (1 - relArea) / N));
    for (int k = 0; k < 3; ++k) {
        const double mean = sum[k] / N, se = std::sqrt((sum2[k] / N - mean * mean) / N);
        const double ref = relArea * beckmannFCosScalar(shape, wo, wis[k]);
        std::printf("flakes: mean f cos %.5f +- %.5f, A x Beckmann %.5f (ratio %.4f)\n", mean, se, ref, mean / ref);
        EXPECT_NEAR(mean, ref, 4.0 * se);
        EXPECT_NEAR(mean / ref, 1.0, 0.03);
    }
}

// Flakes have their size: the points of a fine grid over a square 30 flakes wide fall on about 900 distinct flakes
// (one Voronoi site per flake-sized cell; the sites near the edge are shared with the outside, hence the margin), and
// every point of one flake sees the same flake slope.
TEST(GlintFlakes, FlakesHaveTheirSizeAndOneSlopeEach) {
    const GlintShape shape = GlintShape::make(0.18f, 0.12f, -0.35f);
    const float size = 0.002f, sf = flakeSigma(0.04f, shape);
    std::map<std::pair<int, int>, Vec2> slopes;
    const int n = 300;  // 10 points per flake size
    int mismatched = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const Vec2 uv(0.5f + (x + 0.5f) * 30.f * size / n, 0.25f + (y + 0.5f) * 30.f * size / n);
            const Flake f = findFlake(uv, size, 1.f, shape, sf);
            auto [it, fresh] = slopes.emplace(std::make_pair(f.cellX, f.cellY), f.slope);
            mismatched += !fresh && it->second != f.slope;
        }
    std::printf("flakes: %zu distinct flakes over 30 x 30 flake sizes\n", slopes.size());
    EXPECT_EQ(mismatched, 0);
    EXPECT_GT(slopes.size(), 860u);
    EXPECT_LT(slopes.size(), 1000u);
}

// Sampling with flakes: a point on a flake, all flake (zero footprint), and a footprint halfway to the counted glints
// over two or more flakes.
TEST(GlintFlakes, SampledDirectionsFollowThePdfChiSquare) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (float footprint : {0.f, 0.75f}) {
        Vec2 uv(0.37f, 0.81f);
        // Halfway, a footprint that spans two or more flakes (the mixture of their Gaussians by their shares).
        const int wanted = footprint > 0.f ? 2 : 1;
        while (flakyLobe(footprint, uv, 1.f).flakes().count < wanted) uv = Vec2(u(rng), u(rng));
        const GlintLobe lobe = flakyLobe(footprint, uv, 1.f);
        ASSERT_GT(lobe.flakeWeight(), footprint > 0.f ? 0.3f : 0.99f);
        const ChiSquare r = lobeChiSquare(lobe, glm::normalize(Vec3(0.25f, 0.1f, 1.f)), "flake");
        EXPECT_GT(r.dof, footprint > 0.f ? 100 : 20);
        EXPECT_LT(r.z, 4.0);
        EXPECT_NEAR(r.total, r.accepted, 0.005);
    }
}

TEST(GlintSampling, PdfIntegratesToOneAndEstimatesTheAlbedo) {
    for (float relArea : {1.f, 0.3f}) {
        const GlintLobe lobe = sparklyLobe(relArea);
        const Vec3 wo = glm::normalize(Vec3(-0.3f, 0.2f, 1.f));
        std::mt19937 rng(9);
        std::uniform_real_distribution<float> u(0.f, 1.f);
        // pdf over the upper hemisphere (quadrature, fine grid) + the rejected fraction (sampled) = 1.
        const int nt = 600, np = 1200;
        double ipdf = 0, ifcos = 0;
        for (int a = 0; a < nt; ++a)
            for (int b = 0; b < np; ++b) {
                double th = (a + 0.5) / nt * kPiD / 2, ph = (b + 0.5) / np * 2 * kPiD;
                Vec3 wi(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th)));
                double dw = std::sin(th) * (kPiD / 2 / nt) * (2 * kPiD / np);
                LobeValue v = lobe.evalPdf(LobeQuery{wo, wi});
                ipdf += v.pdf * dw;
                ifcos += v.f.x * dw;
            }
        const int N = 400000;
        int ok = 0;
        double est = 0, est2 = 0;
        for (int n = 0; n < N; ++n) {
            Vec3 wi;
            if (!lobe.sample(wo, Vec2(u(rng), u(rng)), wi)) continue;
            ++ok;
            LobeValue v = lobe.evalPdf(LobeQuery{wo, wi});
            ASSERT_GT(v.pdf, 0.f);
            const double w = v.f.x / v.pdf;
            est += w, est2 += w * w;
        }
        est /= N;
        const double se = std::sqrt((est2 / N - est * est) / N);
        std::printf("A = %.1f: ∫pdf %.4f vs accepted %.4f; ∫f cos quadrature %.4f, E[f/pdf] %.4f ± %.4f\n", relArea,
                    ipdf, double(ok) / N, ifcos, est, se);
        EXPECT_NEAR(ipdf, double(ok) / N, 0.005);
        EXPECT_NEAR(est, ifcos, std::max(4 * se, 0.01 * ifcos));
    }
}

// The Jacobians of the sampler, checked on their own: half slopes drawn by GlintCellSet::sampleSlope have the density
// P_unfiltered(h~) / keptWeight in the slope plane (2D histogram against the patch SDF integrated per bin).
TEST(GlintSampling, SampledSlopesFollowTheUnfilteredPatchSdf) {
    const GlintLobe lobe = sparklyLobe();
    const GlintCellSet& cells = lobe.cells();
    const GlintShape shape = GlintShape::make(lobe.params().sigmaX, lobe.params().sigmaY, lobe.params().rho);
    const float range = 0.8f;
    const int nb = 40, sub = 16, N = 1000000;
    std::vector<double> expected(nb * nb), observed(nb * nb, 0.0);
    for (int a = 0; a < nb; ++a)
        for (int b = 0; b < nb; ++b) {
            double s = 0;
            for (int i = 0; i < sub; ++i)
                for (int j = 0; j < sub; ++j) {
                    Vec2 hs(-range + 2 * range * (a + (i + 0.5f) / sub) / nb, -range + 2 * range * (b + (j + 0.5f) / sub) / nb);
                    s += cells.evaluate<true>(dict(), shape, shape.applyInv(hs), beckmannSdf(hs, shape), false, Vec2(0.f),
                                              Vec2(0.f)).unfiltered;
                }
            expected[a * nb + b] = s * std::pow(2 * range / nb / sub, 2) / cells.keptWeight;
        }
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int n = 0; n < N; ++n) {
        Vec2 hs;
        ASSERT_TRUE(cells.sampleSlope(dict(), shape, Vec2(u(rng), u(rng)), hs));
        int a = int(std::floor((hs.x + range) / (2 * range) * nb)), b = int(std::floor((hs.y + range) / (2 * range) * nb));
        if (a >= 0 && a < nb && b >= 0 && b < nb) observed[a * nb + b] += 1;
    }
    double chi2 = 0;
    int dof = 0;
    for (size_t k = 0; k < expected.size(); ++k) {
        double e = expected[k] * N;
        if (e < 5) continue;
        chi2 += (observed[k] - e) * (observed[k] - e) / e;
        ++dof;
    }
    const double z = (chi2 - dof) / std::sqrt(2.0 * dof);
    std::printf("slope sampling χ²: %.1f for %d bins (z = %.2f)\n", chi2, dof, z);
    EXPECT_GT(dof, 100);
    EXPECT_LT(z, 4.0);
}

// Variance under an environment (issue 11 item 3): the radiance a glint sphere reflects from the studio environment of
// examples/glint/env/make_studio_env.py (the same function, evaluated analytically), estimated per pixel as the renderer
// does for an environment: the small warm key (the part an environment's luminance sampling finds) by MIS between a
// light sample of its box and the BSDF sample (power heuristic), everything else through the BSDF sample. Once with the
// glint sampler, once with the Beckmann-only sampler (GlintParams::sampleGlints = false, the sampler before). A 64 x 48
// orthographic view; uv (scale 2), the uv footprint and the GGAA frame rotation from neighbouring pixel centres.
// Reference: 1024 samples per pixel with the glint sampler (both are unbiased).
struct StudioKey {
    double az = 20, el = 12, ha = 4, he = 4, lum = 0.2126 * 30 + 0.7152 * 26 + 0.0722 * 20;
    // Support of the soft box (weight 0 beyond |d| >= half + 1 degree), sampled uniformly in (azimuth, elevation).
    double pdf(const Vec3& d) const {
        const double a = std::atan2(d.y, d.x) * 180 / kPiD, e = std::asin(std::clamp(double(d.z), -1.0, 1.0)) * 180 / kPiD;
        const double da = std::fmod(a - az + 540.0, 360.0) - 180.0;
        if (std::abs(da) >= ha + 1 || std::abs(e - el) >= he + 1) return 0;
        const double area = (2 * (ha + 1) * kPiD / 180) * (2 * (he + 1) * kPiD / 180);
        return 1 / (area * std::cos(e * kPiD / 180));  // dω = cos(el) d(az) d(el)
    }
    Vec3 sample(double u1, double u2) const {
        const double a = (az + (2 * u1 - 1) * (ha + 1)) * kPiD / 180, e = (el + (2 * u2 - 1) * (he + 1)) * kPiD / 180;
        return Vec3(float(std::cos(e) * std::cos(a)), float(std::cos(e) * std::sin(a)), float(std::sin(e)));
    }
};
// Luminance of the studio environment along d, split into (everything but the key, the key).
std::pair<double, double> studioLuminance(const Vec3& d) {
    const double z = d.z;
    double r, g, b;
    if (z > 0) {
        r = 0.10 + 0.10 * z, g = 0.12 + 0.12 * z, b = 0.16 + 0.20 * z;
    } else {
        r = g = b = 0.06;
    }
    auto box = [&](double caz, double cel, double ha, double he) {
        const double az = std::atan2(d.y, d.x) * 180 / kPiD, el = std::asin(std::clamp(z, -1.0, 1.0)) * 180 / kPiD;
        const double da = std::fmod(az - caz + 540.0, 360.0) - 180.0;
        const double ea = std::clamp((ha - std::abs(da)) / 2 + 0.5, 0.0, 1.0);
        const double ee = std::clamp((he - std::abs(el - cel)) / 2 + 0.5, 0.0, 1.0);
        return ea * ee;
    };
    const struct { double az, el, ha, he, r, g, b; } boxes[] = {
        {-60, 35, 25, 18, 5.0, 5.0, 4.8}, {70, 25, 20, 14, 3.0, 3.2, 3.6}, {175, 55, 30, 12, 2.0, 2.0, 2.0}};
    for (const auto& k : boxes) {
        const double w = box(k.az, k.el, k.ha, k.he);
        r += w * k.r, g += w * k.g, b += w * k.b;
    }
    const StudioKey key;
    return {0.2126 * r + 0.7152 * g + 0.0722 * b, box(key.az, key.el, key.ha, key.he) * key.lum};
}

struct SpherePixel {
    Vec3 t, b, n;
    GlintEvalInputs in;
};
std::vector<SpherePixel> glintSpherePixels(int W, int H) {
    auto at = [](double x, double z, Vec3& n, Vec2& uv) {
        const double r2 = x * x + z * z;
        if (r2 >= 0.98) return false;
        n = Vec3(float(x), float(-std::sqrt(1 - r2)), float(z));
        uv = Vec2(float(2 * (std::atan2(double(n.y), double(n.x)) / (2 * kPiD) + 0.5)), float(2 * std::acos(z) / kPiD));
        return true;
    };
    std::vector<SpherePixel> px;
    const double step = 2.2 / W;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const double cx = -1.1 + (x + 0.5) * step, cz = 0.825 - (y + 0.5) * step;
            Vec3 n, nx, nz;
            Vec2 uv, uvx, uvz;
            if (!at(cx, cz, n, uv) || !at(cx + step, cz, nx, uvx) || !at(cx, cz - step, nz, uvz)) continue;
            SpherePixel p;
            p.n = n;
            p.t = glm::normalize(glm::cross(Vec3(0, 0, 1), n));
            p.b = glm::cross(n, p.t);
            p.in.uv = uv;
            p.in.duvdx = uvx - uv;
            p.in.duvdy = uvz - uv;
            p.in.diff.dnx = Vec2(glm::dot(p.t, nx - n), glm::dot(p.b, nx - n));
            p.in.diff.dny = Vec2(glm::dot(p.t, nz - n), glm::dot(p.b, nz - n));
            px.push_back(p);
        }
    return px;
}

TEST(GlintSampling, EnvironmentRmseAtEqualSppIsLowerThanWithBeckmannSampling) {
    const std::vector<SpherePixel> pixels = glintSpherePixels(64, 48);
    ASSERT_GT(pixels.size(), 1500u);
    GlintParams p;
    p.sigmaX = p.sigmaY = 0.15f;
    p.logDensity = 15.f;
    const Vec3 woWorld(0, -1, 0);
    auto estimate = [&](const SpherePixel& px, bool glints, int spp, uint32_t seed) {
        GlintParams q = p;
        q.sampleGlints = glints;
        const GlintLobe lobe(dict(), q, px.in, Fresnel::one());
        const Vec3 wo(glm::dot(woWorld, px.t), glm::dot(woWorld, px.b), glm::dot(woWorld, px.n));
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(0.f, 1.f);
        const StudioKey key;
        double sum = 0;
        for (int s = 0; s < spp; ++s) {
            const Vec3 wl = key.sample(u(rng), u(rng));  // light sample of the key
            const Vec3 wlLocal(glm::dot(wl, px.t), glm::dot(wl, px.b), glm::dot(wl, px.n));
            if (wlLocal.z > 0.f) {
                const LobeValue v = lobe.evalPdf(LobeQuery{wo, wlLocal});
                const double pl = key.pdf(wl);
                sum += v.f.x * studioLuminance(wl).second * pl / (pl * pl + double(v.pdf) * v.pdf);
            }
            Vec3 wi;  // BSDF sample
            const Vec2 uu(u(rng), u(rng));
            if (!lobe.sample(wo, uu, wi)) continue;
            const LobeValue v = lobe.evalPdf(LobeQuery{wo, wi});
            if (!(v.pdf > 0.f)) continue;
            const Vec3 w = wi.x * px.t + wi.y * px.b + wi.z * px.n;
            const auto [rest, keyL] = studioLuminance(w);
            const double pl = key.pdf(w), pb = v.pdf;
            sum += v.f.x * (rest / pb + keyL * pb / (pb * pb + pl * pl));
        }
        return sum / spp;
    };
    double errGlint = 0, errBeckmann = 0, meanRef = 0, meanGlint = 0, meanBeckmann = 0, ssG = 0, ssB = 0;
    for (size_t k = 0; k < pixels.size(); ++k) {
        const double ref = estimate(pixels[k], true, 1024, 1000003u * uint32_t(k) + 7u);
        const double g = estimate(pixels[k], true, 8, 7919u * uint32_t(k) + 1u);
        const double b = estimate(pixels[k], false, 8, 7919u * uint32_t(k) + 1u);
        errGlint += (g - ref) * (g - ref);
        errBeckmann += (b - ref) * (b - ref);
        meanRef += ref, meanGlint += g, meanBeckmann += b;
        ssG += (g - ref) * (g - ref), ssB += (b - ref) * (b - ref);
    }
    const double n = double(pixels.size());
    const double rmseGlint = std::sqrt(errGlint / n), rmseBeckmann = std::sqrt(errBeckmann / n);
    std::printf("environment, 8 spp BSDF sampling over %zu pixels: RMSE glint sampler %.4f, Beckmann sampler %.4f "
                "(ratio %.3f); means ref %.4f glint %.4f Beckmann %.4f\n",
                pixels.size(), rmseGlint, rmseBeckmann, rmseGlint / rmseBeckmann, meanRef / n, meanGlint / n,
                meanBeckmann / n);
    EXPECT_LT(rmseGlint, 0.9 * rmseBeckmann);  // measured 0.734 with these seeds, 0.800 with another seed set
    // Unbiased: the image means agree within 4 standard errors of the mean difference.
    EXPECT_NEAR(meanGlint / n, meanRef / n, 4 * std::sqrt(ssG) / n);
    EXPECT_NEAR(meanBeckmann / n, meanRef / n, 4 * std::sqrt(ssB) / n);
}

}  // namespace
