// Fitting LTCs: the Student-t (ν = 2) EM fit of weighted directions (ltc-filtering.md §5.2) and, built on it and on
// the Nelder-Mead L3 fit of ltc_code (§2), the isotropic/anisotropic GGX tables and the sphere table (§3 step 5).
#include "core/ltc/ltc_fit.h"

#include <glm/gtc/matrix_inverse.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace specula::ltc {

namespace {

using DMat3 = glm::dmat3;
using DVec2 = glm::dvec2;

// Symmetric 2×2 matrix (s00, s01; s01, s11) with its eigenvalues clamped to >= lo (§5.2 step 3: keeps S invertible
// when the samples are (nearly) collinear, e.g. a mirror-like lobe fitted from few distinct directions).
void clampEigen2(double& s00, double& s01, double& s11, double lo) {
    double tr = 0.5 * (s00 + s11);
    double d = 0.5 * (s00 - s11);
    double r = std::sqrt(d * d + s01 * s01);
    double l0 = tr + r, l1 = tr - r;  // l0 >= l1
    if (l1 >= lo) return;
    // Eigenvector of l0: (cos c, sin c) with tan 2c = 2 s01 / (s00 − s11).
    double c = 0.5 * std::atan2(2.0 * s01, s00 - s11);
    double ca = std::cos(c), sa = std::sin(c);
    l0 = std::max(l0, lo);
    l1 = std::max(l1, lo);
    s00 = l0 * ca * ca + l1 * sa * sa;
    s11 = l0 * sa * sa + l1 * ca * ca;
    s01 = (l0 - l1) * ca * sa;
}

}  // namespace

Ltc fitStudentT(const std::vector<WeightedDirection>& samples, const Vec3& tangentHint, int iterations) {
    Ltc out;
    out.invM = Mat3(1.f);
    out.fresnel = 0.f;
    const size_t n = samples.size();
    if (n == 0) {
        out.magnitude = 0.f;
        return out;
    }
    // Magnitude = mean sample weight over ALL samples, dropped ones included (§5.2 step 4): with weights f·cos/pdf it
    // is the Monte Carlo estimate of the albedo.
    double wSum = 0.0;
    DVec3 mean(0.0);
    for (const WeightedDirection& s : samples) {
        wSum += double(s.weight);
        mean += double(s.weight) * DVec3(s.w);
    }
    out.magnitude = float(wSum / double(n));
    double meanLen = glm::length(mean);
    if (!(wSum > 0.0) || !(meanLen > 0.0)) return out;

    // Step 1: axis Z = normalised weighted mean; X = Gram-Schmidt of the hint, so that neighbouring fits share a frame
    // (no KHDN22 alignment pass needed); Y = Z × X.
    DVec3 Z = mean / meanLen;
    DVec3 X = DVec3(tangentHint) - Z * glm::dot(Z, DVec3(tangentHint));
    if (!(glm::dot(X, X) > 1e-20)) {
        // Hint parallel to the axis: any deterministic perpendicular.
        DVec3 a = std::abs(Z.x) < 0.9 ? DVec3(1, 0, 0) : DVec3(0, 1, 0);
        X = a - Z * glm::dot(Z, a);
    }
    X = glm::normalize(X);
    DVec3 Y = glm::cross(Z, X);

    // Step 2: gnomonic projection p = (w·X, w·Y)/(w·Z); samples with w·Z <= 1e-4 are dropped (their weight still counts
    // in the magnitude above).
    std::vector<DVec2> p;
    std::vector<double> om;
    p.reserve(n);
    om.reserve(n);
    double omSum = 0.0;
    for (const WeightedDirection& s : samples) {
        DVec3 w(s.w);
        double wz = glm::dot(w, Z);
        if (wz <= 1e-4 || !(s.weight > 0.f)) continue;  // weight 0 samples carry no information
        p.emplace_back(glm::dot(w, X) / wz, glm::dot(w, Y) / wz);
        om.push_back(double(s.weight));
        omSum += double(s.weight);
    }
    if (p.empty() || !(omSum > 0.0)) return out;

    // Step 3: Liu & Rubin (1995) EM for a bivariate Student-t with ν = 2 fixed: E-step weight (ν + 2)/(ν + δ) = 4/(2 + δ).
    // Start: μ = 0, S = ½·median(|p|²)·I (the median of the unweighted kept samples; the upper median for an even count).
    std::vector<double> r2(p.size());
    for (size_t i = 0; i < p.size(); ++i) r2[i] = glm::dot(p[i], p[i]);
    std::nth_element(r2.begin(), r2.begin() + r2.size() / 2, r2.end());
    double med = r2[r2.size() / 2];
    const double kEigMin = 1e-14;
    DVec2 mu(0.0);
    double s00 = std::max(0.5 * med, kEigMin), s01 = 0.0, s11 = s00;
    std::vector<double> wt(p.size());
    for (int it = 0; it < iterations; ++it) {
        double det = s00 * s11 - s01 * s01;
        double i00 = s11 / det, i01 = -s01 / det, i11 = s00 / det;
        double sw = 0.0;
        DVec2 m(0.0);
        for (size_t i = 0; i < p.size(); ++i) {
            DVec2 d = p[i] - mu;
            double delta = d.x * d.x * i00 + 2.0 * d.x * d.y * i01 + d.y * d.y * i11;
            wt[i] = om[i] * 4.0 / (2.0 + delta);
            sw += wt[i];
            m += wt[i] * p[i];
        }
        mu = m / sw;
        double a00 = 0.0, a01 = 0.0, a11 = 0.0;
        for (size_t i = 0; i < p.size(); ++i) {
            DVec2 d = p[i] - mu;
            a00 += wt[i] * d.x * d.x;
            a01 += wt[i] * d.x * d.y;
            a11 += wt[i] * d.y * d.y;
        }
        s00 = a00 / omSum;
        s01 = a01 / omSum;
        s11 = a11 / omSum;
        clampEigen2(s00, s01, s11, kEigMin);
    }

    // Step 4: p = A u + μ with u ~ t₂(0, I/2) (the clamped cosine in gnomonic coordinates, §1), so A Aᵀ = 2S:
    // A = lower Cholesky of 2S; K rows (A11, 0, μx), (A21, A22, μy), (0, 0, 1); M = [X Y Z]·K.
    double c00 = 2.0 * s00, c01 = 2.0 * s01, c11 = 2.0 * s11;
    double A11 = std::sqrt(c00);
    double A21 = c01 / A11;
    double A22 = std::sqrt(std::max(c11 - A21 * A21, kEigMin));
    DMat3 K(1.0);  // glm: K[col][row]
    K[0][0] = A11;
    K[0][1] = A21;
    K[1][1] = A22;
    K[2][0] = mu.x;
    K[2][1] = mu.y;
    K[2][2] = 1.0;
    K[0][2] = 0.0;
    K[1][0] = 0.0;
    K[1][2] = 0.0;
    DMat3 Q(X, Y, Z);
    DMat3 M = Q * K;
    DMat3 inv = glm::inverse(M);
    // Normalisation: the LTC is invariant to the scale of invM; we scale it to determinant 1 (det M = A11·A22 > 0), which
    // keeps the entries O(1/α^(1/3))..O(α^(2/3)) — well inside float range for any lobe — and makes tables interpolate
    // between consistently scaled neighbours.
    double det = glm::determinant(inv);
    inv *= 1.0 / std::cbrt(det);
    out.invM = Mat3(inv);
    return out;
}

}  // namespace specula::ltc
