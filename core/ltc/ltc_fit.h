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

}  // namespace specula::ltc
