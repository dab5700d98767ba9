// bsdf.sheen's formulas (nodes/bsdf/sheen/sheen_lobe.h): the Charlie D is normalised, the directional-albedo table
// agrees with quadrature and stays ≤ 1 from the clamped α up, and Λ stays finite where a unit z rounds above 1.
#include "nodes/bsdf/sheen/sheen_lobe.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace specula;

namespace {
// ∫ f cos θi dωi for one view, midpoint quadrature in (cos θi, φ), n × n points.
double albedoByQuadrature(float cosThetaO, float alpha, int n) {
    const Vec3 wo(std::sqrt(1.f - cosThetaO * cosThetaO), 0.f, cosThetaO);
    double sum = 0;
    for (int a = 0; a < n; ++a) {
        const float ci = (float(a) + 0.5f) / float(n), si = std::sqrt(1.f - ci * ci);
        for (int b = 0; b < n; ++b) {
            const float phi = kPi * (float(b) + 0.5f) / float(n);
            sum += sheen::reflectanceCos(wo, Vec3(si * std::cos(phi), si * std::sin(phi), ci), alpha);
        }
    }
    return sum * 2.0 * kPi / (double(n) * n);
}
}  // namespace

// Estevez & Kulla 2017, §2: ∫ D(h) cos θh dωh = 2π ∫_0^1 D(μ) μ dμ = 1.
TEST(Sheen, CharlieDistributionIsNormalised) {
    for (float alpha : {sheen::kMinAlpha, 0.1f, 0.3f, 0.5f, 1.f}) {
        const int n = 200000;
        double s = 0;
        for (int k = 0; k < n; ++k) {
            const double mu = (k + 0.5) / n;
            s += double(sheen::ndf(float(mu), alpha)) * mu;
        }
        EXPECT_NEAR(s * 2.0 * M_PI / n, 1.0, 1e-3) << "alpha " << alpha;
    }
}

TEST(Sheen, AlbedoTableMatchesQuadrature) {
    for (float alpha : {0.1f, 0.3f, 0.6f, 1.f})
        for (float c : {0.2f, 0.5f, 0.8f, 1.f}) {
            const double ref = albedoByQuadrature(c, alpha, 400);
            EXPECT_NEAR(sheen::directionalAlbedo(c, alpha), ref, 0.01 + 0.02 * ref) << "alpha " << alpha << " cos " << c;
        }
}

// The reason for kMinAlpha: from it up the fitted Λ keeps the albedo ≤ 1 even at grazing views.
TEST(Sheen, AlbedoAtMostOneFromTheClampedAlpha) {
    for (float alpha : {sheen::kMinAlpha, 0.1f, 0.3f, 1.f})
        for (float c = 1.5e-3f; c < 0.05f; c *= 1.5f) EXPECT_LE(albedoByQuadrature(c, alpha, 600), 1.0) << alpha << " " << c;
}

// A unit vector's z may round above 1 (the raster integrator asks for wi = the normal): Λ must stay finite.
TEST(Sheen, LambdaFiniteAboveOne) {
    EXPECT_TRUE(std::isfinite(sheen::lambda(std::nextafter(1.f, 2.f), 0.3f)));
    EXPECT_TRUE(std::isfinite(sheen::reflectanceCos(Vec3(0.6f, 0.f, 0.8f), Vec3(0.f, 0.f, std::nextafter(1.f, 2.f)), 0.3f)));
}
