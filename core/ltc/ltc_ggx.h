// LTCs of the renderer's GGX-family lobes from the fitted tables: isotropic, anisotropic and roughness-matrix GGX, and
// the Fresnel weighting F0·mag + (1 − F0)·fres of ltc_code's 2017 revision (exact for Schlick).
#pragma once

#include "core/ltc/ltc_tables.h"
#include "core/render/lobes/fresnel.h"

namespace specula::ltc {

// The LTC of GGX with the roughness matrix A = [[a, c], [c, d]] (entries α², the slope covariance scale of
// filtered-ggx.md; a = αx², d = αy², c = 0 for an axis-aligned lobe), for unit wo in the lobe frame. Isotropic A
// uses the 64×64 Nelder-Mead table; otherwise the principal axes of A (eigenvectors) select the anisotropic table
// and the rotation into them is folded into invM.
Ltc ggxRoughnessMatrix(const LtcTables& t, double a, double c, double d, const Vec3& wo);

// The Schlick-equivalent reflectance a Fresnel term gives an LTC integral: F0·mag + (1 − F0)·fres with F0 = F(1).
// Exact for Mode::One (mag) and Schlick; for dielectrics and conductors it is the Schlick approximation with their
// normal-incidence reflectance (documented in docs/ltc-tables.md, measured in tests/unit/test_ltc_lobes.cpp).
Color3 fresnelScale(const Fresnel& f, const Ltc& l);

// ∫_P f·cos of a GGX-family lobe described by 'l' and 'f' (tint applied by the caller), and its polygon sampling.
Color3 integrateGgx(const Ltc& l, const Fresnel& f, const Vec3* vertices, int n, uint8_t horizon);

}  // namespace specula::ltc
