// Fitting LTCs: the Nelder-Mead L3 fit of ltc_code (ltc-filtering.md §2), the Student-t EM fit of weighted sample
// directions (§5.2, used for the cross-check table, the anisotropic table and normal-map prefiltering), the tables.
#pragma once

#include "core/ltc/ltc_tables.h"

#include <vector>

namespace specula::ltc {

// A weighted direction (unit, in the frame the fit is expressed in).
struct WeightedDirection {
    Vec3 w;
    float weight;
};

// Student-t (ν = 2) maximum-likelihood fit of an LTC to weighted directions (ltc-filtering.md §5.2 steps 1-4, no
// axis refinement): Z = normalised weighted mean, X = Gram-Schmidt of 'tangentHint' (so neighbouring fits share a
// frame), gnomonic projection (samples with w·Z <= 1e-4 dropped), Liu-Rubin EM (ν = 2, 'iterations' steps from μ = 0,
// S = ½·median(|p|²)·I, eigenvalues of S clamped to >= 1e-14), A = lower Cholesky of 2S, M = [X Y Z]·K.
// Returns invM = inverse(M) scaled to determinant 1, magnitude = mean weight over ALL samples (dropped ones and
// weight-0 ones included), fresnel = 0. Computed in double internally. Deterministic (no RNG).
Ltc fitStudentT(const std::vector<WeightedDirection>& samples, const Vec3& tangentHint, int iterations = 30);

// ---- Table fits (tools/ltc-fit, tests) ---------------------------------------------------------------------------

// Grid of the isotropic tables (§2 "Grid"): roughness r = a/63, α = max(r², 1e-5); x = t/63, cos θ = 1 − x² with
// θ <= 1.57. View direction of a cell: v = (sin θ, 0, cos θ).
double isoAlpha(int a);
double isoCosTheta(int t);

// An isotropic 64×64 GGX table in the LtcTables::ggxInv / ggxMagFres layouts (see ltc_tables.h).
struct IsoTable {
    std::vector<float> inv;      // 4 floats per cell
    std::vector<float> magFres;  // 2 floats per cell
};

struct IsoFitOptions {
    int ns = 32;        // the L3 objective uses Ns×Ns stratified points, each one LTC and one BRDF sample (§2)
    int threads = 1;    // rows a are fitted in parallel after the t = 0 column; the result does not depend on it (T9)
    int aMin = 0;       // fit only the roughness rows a in [aMin, 63] (cells of other rows stay 0): tests
    int momentsN = 64;  // mag/fres/mean direction from momentsN² stratified VNDF samples per cell (§5.1)
};

// The reference table: Nelder-Mead on the MIS L3 objective with warm starts, exactly as §2 (see ltc_fit.cpp for the
// few documented choices: VNDF samples, true VNDF pdf below the horizon, double precision).
IsoTable fitGgxIsoNelderMead(const IsoFitOptions& opt);
// The t-EM variant of the same table (§5.2 "Base GGX table built this way": samplesPerAxis² stratified VNDF samples
// per cell weighted G2/G1, no axis refinement, y-couplings zeroed, packed like the reference). Not shipped: the T11
// cross-check of the tests.
IsoTable fitGgxIsoStudentT(int samplesPerAxis = 16, int threads = 1);

// scale(z, len) of the clip-free path, 64×64 (§3 step 5), layout of LtcTables::sphere.
std::vector<float> fitSphereTable();
// Snyder's horizon-clipped cap form factor (§3 step 5). A private copy of ltc::capFormFactor (ltc.cpp belongs to the
// integrator), so the tables do not depend on the integrator's implementation; the tests compare the two.
double capFormFactorSnyder(double omega, double sigma);

// Anisotropic GGX by t-EM (layouts of LtcTables::aniso*): n values of αx, αy and θ, nPhi values of φ in [0, π/2].
// samplesPerAxis² stratified VNDF samples per cell weighted G2/G1.
void fitGgxAnisotropic(int n, int nPhi, int samplesPerAxis, int threads, LtcTables& out);
// Node values of the anisotropic grid: α = max((i/(n−1))², 1e-3); cos θ = 1 − (t/(n−1))² with θ <= 0.9999·π/2;
// φ = k/(nPhi−1)·π/2.
double anisoAlpha(int i, int n);
double anisoCosTheta(int t, int n);
double anisoPhi(int k, int nPhi);

// The shipped configuration (tools/ltc-fit and the drift test use these).
constexpr int kShippedNs = 32;
constexpr int kShippedAnisoSize = 8;
constexpr int kShippedAnisoPhiSize = 8;
constexpr int kShippedAnisoSamples = 16;

struct FitTimes {
    double iso = 0, sphere = 0, aniso = 0;  // seconds (iso includes its mag/fres)
};
// Every shipped table, as builtinTables() holds them.
LtcTables fitAllTables(int threads, FitTimes* times = nullptr);

}  // namespace specula::ltc
