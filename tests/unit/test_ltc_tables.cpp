// Tests for the LTC fits and tables (core/ltc/ltc_fit, core/ltc/ltc_tables): the Student-t EM fit, and the
// acceptance invariants of ltc-filtering.md §6 that concern the tables (T1, T4, T8, T9, T10, T11, golden hash, drift).
#include "core/ltc/ltc_fit.h"
#include "core/ltc/ltc_tables.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace specula;
using namespace specula::ltc;

namespace {

constexpr double kPiD = 3.14159265358979323846;
using DMat3 = glm::dmat3;

// D(w) of an LTC given its inverse (HDHN16 Eq. 1); computed here in double so the tests do not depend on ltc.cpp.
double ltcDensity(const DMat3& invM, const DVec3& w) {
    DVec3 wo = invM * w;
    double l = glm::length(wo);
    double z = wo.z / l;
    if (z <= 0.0) return 0.0;
    return z / kPiD * std::abs(glm::determinant(invM)) / (l * l * l);
}

// Cosine-distributed direction for stratified u (Malley's method).
DVec3 cosineDir(double u1, double u2) {
    double r = std::sqrt(u1), ph = 2.0 * kPiD * u2;
    return {r * std::cos(ph), r * std::sin(ph), std::sqrt(std::max(0.0, 1.0 - u1))};
}

}  // namespace

// §5.2: samples drawn from a known LTC (M = Q·K with μ = 0, so its weighted mean is exactly Q's axis and the t-EM model
// is exact) give back the same density: ∫|D_fit − D_true| (importance-sampled from D_true) below 2%.
TEST(LtcFit, StudentTRecoversKnownLtc) {
    DMat3 K(1.0);
    K[0][0] = 0.35;  // A11
    K[0][1] = 0.12;  // A21 (shear)
    K[1][1] = 0.6;   // A22
    DVec3 Z = glm::normalize(DVec3(0.3, -0.2, 0.9));
    DVec3 X = glm::normalize(glm::cross(DVec3(0, 1, 0), Z));
    DVec3 Y = glm::cross(Z, X);
    DMat3 M = DMat3(X, Y, Z) * K;
    DMat3 invTrue = glm::inverse(M);
    const int n = 128;
    std::vector<WeightedDirection> s;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            DVec3 w = glm::normalize(M * cosineDir((i + 0.5) / n, (j + 0.5) / n));
            s.push_back({Vec3(w), 0.75f});
        }
    Ltc fit = fitStudentT(s, Vec3(1, 0, 0));
    EXPECT_NEAR(fit.magnitude, 0.75f, 1e-6f);
    EXPECT_NEAR(glm::determinant(fit.invM), 1.f, 1e-4f);  // documented normalisation
    DMat3 invFit(fit.invM);
    double l1 = 0.0;
    const int m = 64;
    for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i) {
            DVec3 w = glm::normalize(M * cosineDir((i + 0.37) / m, (j + 0.61) / m));
            double dt = ltcDensity(invTrue, w), df = ltcDensity(invFit, w);
            l1 += std::abs(df / dt - 1.0);
        }
    l1 /= m * m;
    EXPECT_LT(l1, 0.02);
}

// Non-uniform weights: a weighted sample set equals the density it represents (cosine samples reweighted towards a
// narrower LTC would need the exact ratio; here half the samples get weight 0 — they must not move the fit — and the
// magnitude still averages over all of them).
TEST(LtcFit, StudentTZeroWeightsIgnoredButCounted) {
    DMat3 K(1.0);
    K[0][0] = 0.2;
    K[1][1] = 0.2;
    DMat3 M = K;
    const int n = 64;
    std::vector<WeightedDirection> a, b;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec3 w(glm::normalize(M * cosineDir((i + 0.5) / n, (j + 0.5) / n)));
            a.push_back({w, 1.f});
            b.push_back({w, 1.f});
            b.push_back({Vec3(0.6f, 0.f, 0.8f), 0.f});
        }
    Ltc fa = fitStudentT(a, Vec3(1, 0, 0)), fb = fitStudentT(b, Vec3(1, 0, 0));
    EXPECT_NEAR(fa.magnitude, 1.f, 1e-6f);
    EXPECT_NEAR(fb.magnitude, 0.5f, 1e-6f);
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) EXPECT_NEAR(fa.invM[c][r], fb.invM[c][r], 1e-5f);
    // The isotropic lobe M = diag(0.2, 0.2, 1) normalised to det 1: invM = diag(5, 5, 1)/25^(1/3).
    double k = 1.0 / std::cbrt(25.0);
    EXPECT_NEAR(fa.invM[0][0], 5 * k, 0.02 * 5 * k);
    EXPECT_NEAR(fa.invM[1][1], 5 * k, 0.02 * 5 * k);
    EXPECT_NEAR(fa.invM[2][2], k, 0.02 * k);
}
