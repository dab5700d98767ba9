// Quad lights through the lobes (issue 10 item 2): GGX (isotropic, anisotropic, Schlick Fresnel), filtered GGX (the
// roughness matrix's principal axes) and Beckmann-LEAN (equivalent GGX) against independent MIS Monte Carlo (T6 bands).
#include "core/ltc/ltc_ggx.h"
#include "core/ltc/ltc_reference.h"
#include "core/render/lobes/ggx.h"
#include "nodes/bsdf/beckmann_lean/beckmann_lean.h"
#include "nodes/bsdf/ggx_filtered/filtered_ggx.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace specula;
using ltc::LobeUnderTest;

namespace {

void report(const char* name, const ltc::BandErrors& s) {
    std::printf("%-28s mean|err|/albedo by band: %.4f %.4f %.4f; median rel (>=10%%): %.3f %.3f %.3f (n %zu %zu %zu)\n",
                name, s.meanAbs(0), s.meanAbs(1), s.meanAbs(2), s.medianRelative(0), s.medianRelative(1),
                s.medianRelative(2), s.relative[0].size(), s.relative[1].size(), s.relative[2].size());
}

// T6 limits (ltc-filtering.md §6): mean |err|/mag <= 0.005, 0.015, 0.03; median relative <= 3%, 7% (band 3 not asserted).
void expectT6(const ltc::BandErrors& s) {
    EXPECT_LE(s.meanAbs(0), 0.005);
    EXPECT_LE(s.meanAbs(1), 0.015);
    EXPECT_LE(s.meanAbs(2), 0.03);
    if (s.relative[0].size() >= 5) EXPECT_LE(s.medianRelative(0), 0.03);
    if (s.relative[1].size() >= 5) EXPECT_LE(s.medianRelative(1), 0.07);
}
void expectT6Means(const ltc::BandErrors& s, double scale) {
    EXPECT_LE(s.meanAbs(0), 0.005 * scale);
    EXPECT_LE(s.meanAbs(1), 0.015 * scale);
    EXPECT_LE(s.meanAbs(2), 0.03 * scale);
}
double uniform(uint64_t& s) { return ltc::nextUniform(s); }

const ltc::LtcTables& tables() { return ltc::builtinTables(); }

// measureQuadErrors over perBand random lobes per view band from makeLobe (100,000 MC samples per quad), printed.
template <class MakeLobe>
ltc::BandErrors measured(const char* name, int perBand, uint64_t seed, MakeLobe makeLobe) {
    ltc::BandErrors s = ltc::measureQuadErrors(makeLobe, perBand, 100000, seed);
    report(name, s);
    return s;
}

}  // namespace

TEST(LtcLobes, IsotropicGgxMeetsT6) {
    const ltc::BandErrors s = measured("ggx isotropic", 40, 1, [](uint64_t& r, const Vec3& wo) {
        float a = float(std::pow(0.25 + 0.75 * uniform(r), 2.0));
        LobeUnderTest c{std::make_unique<GgxLobe>(a, a, Fresnel::one())};
        c.albedo = ltc::ggxIsotropic(tables(), a, wo).magnitude;
        return c;
    });
    expectT6(s);
}

TEST(LtcLobes, SchlickFresnelThroughTheFresTableMeetsT6) {
    // F0·mag + (1 − F0)·fres is exact for Schlick (ltc_code 2017): the same limits with a dielectric-like F0.
    const ltc::BandErrors s = measured("ggx schlick F0 0.3", 16, 2, [](uint64_t& r, const Vec3& wo) {
        float a = float(std::pow(0.25 + 0.75 * uniform(r), 2.0));
        Fresnel f = Fresnel::schlick(Color3(0.04f, 0.3f, 0.9f));
        LobeUnderTest c{std::make_unique<GgxLobe>(a, a, f)};
        c.albedo = ltc::fresnelScale(f, ltc::ggxIsotropic(tables(), a, wo)).y;
        return c;
    });
    expectT6(s);
}

TEST(LtcLobes, AnisotropicGgxMeetsT6Means) {
    // The t-EM anisotropic table (docs/ltc-tables.md). Its median relative errors are reported, not asserted: the
    // 8^4 grid interpolates matrices across roughness ratios, where the spec's limits are for the 64×64 table.
    const ltc::BandErrors s = measured("ggx anisotropic", 16, 3, [](uint64_t& r, const Vec3& wo) {
        float ax = float(std::pow(0.3 + 0.7 * uniform(r), 2.0)), ay = float(std::pow(0.3 + 0.7 * uniform(r), 2.0));
        LobeUnderTest c{std::make_unique<GgxLobe>(ax, ay, Fresnel::one())};
        c.albedo = ltc::ggxRoughnessMatrix(tables(), ax * ax, 0, ay * ay, wo).magnitude;
        return c;
    });
    expectT6Means(s, 2.0);
}

