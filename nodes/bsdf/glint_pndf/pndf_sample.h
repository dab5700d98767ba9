// Importance sampling of the position-normal manifold P-NDF (Wu et al. 2024): draws a projected normal s with pdf
// exactly D_P(s) as evalPndfHierarchy computes it, for the BSDF sampling of the glint lobe (spec §5 NEE/MIS).
//
// Spec: shared/specs/pndf-manifold.md §2.4 (sampling: x ~ K_σ, the representation eval uses at x, the affine map of
// its triangle) with both consistency fixes (the Gaussian is truncated to the |Δ| <= σ box like eval; the bounds
// cover cluster and original vertices, pndf_manifold.cpp), §1 (kernels), §2.1 (T⁺/T⁻ split), §2.3 (replaced
// triangles keep their x parametrisation, so their kernel mass), §3.1 (entry level), §3.2 (cluster test, through
// clusterAccepted), §6 invariants 4 (histogram agreement) and 8 (E[g(s)] = ∫ g D_P). Paper Sec. 4.1 / Eq. 5.
//
// Measure of the pdf. samplePndf draws s with density p(s) = Σ_k K(x_k - x_q)/|det ∂s/∂x(x_k)| over the preimages
// x_k of s in the representation eval uses, i.e. p(s) = evalPndfHierarchy(m, fp, s, nullptr, clusterThreshold) in
// the d²s measure (spec §1: D_P is a pdf over the projected disk). For the microfacet normal h = m(s) =
// (s, sqrt(1-|s|²)), d²s = cosθ_h dω_h, so the solid-angle pdf of h is D_P(s)·cosθ_h, and that of the reflected
// direction ω_o = reflect(ω_i, h) is D_P(s)·cosθ_h/(4|ω_o·h|) (spec §2.4, §5).
// With fp.gaussianUnitMass == false (authors' code reproduction) the sampler still draws the *normalised* truncated
// Gaussian (a pdf must integrate to 1), while eval's kernel then carries mass erf(3/√2)² = 0.99461: the pdf of the
// sampled s is evalPndfHierarchy(...)/truncatedGaussianMass() in that mode (box and disk are unaffected).
#pragma once

#include "nodes/bsdf/glint_pndf/pndf_eval.h"
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"

namespace specula::pndf {

// Inverse of the standard normal CDF Φ for p in (0, 1): the rational approximation of P. J. Acklam (relative error
// < 1.2e-9) refined by one Halley step on Φ(z) - p computed with std::erfc, giving ~1e-15 relative accuracy on z.
// Returns ∓infinity for p <= 0 / p >= 1 and NaN for NaN. Pure function (no state): deterministic and thread-safe.
double inverseNormalCdf(double p);

// Draws a texel position x ~ K_σ (the normalised, truncated kernel eval uses) from two uniforms in [0,1):
// Gaussian: per axis inverse CDF of the Gaussian (std σ/3) truncated to |Δ| <= σ (exact, no rejection: this is the
// spec §2.4 truncation fix, consistent with gaussianUnitMass = true); box: uniform; disk: r = σ sqrt(u1), angle 2π u2
// (elliptic: Δ = (σ_u r cos φ, σ_v r sin φ)). Returns the offset Δ = x - x_q; it always lies in the kernel support
// (the box, or the closed ellipse for the disk).
Vec2d sampleKernelOffset(const Footprint& fp, double u1, double u2);

// Spec §2.4 steps 2-3: the manifold triangle that evalPndfHierarchy sums over at the (unwrapped) texel position
// (x, y) for this footprint and cluster threshold, and the triangle parameters (t1, t2) of that position, so that
// s = tri.sOrigin + t1·tri.sEdge1 + t2·tri.sEdge2 and (x, y) = tri.xOrigin + t1·tri.xStep1 + t2·tri.xStep2.
// Top-down from min(entryLevel, kMaxQueryClusterLevel): the first level ℓ >= 1 whose node holding x passes
// clusterAccepted gives its cluster triangle, else the cell's triangle at level 0 (eval descends the same way, so a
// node is used for x exactly when none of its ancestors was). T⁺ when the node-local ξ+η < 1, else T⁻ (spec §2.1).
// Returns the level the triangle came from (0 = cell, 1..4 = cluster).
int manifoldTriangleAt(const PndfManifold& m, const Footprint& fp, double clusterThreshold, double x, double y,
                       ManifoldTriangle& tri, double& t1, double& t2);

// Spec §2.4: draws s from D_P for the footprint: x = x_q + Δ with Δ = sampleKernelOffset(fp, u1, u2), then the
// representation eval uses at x (manifoldTriangleAt: cluster or cell triangle, T⁺ or T⁻), then the affine map of that
// triangle (replaced/equilateral triangles included, spec §2.3). Returns false only if no s could be produced (a
// non-finite or non-positive footprint, non-finite uniforms); s is then untouched. Optionally reports the unwrapped
// texel position x = x_q + Δ. s is not clipped to the unit disk: only an overshooting cluster fit can leave it, and
// the caller rejects such h (h_z <= 0) like eval's query does (spec §1).
bool samplePndf(const PndfManifold& m, const Footprint& fp, double clusterThreshold, double u1, double u2, Vec2d& s,
                Vec2d* x = nullptr);

}  // namespace specula::pndf
