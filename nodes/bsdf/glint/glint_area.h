// Glints under polygonal (quad) lights, issue 11 item 2: the integral of the glint BRDF times cos over a light's
// solid angle, computed per EWA cell from the dictionary's cumulative marginals instead of point-sampling the light.
//
// Change of variables (ω_i -> half vector -> half slope h~ = (-h_x/h_z, -h_y/h_z)):
//   dω_i = 4 (wo·h) dω_h   (reflection Jacobian, Walter et al. 2007 Eq. 14 inverted)
//   dω_h = h_z^3 dh~       (slope space: the Jacobian of h~ -> h = (-h~, 1)/|(-h~, 1)|)
// so with f cos = F G D / (4 wo.z) and D = P(h~) / h_z^4 (C20 Eq. 14):
//   ∫_light f cos dω_i = ∫_R F G P(h~) (wo·h) / (h_z wo.z) dh~                                           (A1)
// over R, the light's region of half slopes. The smooth factor G (wo·h)/(h_z wo.z) is taken at each cell's mass
// centroid in R (first moments by the same edge integrals), F at the mass-weighted centroid of all cells; P is the LOD blend of EWA averages of cell SDFs (C20 Eq. 3), and
// a cell's SDF det(M^-1) p_i(|m_x|) p_j(|m_y|), m = Rot(-θ) M^-1 h~, integrates over R to the mass of the separable
// p_i(|x|) p_j(|y|) over the convex-ish polygon Rot(-θ) M^-1 R (det(M^-1) is the Jacobian dm/dh~). By Green's theorem
//   ∫∫_Q p_i(x) p_j(y) dx dy = -∮_∂Q p_i(x) F_j(y) dx,   F_j(y) = ∫_0^y p_j = Dictionary::marginalCdf      (A2)
// for any simple counter-clockwise polygon Q. Along an edge y is linear in x, p_i is piecewise linear in x between
// texel centres and F_j piecewise quadratic in y between texel centres, so between consecutive breakpoints of both
// grids the integrand is a cubic and Simpson's rule is exact: the cell integral is exact for the polygonal R.
// The only approximations are the polygonal R (the images of the light's great-circle edges are curves, split
// adaptively into chords) and the smooth factor at the centroids. Converged cells (k = L) and the no-footprint case integrate the Beckmann SDF,
// which in m-space is the isotropic N(0, σ_o² I) whatever the cell's rotation (M M^T = Σ/σ_o², C21 Eq. 18), through
// the same (A2) with Gaussian p and erf F (Simpson on σ_o/8 steps).
// GGAA (C21 §4.2): each cell's marginals are integrated at the MIP blend textureGrad1D selects for the kernel gradients
// of the light's centre direction (exact CDFs of every MIP level). The light's extent filters over h~ but not over the
// pixel's change of h (curvature): without it the 16-spp pixel-centre torus of test_glint_area.cpp had RMSE 0.040 and
// bias -1.3 % against GGAA renders, with it 0.003 and -0.02 %. The residual is GGAA's variation of the MIPs across
// the light (max 1.9 % per query against Monte Carlo).
#pragma once

#include "nodes/bsdf/glint/glint_bsdf.h"

#include <cstdint>