TEST(LtcLobes, FilteredGgxRoughnessMatrixUsesItsPrincipalAxes) {
    // A rotated anisotropic roughness matrix (no filter): the LTC rotated into the eigenvectors equals the MC of the
    // filtered lobe as closely as the axis-aligned anisotropic lobe does.
    const ltc::BandErrors s = measured("ggx_filtered rotated matrix", 16, 4, [](uint64_t& r, const Vec3& wo) {
        double ax = std::pow(0.3 + 0.7 * uniform(r), 2.0), ay = std::pow(0.3 + 0.7 * uniform(r), 2.0);
        double phi = M_PI * uniform(r), cs = std::cos(phi), sn = std::sin(phi);
        fggx::LobeSetup setup;
        setup.A = {cs * cs * ax * ax + sn * sn * ay * ay, cs * sn * (ax * ax - ay * ay), sn * sn * ax * ax + cs * cs * ay * ay};
        setup.params.filter = fggx::Filter::None;
        LobeUnderTest c{std::make_unique<fggx::FilteredGgxLobe>(setup, Fresnel::one())};
        c.albedo = ltc::ggxRoughnessMatrix(tables(), setup.A.a, setup.A.c, setup.A.d, wo).magnitude;
        return c;
    });
    expectT6Means(s, 2.0);
}

TEST(LtcLobes, BeckmannLeanEquivalentGgxErrorIsMeasured) {
    // The equivalent-GGX mapping (tilted mean normal, α² = 1.5Σ) approximates a different microfacet model (Beckmann
    // slopes, mean-plane masking) by GGX: the error is that model gap, not a fit error. Measured (2026-12-01) mean
    // |err|/albedo 0.031 / 0.016 / 0.093 by band; bounds 0.04 / 0.025 / 0.12.
    const ltc::BandErrors s = measured("beckmann_lean (equivalent)", 16, 5, [](uint64_t& r, const Vec3& wo) {
        Vec2 mean(float(0.3 * (uniform(r) - 0.5)), float(0.3 * (uniform(r) - 0.5)));
        Vec3 cov(float(0.02 * uniform(r)), float(0.02 * uniform(r)), 0.f);
        float alpha = float(0.2 + 0.6 * uniform(r));
        lean::SlopeGaussian g = lean::makeSlopeGaussian(mean, cov, alpha);
        auto lobe = std::make_unique<BeckmannLeanLobe>(g, Fresnel::one());
        LobeUnderTest c{std::move(lobe)};
        c.albedo = static_cast<BeckmannLeanLobe*>(c.lobe.get())->polygonLtc(wo).magnitude;
        return c;
    });
    EXPECT_LE(s.meanAbs(0), 0.04);
    EXPECT_LE(s.meanAbs(1), 0.025);
    EXPECT_LE(s.meanAbs(2), 0.12);
}

TEST(LtcLobes, T2HugeQuadIntegratesMagnitudeMinusLeak) {
    // ltc-filtering.md T2: a huge quad at z = 1 (±1e4) sees the whole upper hemisphere, so mag·∫D = mag·(1 − leak), leak =
    // the LTC's mass below the lobe's horizon, here the fraction of LTC samples with z <= 0 (400² stratified samples).
    // Cells as T1: every 9th with roughness >= 0.14 (sharper lobes at grazing views put mass within 0.006° of the
    // horizon, which the ±1e4 quad does not reach: r = 1/63 at θ = 1.57 misses 1.35 %).
    const auto& t = tables();
    const Vec3 huge[4] = {{-1e4f, -1e4f, 1.f}, {1e4f, -1e4f, 1.f}, {1e4f, 1e4f, 1.f}, {-1e4f, 1e4f, 1.f}};
    double worst = 0;
    int cells = 0;
    for (int cell = 0; cell < 64 * 64; cell += 9) {
        const int a = cell % 64, tv = cell / 64;
        const float r = float(a) / 63.f, x = float(tv) / 63.f;
        if (r < 0.14f) continue;
        const float alpha = std::max(r * r, 1e-5f), cosTheta = 1.f - x * x;
        const Vec3 wo(std::sqrt(std::max(0.f, 1.f - cosTheta * cosTheta)), 0.f, cosTheta);
        const ltc::Ltc l = ltc::ggxIsotropic(t, alpha, wo);
        const double integral = ltc::integrate(l, huge, 4, false, ltc::Horizon::Clip, nullptr);
        const int n = 400;
        int below = 0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) below += l.sample(Vec2((i + 0.5f) / n, (j + 0.5f) / n)).z <= 0.f;
        const double leak = double(below) / (double(n) * n);
        if (std::abs(integral - (1.0 - leak)) > 3e-3) std::printf("  cell a=%d t=%d: integral %.5f, 1 - leak %.5f\n", a, tv, integral, 1.0 - leak);
        worst = std::max(worst, std::abs(integral - (1.0 - leak)));
        ++cells;
    }
    std::printf("T2: %d cells, worst |∫D − (1 − leak)| = %.2e (limit 3e-3)\n", cells, worst);
    EXPECT_LE(worst, 3e-3);
}
