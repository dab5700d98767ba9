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

// [OWNED BY THE TABLE HELPER] Student-t (ν = 2) maximum-likelihood fit of an LTC to weighted directions
// (ltc-filtering.md §5.2 steps 1-4). 'tangentHint' fixes X by Gram-Schmidt so neighbouring fits are consistent.
// Returns the LTC (invM normalised as documented in the implementation) with magnitude = mean sample weight.
Ltc fitStudentT(const std::vector<WeightedDirection>& samples, const Vec3& tangentHint, int iterations = 30);

}  // namespace specula::ltc