namespace specula::glint {

using DVec2 = glm::dvec2;

struct GlintAreaSettings {
    // The images of the light's great-circle edges in half-slope space are curves: they are split into chords until
    // the arc's midpoint lies within this distance of its chord in M^-1 space (the cell distributions' space, whose
    // lobes are σ_l = 0.02 wide); at most 2^maxDepth chords per edge (maxDepth <= kMaxChordDepth). Error measured in test_glint_area.cpp.
    float chordTolerance = 1e-4f;
    int maxDepth = 6;
    // The light is split into up to 4^maxSplitDepth pieces until the smooth factor G (wo·h)/(h_z wo.z) spreads by at
    // most splitTolerance (relative) over each piece's corners and centre (the V-cavity G is not smooth: a kink
    // and a fall to 0 at the horizon).
    float splitTolerance = 0.1f;
    int maxSplitDepth = 2;
    // Pieces where that spread is below this use the factor at their area centroid and the cells' masses alone
    // (half the table reads of the moments).
    float constantFactorSpread = 0.1f;
};

struct GlintAreaResult {
    float integral = 0.f;  // ∫_light G D/(4 wo.z) cos dω_i without the Fresnel factor (A1 with F = 1)
    Vec3 hCentroid{0, 0, 1};  // half vector at R's centroid: where the caller evaluates F (wo·h)
    int cells = 0;            // cells visited (both LODs)
};

// The half-slope region R of a light polygon (lobe frame, vertices relative to the shading point, CCW from it) for wo:
// the polygon clipped to wi.z > 0, its edges split into chords, each vertex mapped to h~. Returns the vertex count
// (0: invisible); 'out' is counter-clockwise in the h~ plane and needs kMaxRegionVertices entries.
constexpr int kMaxChordDepth = 6;
constexpr int kMaxRegionVertices = 5 << kMaxChordDepth;  // the clipped quad's <= 5 edges, 2^depth chords each
int halfSlopeRegion(const Vec3& wo, const Vec3* vertices, int count, const GlintShape& shape,
                    const GlintAreaSettings& settings, DVec2* out);

// ∫_light f_glint cos dω_i / F (A1) for one shading point. False when the light is invisible from the lobe's side.
bool glintPolygonIntegral(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                          const GlintEvalInputs& in, const Vec3& wo, const Vec3* vertices, int count,
                          GlintAreaResult& out, const GlintAreaSettings& settings = {});

// The mass ∫∫_Q p_i(|x|) p_j(|y|) dx dy of the separable cell distribution of dictionary level k (< kLevels) over a
// polygon Q in m-space (A2, exact for the polygon), each marginal read at the MIP blend of textureGrad1D (GGAA;
// default: MIP 0, unfiltered). Exposed for the tests.
double cellPolygonMass(const Dictionary& dict, int k, int i, int j, const DVec2* q, int n, MipBlend bx = {},
                       MipBlend by = {});
// The same for the isotropic Gaussian N(0, σ_o² I): the Beckmann SDF of converged cells, in m-space.
double gaussianPolygonMass(const DVec2* q, int n);
// Mass and first moments (∫∫ p, ∫∫ x p, ∫∫ y p) of both, by the same edge integrals.
DVec3 cellPolygonMoments(const Dictionary& dict, int k, int i, int j, const DVec2* q, int n, MipBlend bx = {},
                         MipBlend by = {});
DVec3 gaussianPolygonMoments(const DVec2* q, int n);

// A direction for the shadow ray of the ratio estimator (Heitz, Hill & McGuire 2018), deterministic from (u, seed):
// a point of the light with density ∝ cos θ_i (Malley's method, ltc::samplePolygon with the identity LTC). Not ∝ the
// glint integrand (the ratio's visibility would be a cosine-weighted average over the light): the fallback below.
bool glintSamplePolygon(const Vec3* vertices, int count, const Vec2& u, uint64_t seed, Vec3& wi);
// What GlintLobe::samplePolygon uses: approximately ∝ the glint integrand. A cell is picked with probability ∝ its
// share of the integral (level weight x EWA weight x mass x smooth factor; the integral is recomputed, recording the
// cells), then a point of its slope distribution inside the light's region by inverting its marginals' CDFs over the
// region's bounding box (MIP 0) with rejection, mapped back to wi = reflect(wo, h). Falls back to glintSamplePolygon
// when no try lands inside.
bool glintSamplePolygonByCells(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                               const GlintEvalInputs& in, const Vec3& wo, const Vec3* vertices, int count,
                               const Vec2& u, uint64_t seed, Vec3& wi, const GlintAreaSettings& settings = {});

// Explicit flakes (glint_flakes.h) under a quad light: each flake's Gaussian N(m_k, σ_f² I) over the light's
// half-slope region, in m' = (h~ - m_k) σ_o / σ_f where it is the isotropic N(0, σ_o² I) of gaussianPolygonMoments
// (exact for the polygonal region), the smooth factor at its centroid in each piece of the light (splitLight, as the
// cells); the footprint's flakes weighted as in flakeSetSdf. integral: ∫_light G D_flakes / (4 wo.z) cos dω_i without
// F; hCentroid: where the caller evaluates F. False when the light is invisible.
bool flakePolygonIntegral(const FlakeSet& flakes, float sigmaF, const Vec3& wo, const Vec3* vertices, int count,
                          GlintAreaResult& out, const GlintAreaSettings& settings = {});
// A shadow-ray direction with density ∝ that integrand, approximately: a flake by its share, a piece of the light by
// the flake's mass in it, then a point of the flake's Gaussian restricted to the piece (per axis by inversion of its
// CDF over the piece's bounding box in m', then rejection), deterministic from (u, seed); the cosine-weighted
// glintSamplePolygon when no try lands inside.
bool flakeSamplePolygon(const FlakeSet& flakes, float sigmaF, const Vec3& wo, const Vec3* vertices, int count,
                        const Vec2& u, uint64_t seed, Vec3& wi, const GlintAreaSettings& settings = {});

}  // namespace specula::glint
