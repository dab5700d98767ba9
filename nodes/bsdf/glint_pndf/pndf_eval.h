// Exact position-normal NDF D_P(s) of a footprint on a PndfManifold (Wu et al. 2024 Eq. 5, spec §2.2): the sum
// over the normal triangles whose image contains s of K(x_T(s) - x_q)/|J_T|, by brute force or min-max traversal.
//
// Spec: shared/specs/pndf-manifold.md §1 (kernels and their normalisation, footprint half-widths), §2.2 (hit test by
// Cramer's rule, contribution K/|J|), §2.3 (clamped triangles are inverted through the same affine map), §3.1 (entry
// level, node index range, stack traversal). D_P is a pdf over the projected disk (∫ D_P d²s = ∫ K = 1, paper Eq. 2),
// and also the microfacet D in solid angle since d²s = cosθ_m dω_m. Clusters (§3.2) are optional in the traversal.
#pragma once

#include "nodes/bsdf/glint_pndf/pndf_manifold.h"

#include <cstdint>

namespace specula::pndf {

enum class FootprintKernel : uint8_t { Gaussian = 0, Box = 1, Disk = 2 };

// An axis-aligned footprint in texel units (spec §1): centre x_q = (x, y) with x along columns (u) and y along
// rows (v), half-widths σ_u, σ_v in texels.
struct Footprint {
    double centreX = 0, centreY = 0;
    double sigmaU = 1, sigmaV = 1;
    FootprintKernel kernel = FootprintKernel::Gaussian;
    // Spec §1: the authors' Gaussian (std σ/3, truncated to the |Δ| <= σ box) is not renormalised, mass 0.99461.
    // true (default) divides by the truncated mass so that ∫ D_P = 1 for every kernel and sampling by the inverse CDF
    // of the Gaussian truncated to the box (pndf_sample.h; the spec §2.4 fix) matches eval exactly; false reproduces
    // the authors' code.
    bool gaussianUnitMass = true;

