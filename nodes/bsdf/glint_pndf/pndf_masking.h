// Shadowing-masking of the position-normal manifold P-NDF (Wu et al. 2024): the footprint's projected area Ā(ω)
// by the exact per-triangle integral (paper Eq. 9, App. B) and the grazing GGX fit of spec §4.2, for G = G1·G1.
//
// Spec: shared/specs/pndf-manifold.md §4 (separable Smith form G1 = cosθ/A), §4.1 (canonical frame, visible region
// V = right half-disk ∪ left half-ellipse, Green/Stokes boundary integral, clamp of A to [cosθ, 1]), §4.2 (grazing
// projected area A(φ) = α(φ)/2 of GGX, least-squares fit of (2A)², eigen-decomposition, anisotropic GGX Smith G1
// of Heitz 2014), §6 invariant 7 (Ā(0) = 1, flat map Ā = cosθ, Ā >= cosθ, Π_T against Monte Carlo).
#pragma once

#include "nodes/bsdf/glint_pndf/pndf_eval.h"
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"

#include <cstddef>
#include <vector>

namespace specula::pndf {

// Vertices of a normal triangle are pulled radially inside |s| <= kMaxProjectedRadius before integrating: the
// integrand ⟨ω,m⟩/m_z has an integrable 1/sqrt(1-|s|²) singularity on the rim, and float normals with n_z = 0 (or an
// equilateral replacement E of radius 6.2e-4 around a rim vertex, spec §2.3) would otherwise poke out of the disk.
// Pulling a vertex in changes Π_T by O(1e-9·length), far below every tolerance, and the normaliser of projectedArea
// uses the same pulled-in triangles, so Ā(0) = 1 still holds exactly.
constexpr double kMaxProjectedRadius = 1.0 - 1e-9;

// Π_T(ω) = ∬_{s(T) ∩ V} ⟨ω, m(s)⟩ / m_z d²s, m(s) = (s, sqrt(1-|s|²)), V = {⟨ω,m⟩ >= 0} (spec §4.1), exactly (to
// round-off) by the boundary integral. ω must be a unit vector with ω_z > 0 (ω_z <= 0 returns 0: nothing is lit
// from below the macro surface). The triangle's orientation does not matter (Π_T >= 0).
double triangleProjectedArea(const ManifoldTriangle& t, const Vec3& w);

// The normal triangle's s-area after the vertex pull-in above (|J|/2 otherwise): Π_T at ω = (0,0,1).
double triangleNormalArea(const ManifoldTriangle& t);

// The kernel mass of a triangle's texel area, g_T = ∫_{x(T)} K(x - x_q) dx, the weight projectedArea gives Π_T/|J_T|.
// Triangles inside the kernel support: box/disk exact; the Gaussian by the edge-midpoint rule (exact up to
// quadratics) on n² sub-triangles, n = ceil(3/σ_min) (its std is σ/3). Triangles cut by the support boundary: the
// box kernel is exact on the triangle clipped to the box, the Gaussian uses the same rule on the clipped polygon's
// fan, and the disk is exact (triangle ∩ ellipse area by the polygon-circle formula, after scaling to a unit circle).
double triangleKernelMass(const ManifoldTriangle& t, const Footprint& fp);

struct ProjectedAreaOptions {
    // Fast path: when the footprint's support box holds more than maxCells cells (0 = no limit, the exact sum),
    // only one cell per k x k block is integrated, k = ceil(sqrt(cells/maxCells)), picked by a deterministic hash of
    // the block (stratified sampling, which avoids aliasing with periodic maps that a fixed stride would have).
    // Numerator and normaliser use the same cells, so Ā(0) = 1 and the flat-map Ā = cosθ stay exact.
    // Cost of the exact sum is ~200 ns per cell (σ = 64: 129² cells, ~3.6 ms); maxCells = 1024 bounds a call to
    // ~0.15 ms at a relative error of ~5e-4 on a bumpy map (test SubsamplingAccuracyAndCost).
    int maxCells = 0;
};

// What one projectedArea call summed: the normaliser Σ_T 2g_T |s(T)|/|J_T| (the discrete kernel mass, ≈ ∫K = 1 up to
// the kernel quadrature; with subsampling, ≈ the mass of the sampled cells), the cells integrated and the stride k.
struct ProjectedAreaStats {
    double kernelMass = 0;
    long cellsIntegrated = 0;
    int stride = 1;
};

// Ā(ω) = Σ_T g_T Π_T(ω)/|J_T| / Σ_T g_T Π_T(n)/|J_T| over both triangles of every cell of the footprint's support box
// (spec §4.1: brute force, no hierarchy). Π_T/|J_T| = ∫_{x(T)} ⟨ω,m⟩₊/m_z dx is the change of variables from
// s-area to texel area (the affine map of a replaced triangle is exact too, so the same formula holds there), and
// g_T = triangleKernelMass is the footprint's own kernel over the triangle (the spec's code uses equal weights on
// a box of cells instead). The normaliser Σ 2g_T |s(T)|/|J_T| ≈ ∫K = 1 makes Ā(ω = n) = 1 exactly (invariant 7).
// ω: unit vector in the shading frame; returns 0 for ω_z <= 0.
double projectedArea(const PndfManifold& m, const Footprint& fp, const Vec3& w, const ProjectedAreaOptions& opt = {},
                     ProjectedAreaStats* stats = nullptr);

// The footprint's mean tilt E_K[s/m_z] = ∫ K s/m_z dx / ∫ K dx (GgxAlpha::tiltX/Y) over every cell of its support box,
// by the midpoint rule on sub-triangles (finer where σ is a few texels). The GGX fit stores the tilt of 2^ℓ blocks; a
// footprint of a few texels leans as its own facets do, which this gives at (2σ+1)² cells of cost.
Vec2d footprintTilt(const PndfManifold& m, const Footprint& fp);

// Spec §4: G1 = cosθ / clamp(A, cosθ, 1), so G1 ∈ [cosθ, 1] ⊂ (0, 1] for ω_z > 0; 0 for ω_z <= 0.
double smithG1FromProjectedArea(double area, double cosTheta);
double smithG1Analytic(const PndfManifold& m, const Footprint& fp, const Vec3& w, const ProjectedAreaOptions& opt = {});

// Anisotropic GGX roughness of spec §4.2: α(φ)² = α1² cos²(φ-φ0) + α2² sin²(φ-φ0), α1 >= α2 >= 0, φ0 the azimuth
// (radians, in (-π/2, π/2]) of the α1 axis in the shading frame (x = tangent = u).
struct GgxAlpha {
    double alpha1 = 0, alpha2 = 0, phi0 = 0;
    // The footprint's mean tilt t = E_K[s/m_z] (= -mean ∇h): the projected area of its mean plane per unit texel area
    // is e(ω) = ω_z + ω_xy·t. smithG1GgxFit shears the GGX lobe by it (0: the centred GGX of spec §4.2).
    double tiltX = 0, tiltY = 0;
    double alphaSquaredAt(double phi) const;
};

// Eigen-decomposition of [[a, e/2], [e/2, b]] (the fit (2A)² ≈ a cos²φ + b sin²φ + e cosφ sinφ) into GgxAlpha;
// negative eigenvalues of a degenerate fit are clamped to 0.
GgxAlpha ggxAlphaFromFit(double a, double b, double e);

// Smith G1 = cosθ / max(A(ω), cosθ) of the GGX slope distribution sheared by the footprint's mean tilt: with the
// 1D GGX slope marginal along ω's azimuth (a Student-t of ν = 2, scale α(φ)), E[(q - μ)₊] = (sqrt(α² + μ²) - μ)/2 gives
// the projected area A(ω) = (e + sqrt(α(φ)² |ω_xy|² + e²))/2 with e = ω_z + ω_xy·t (the mean plane's projected area;
// the shifted-slope construction of LEAN's Beckmann Λ, Olano & Baker 2010). Untilted (t = 0) this is Heitz 2014's
// anisotropic GGX Smith 2 / (1 + sqrt(1 + α(φ)² tan²θ)). The tilt keeps the lobe's albedo ≤ 1 where a small
// footprint's facets lean towards a grazing viewer, which the centred GGX of the paper's code does not (its G1 ≈ 1
// there while ∫ D⟨ω,m⟩ = e(ω) > cosθ). A is clamped below at cosθ (G1 <= 1) only: spec §4.1 also clamps it at 1, which
// would let such footprints reflect more than they receive. 0 for ω_z <= 0.
double smithG1GgxFit(const GgxAlpha& alpha, const Vec3& w);

// The grazing (θ = 90°) projected area of cell (row, col) per unit texel area, A(φ) = Σ_{T in cell} Π_T/|J_T|, with
// ω = (cosφ, sinφ, 0) (spec §4.2). Row/col unwrapped.
double cellGrazingArea(const PndfManifold& m, int row, int col, double phi);

// Spec §4.2: per cell the grazing A(φ) at `azimuths` angles φ_k = 2πk/K, the linear least-squares fit
// α(φ)² ≈ a cos²φ + b sin²φ + e cosφ sinφ, and MIP averages of (a, b, e) and of the cell's mean tilt t = ∫ s/m_z dx
// over 2^ℓ x 2^ℓ blocks. The spec fits (2A)², the centred GGX's α(φ)² at grazing; we fit the sheared GGX's
// α(φ)² = 4A(A - e_φ) with e_φ = (cosφ, sinφ)·t (smithG1GgxFit at θ = 90°), which is (2A)² for an untilted cell and
// leaves the odd part of A(φ), the tilt, to t instead of the π-periodic basis that cannot represent it.
// Deviation from the spec, documented: the spec averages A over a block and then fits; averaging the per-cell
// coefficients instead is (the fit being linear in its data) the fit of the block-averaged (2A)², which differs from
// (2·mean A)² by the block's variance of 2A. It lets one pass build every level from the cells.
// Storage: float (a, b, e, t_x, t_y) per node from level 1 (2x2 cells) up, the level-0 cells are not kept:
// 20·(4^10-1)/3 B = 6.7 MiB for a 1024² map. Levels exist while width and height are divisible by 2^ℓ (level 0 is kept instead
// when a side is odd). Build: TBB parallel_for over level-1 rows; every node is computed independently in a fixed
// order, so the result does not depend on the thread count.
class PndfGgxFit {
public:
    explicit PndfGgxFit(const PndfManifold& m, int azimuths = 32);

    int firstLevel() const { return firstLevel_; }
    int levelCount() const { return static_cast<int>(levels_.size()); }  // levels firstLevel .. firstLevel+count-1
    int azimuths() const { return azimuths_; }

    struct Coeffs {
        float a, b, e;
        float tiltX, tiltY;
    };
    // Fit of node (row, col) at `level` (firstLevel <= level < firstLevel + levelCount), row/col unwrapped.
    const Coeffs& node(int level, int row, int col) const;

    // The level whose node size matches the footprint, 2^ℓ ≈ 2·max(σ_u, σ_v) (rounded in log2, clamped to the
    // stored levels), its (a, b, e) bilinearly interpolated at the footprint centre between node centres (periodic),
    // then eigen-decomposed.
    GgxAlpha alphaAt(const Footprint& fp) const;
    int levelFor(const Footprint& fp) const;

    size_t memoryBytes() const;

private:
    int width_ = 0, height_ = 0, azimuths_ = 0, firstLevel_ = 0;
    std::vector<std::vector<Coeffs>> levels_;
};

}  // namespace specula::pndf