    // Footprint from texture coordinates: x = frac(u·tiles)·N along columns (spec §1), σ already in texels.
    static Footprint fromUv(Vec2 uv, double tiles, int width, int height, double sigmaU, double sigmaV,
                            FootprintKernel kernel);
};

// Spec §1: σ_u = k·(|∂u/∂X| + |∂u/∂Y|)/2 (likewise σ_v) from the untiled uv's per-pixel ray differentials, in
// texels of a map of `texels` across one uv unit (N·tiles), clamped to [1, 128].
double footprintHalfWidth(double duDX, double duDY, double scaleK, double texels);

// The truncated Gaussian's mass inside its ±3-std box: erf(3/√2)² = 0.994608 (spec §1).
double truncatedGaussianMass();

// Normalised kernel K_σ(Δ) on the texel plane (spec §1), zero outside the box (Gaussian, box) or ellipse (disk).
double kernelWeight(const Footprint& fp, double dx, double dy);

// The contribution of one triangle to D_P(s): K(x_T(s) - x_q)/|J_T| when s lies in its normal image (closed
// edges), else 0. Spec §2.2 Cramer's rule; the same affine map inverts replaced triangles (§2.3).
double triangleContribution(const ManifoldTriangle& tri, const Vec2d& s, const Footprint& fp);

// Work counters of one query, for benchmarks and the culling tests.
struct EvalStats {
    uint64_t nodesVisited = 0;      // hierarchy nodes popped (brute force: 0)
    uint64_t cellsTested = 0;       // cells whose two triangles were hit-tested
    uint64_t trianglesHit = 0;      // triangles containing s with a non-zero kernel weight
    uint64_t clustersUsed = 0;      // cluster nodes whose two triangles replaced their subtree
};

// Inclusive range of cells (level 0) or nodes of level ℓ that the footprint's support box touches, per axis:
// i_lo = ⌊(x_q-σ)/2^ℓ⌋, i_hi = ⌈(x_q+σ)/2^ℓ⌉-1 (spec §3.1, Appendix C). Unwrapped indices.
struct IndexRange {
    int colLo, colHi, rowLo, rowHi;
};
IndexRange footprintRange(const Footprint& fp, int level);

// Spec §3.1 entry level ℓ0 = clamp(⌈log2 max(σ_u,σ_v)⌉ + 1, 0, levelCount-1).
int entryLevel(const PndfManifold& manifold, const Footprint& fp);

// D_P(s) by testing both triangles of every cell in the footprint's support box (spec §6 invariant 5's reference).
double evalPndfBruteForce(const PndfManifold& manifold, const Footprint& fp, const Vec2d& s,
                          EvalStats* stats = nullptr);

// Spec §3.1/§3.2: clusters are used at levels 1..4 (B = 2..16); the B = 32 level is built but not queried.
// Measured (bench_pndf --calibrate, issue 12 item 8): allowing level 5 changes nothing at any ε_c (node counts within
// 2% at 128 texels across, uniform and kernel-weighted test alike), since a B = 32 block's fit error is ~20x a B = 16
// one's and it fails the test first.
constexpr int kMaxQueryClusterLevel = 4;

// Default ε_c of the cluster test (clusterAccepted): r < ε_c σ_u σ_v (spec §3.2), for the Gaussian kernel
// r·K_max(node)/K(0) < ε_c σ_u σ_v; r = the true float64 fit error of paper Eq. 7 (Σ_T w_T ∫_T |ŝ-s|²,
// w_T = 1/max(|J_T|, ε_J), in texel²·s²/|J| units). What r·K/(σ_uσ_v) means: up to the kernel's constant it is the
// node's share of ∫ K(x) |ŝ(x)-s(x)|²/|J(x)| dx, the kernel-mass-weighted squared normal error counted in units of
// the local normal-triangle size, so the test bounds each cluster's error relative to the NDF's own resolution.
// Calibrated with bench_pndf --calibrate on the bumps / brushed / scratches maps of core/texture/normal_map_gen.h at
// 1024², footprints 4..128 texels across (table in bench/bench_pndf.cpp's header): the largest half-decade at which
// the relative L1 error of D against the exact sum stays <= ~0.02 (the error of the paper's default in Tab. 3) at
// every footprint on all three maps; bumps bind (1e-5 gives 0.047 at 128 texels across). At this setting clusters
// give only 1.0-1.2x: the ≥10x of issue 12 item 8 needs ε_c ≈ 0.1 on brushed (14.6x fewer nodes, 9.7x time) at
// ~0.28 relative L1 error of D, and is not reached on bumps or scratches at any usable ε_c, so trading accuracy for
// speed is left to the material. Also measured: r normalised by Σ w_T|T| (a weighted mean squared normal error), and
// further by the node's squared s-extent: they line the maps' transitions up within a decade but give no better
// speed at equal error, so the raw fit error stays (spec §3.2's definition).
constexpr double kDefaultClusterThreshold = 3e-6;

// D_P(s) by the min-max quadtree (spec §3.1): from the entry level, nodes whose normal bounds exclude s, or whose
// texel extent misses the kernel support (box range, and the ellipse for the disk kernel), are culled; cells of
// the surviving level-0 nodes are hit-tested. Equal to the brute force up to summation order when
// clusterThreshold = 0. With ε_c = clusterThreshold > 0, a node at level 1..4 whose cluster residual
// r < ε_c σ_u σ_v is replaced by its two cluster triangles (spec §3.2; r is the true fit error, so the paper's ε
// values, which apply to the code's normal-equation residual, do not carry over: see kDefaultClusterThreshold). Level-0
// nodes are culled by PndfManifold::cellMayContain (level-0 bounds are not stored), a superset of their bounds.
double evalPndfHierarchy(const PndfManifold& manifold, const Footprint& fp, const Vec2d& s,
                         EvalStats* stats = nullptr, double clusterThreshold = 0.0);

// The cluster test of spec §3.2 that evalPndfHierarchy applies to node (row, col) of `level`: the level is 1..4 (and
// built) and its residual r < ε_c σ_u σ_v, for the Gaussian kernel r·K_max(node)/K(0) < ε_c σ_u σ_v (a deviation
// from the spec, see kDefaultClusterThreshold; nested in ε_c, so invariant 6's coarser-cut order holds). Sampling
// (spec §2.4 step 2) uses the same test, top-down from the entry level, so that it draws from the representation
// eval sums over.
bool clusterAccepted(const PndfManifold& manifold, int level, int row, int col, const Footprint& fp,
                     double clusterThreshold);

// Union of the level-0 normal bounds of the cells in the footprint's support: an s-AABB that holds D_P's support.
NormalBounds footprintNormalBounds(const PndfManifold& manifold, const Footprint& fp);

}  // namespace specula::pndf
