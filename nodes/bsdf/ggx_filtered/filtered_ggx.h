// Filtered GGX (Tokuyoshi & Kaplanyan 2021, "TK21"): GGX with a 2×2 roughness matrix (NDF, Smith Λ, G2, τ clamp),
// the NDF-filtering variants (K16 slope space, TK21 projected space exact/approx, axis-aligned, isotropic) and a BsdfLobe.
//
// Spec: shared/specs/filtered-ggx.md. Everything here is in the local frame of the lobe (z = its normal, x = its
// tangent t, y = its bitangent b); screen derivatives are "per one-pixel step" along screen x (u) and y (v).
// Filter math runs in double (spec §3.3 [S]: "compute in double on the CPU"), except the per-query evaluation of
// projected_approx with analytic derivatives, which runs in float where its condition allows (FloatProjectedApprox).
#pragma once

#include "core/render/bsdf.h"
#include "core/render/lobes/fresnel.h"
#include "core/render/lobes/ggx.h"

#include <cmath>
#include <limits>
#if defined(__SSE__) || defined(_M_X64)
#include <xmmintrin.h>
#define SPECULA_FGGX_FLOAT_PATH 1  // FloatProjectedApprox is written in SSE; elsewhere every query runs in double
#else
#define SPECULA_FGGX_FLOAT_PATH 0
#endif

namespace specula::fggx {

constexpr double kPiD = 3.14159265358979323846;
constexpr double kDefaultSigma2 = 1.0 / (2.0 * kPiD);  // TK21 App. B: Gaussian pixel filter with peak 1
constexpr double kDefaultKappa = 0.18;                 // K16 / TK21 Listing 3 clamp

using D2 = glm::dvec2;
using D3 = glm::dvec3;

// Symmetric 2×2 matrix [[a, c], [c, d]] (roughness matrices, kernels).
struct Sym2 {
    double a = 0, c = 0, d = 0;
    static Sym2 diag(double x, double y) { return {x, 0, y}; }
    double det() const { return a * d - c * c; }
    double trace() const { return a + d; }
    Sym2 operator+(const Sym2& o) const { return {a + o.a, c + o.c, d + o.d}; }
    Sym2 operator-(const Sym2& o) const { return {a - o.a, c - o.c, d - o.d}; }
    Sym2 operator*(double s) const { return {a * s, c * s, d * s}; }
    bool operator==(const Sym2& o) const { return a == o.a && c == o.c && d == o.d; }
    // adj([[a, c], [c, d]]) = [[d, −c], [−c, a]]  (TK21 A.4)
    Sym2 adj() const { return {d, -c, a}; }
    // Eigenvalues, largest first: tr/2 ± sqrt((tr/2)² − det)  (TK21 Eq. 10)
    double eigMax() const {
        double h = 0.5 * trace();
        return h + std::sqrt(std::max(0.0, h * h - det()));
    }
    double eigMin() const {
        double h = 0.5 * trace();
        return h - std::sqrt(std::max(0.0, h * h - det()));
    }
    // Quadratic form vᵀ M v.
    double quad(double x, double y) const { return a * x * x + 2.0 * c * x * y + d * y * y; }
};

// Symmetric matrix product X Y X for symmetric X, Y (used by the first-order analysis of Eq. 8).
inline Sym2 sandwich(const Sym2& X, const Sym2& Y) {
    // X Y = [[xa ya + xc yc, xa yc + xc yd], [xc ya + xd yc, xc yc + xd yd]]
    double p = X.a * Y.a + X.c * Y.c, q = X.a * Y.c + X.c * Y.d;
    double r = X.c * Y.a + X.d * Y.c, s = X.c * Y.c + X.d * Y.d;
    return {p * X.a + q * X.c, p * X.c + q * X.d, r * X.c + s * X.d};
}

// Clamps the eigenvalues of a symmetric non-negative definite K at kappa (spec §3.5, option clamp_full_kernel).
inline Sym2 clampEigen(const Sym2& K, double kappa) {
    double l1 = K.eigMax(), l2 = K.eigMin();
    if (l1 <= kappa) return K;
    double c1 = std::min(l1, kappa), c2 = std::min(std::max(l2, 0.0), kappa);
    // Eigenvector of l1: (c, l1 − a) or (l1 − d, c).
    double vx = K.c, vy = l1 - K.a;
    if (std::abs(vx) + std::abs(vy) < 1e-300) vx = l1 - K.d, vy = K.c;
    double n2 = vx * vx + vy * vy;
    if (!(n2 > 0)) return Sym2::diag(c1, c1);  // isotropic: any basis
    vx /= std::sqrt(n2), vy /= std::sqrt(n2);
    // c1 v vᵀ + c2 (I − v vᵀ)
    return {c2 + (c1 - c2) * vx * vx, (c1 - c2) * vx * vy, c2 + (c1 - c2) * vy * vy};
}

// ---- Non-axis-aligned GGX with roughness matrix A (TK21 §2.1, App. A) ----------------------------------------------

// D(h) = χ⁺(h_z) / (π sqrt(det A) (h⊥ᵀ A⁻¹ h⊥ + h_z²)²)   (TK21 Eq. 1) with the determinant clamp of A.4:
// sqrt(max(det A, τ)) and A⁻¹ = adj(A) / max(det A, τ).
inline double ndf(const D3& h, const Sym2& A, double tau) {
    if (h.z <= 0.0) return 0.0;
    double det = std::max(A.det(), tau);
    double e = A.adj().quad(h.x, h.y) / det + h.z * h.z;
    return 1.0 / (kPiD * std::sqrt(det) * e * e);
}

// Smith Λ(w) = −1/2 + sqrt(w⊥ᵀ A w⊥ + w_z²) / (2|w_z|)   (TK21 A.3; Λ uses A, the NDF uses A⁻¹): Heitz's Λ
// (ggx::lambdaOfTan2) of α²tan²θ = w⊥ᵀ A w⊥ / wz², the general form of ggx::lambda (A = diag(αx², αy²)).
// GLSL twin: spc_ggx_lambda_matrix (nodes/shared/ggx_microfacet.glsl).
inline double lambda(const D3& w, const Sym2& A) {
    double z2 = w.z * w.z;
    if (z2 <= 0.0) return 1e300;
    return ggx::lambdaOfTan2(std::max(0.0, A.quad(w.x, w.y)) / z2);
}
inline double g1(const D3& w, const Sym2& A) { return 1.0 / (1.0 + lambda(w, A)); }
// Height-correlated G2 = 1 / (1 + Λ(i) + Λ(o))   (Heitz 2014, Eq. 99)
inline double g2(const D3& wo, const D3& wi, const Sym2& A) { return 1.0 / (1.0 + lambda(wo, A) + lambda(wi, A)); }

// Lower Cholesky factor L of A = L Lᵀ: [[l11, 0], [l21, l22]].
struct Chol2 {
    double l11 = 1, l21 = 0, l22 = 1;
};
inline Chol2 cholesky(const Sym2& A) {
    Chol2 L;
    L.l11 = std::sqrt(std::max(A.a, 1e-300));
    L.l21 = A.c / L.l11;
    L.l22 = std::sqrt(std::max(A.d - L.l21 * L.l21, 1e-300));
    return L;
}

// Visible-normal sampling of the matrix GGX (spec §2 [S]): o_s = normalize(Lᵀ o⊥, o_z), draw an α = 1 visible
// normal around o_s (Heitz 2018), map back with m = normalize(L m₁⊥, m₁_z). Slopes transform as s = L s₁, so the
// α = 1 slope distribution P(·, I) becomes P(·, L Lᵀ = A) (TK21 Eq. 5 notation), and o·m ∝ (Lᵀ o⊥)·m₁⊥ + o_z m₁_z.
inline D3 sampleVisibleNormal(const D3& wo, const Vec2& u, const Chol2& L) {
    D3 os(L.l11 * wo.x + L.l21 * wo.y, L.l22 * wo.y, wo.z);
    os = glm::normalize(os);
    Vec3 m1 = ggx::sampleVisibleNormal(Vec3(os), u, 1.f, 1.f);
    D3 m(L.l11 * m1.x, L.l21 * m1.x + L.l22 * m1.y, m1.z);
    return glm::normalize(m);
}

// D_wo(h) = G1(wo) max(0, wo·h) D(h) / wo_z   (Heitz 2018, Eq. 1; same Ā, τ in G1 and D)
inline double visibleNdf(const D3& wo, const D3& h, const Sym2& A, double tau) {
    double woh = glm::dot(wo, h);
    if (woh <= 0.0 || wo.z <= 0.0) return 0.0;
    return g1(wo, A) * woh * ndf(h, A, tau) / wo.z;
}

// A roughness matrix made ready for many evaluations: the clamped inverse and the normaliser of Eq. 1 computed once,
// so D(h) costs one division and Λ(w) one division and one square root. Same formulas as ndf() and lambda().
struct PreparedGgx {
    Sym2 A, inv;       // A and A⁻¹ = adj(A) / max(det A, τ)   (TK21 A.4)
    double norm = 0;   // 1 / (π sqrt(max(det A, τ)))
    PreparedGgx() = default;
    PreparedGgx(const Sym2& a, double tau) : A(a) {
        double r = 1.0 / std::max(a.det(), tau);
        inv = a.adj() * r;
        norm = std::sqrt(r) * (1.0 / kPiD);
    }
    // The bracket of Eq. 1, h⊥ᵀ A⁻¹ h⊥ + h_z²; D(h) = norm / e².
    double ndfBracket(const D3& h) const { return inv.quad(h.x, h.y) + h.z * h.z; }
    double lambda(const D3& w, double invZ2) const { return ggx::lambdaOfTan2(std::max(0.0, A.quad(w.x, w.y)) * invZ2); }
};

// ---- Filters (TK21 §3–5) -------------------------------------------------------------------------------------------

enum class Filter : int { None = 0, Slope, Projected, ProjectedApprox, IsoMax, IsoSum, IsoMean, IsoRect };
enum class Kernel : int { Full = 0, AxisAligned };
constexpr int kFilterCount = 8;
inline const char* filterName(Filter f) {
    static const char* n[] = {"none", "slope", "projected", "projected_approx", "iso_max", "iso_sum", "iso_mean", "iso_rect"};
    return n[int(f)];
}
inline bool isHalfVectorFilter(Filter f) { return f == Filter::Slope || f == Filter::Projected || f == Filter::ProjectedApprox; }

struct FilterParams {
    Filter filter = Filter::ProjectedApprox;
    Kernel kernel = Kernel::AxisAligned;
    double sigma2 = kDefaultSigma2;
    double kappa = kDefaultKappa;
    bool clampFullKernel = false;  // clamp the eigenvalues of 2Σ at κ for kernel = full (spec §3.5 [S])
};

// Σ(q) = σ² (Δ_u q Δ_u qᵀ + Δ_v q Δ_v qᵀ)   (K16 Σ∥; TK21 Eq. 3 Σ⊥)
inline Sym2 kernelOf(const D2& du, const D2& dv, double sigma2) {
    return {sigma2 * (du.x * du.x + dv.x * dv.x), sigma2 * (du.x * du.y + dv.x * dv.y), sigma2 * (du.y * du.y + dv.y * dv.y)};
}

inline double saturate(double x) { return std::min(std::max(x, 0.0), 1.0); }

// Eq. 2 (K16, q = h∥) and Eq. 9 (TK21 projected_approx, q = h⊥): Ā = A + 2Σ(q) for the full kernel; the
// axis-aligned kernel (Listing 3) adds min(2σ² fwidth(q)², κ) per axis and saturates (diagonal stays diagonal).
inline Sym2 filterAdditive(const Sym2& A, const D2& du, const D2& dv, const FilterParams& p) {
    if (p.kernel == Kernel::Full) {
        Sym2 K = kernelOf(du, dv, p.sigma2) * 2.0;
        if (p.clampFullKernel) K = clampEigen(K, p.kappa);
        return A + K;
    }
    double wx = std::abs(du.x) + std::abs(dv.x), wy = std::abs(du.y) + std::abs(dv.y);  // fwidth
    double kx = std::min(2.0 * p.sigma2 * wx * wx, p.kappa), ky = std::min(2.0 * p.sigma2 * wy * wy, p.kappa);
    return {saturate(A.a + kx), A.c, saturate(A.d + ky)};
}

// B = A (I − A)⁻¹ = (A⁻¹ − I)⁻¹   (TK21 Eq. 4); diagonal A: b = α²/(1 − α²).
inline Sym2 projectedRoughness(const Sym2& A) {
    Sym2 IA{1.0 - A.a, -A.c, 1.0 - A.d};
    double det = IA.det();
    Sym2 inv = IA.adj() * (1.0 / det);
    // A inv (symmetric because A and (I − A)⁻¹ commute)
    return {A.a * inv.a + A.c * inv.c, A.a * inv.c + A.c * inv.d, A.c * inv.c + A.d * inv.d};
}

// Exact projected-space filtering, TK21 Eqs. 4–7 in the App. D form (Listing 1 semantics):
//   B̄ = B + K,  d = max(det B̄, det B),  M = B̄/d + I,  Ā = M / max(det M, 1)
// with K = 2Σ⊥ (full kernel) or diag(min(2σ² fwidth(h⊥)², κ)) (axis-aligned; spec §3.5: b̄ = b + k', ᾱ² = b̄/(1 + b̄)).
// Fallbacks (spec §3.3 [S]): K = 0 → A exactly; λ_max(A) ≥ 0.998 (α ≥ 0.999) or an underflowing det B̄ → Eq. 9.
inline Sym2 filterProjected(const Sym2& A, const D2& du, const D2& dv, const FilterParams& p) {
    Sym2 K;
    if (p.kernel == Kernel::Full) {
        K = kernelOf(du, dv, p.sigma2) * 2.0;
        if (p.clampFullKernel) K = clampEigen(K, p.kappa);
    } else {
        double wx = std::abs(du.x) + std::abs(dv.x), wy = std::abs(du.y) + std::abs(dv.y);
        K = Sym2::diag(std::min(2.0 * p.sigma2 * wx * wx, p.kappa), std::min(2.0 * p.sigma2 * wy * wy, p.kappa));
    }
    if (K.a == 0.0 && K.c == 0.0 && K.d == 0.0) return A;
    if (A.eigMax() >= 0.998 || !(A.det() > 0.0)) return filterAdditive(A, du, dv, p);
    Sym2 B = projectedRoughness(A);
    Sym2 Bb = B + K;                              // Eq. 6: B̄ = B + 2Σ⊥
    double d = std::max(Bb.det(), B.det());       // App. D lower clamp (exact arithmetic: det B̄ ≥ det B)
    if (!(d > 1e-280)) return filterAdditive(A, du, dv, p);
    Sym2 M = Bb * (1.0 / d) + Sym2::diag(1.0, 1.0);
    return M * (1.0 / std::max(M.det(), 1.0));    // Eq. 7: Ā = (B̄⁻¹ + I)⁻¹ = M / det M
}

// Eq. 7 literally, (B̄⁻¹ + I)⁻¹, for tests of the App. D rewriting.
inline Sym2 unprojectRoughness(const Sym2& Bb) {
    Sym2 Binv = Bb.adj() * (1.0 / Bb.det());
    Sym2 M = Binv + Sym2::diag(1.0, 1.0);
    return M.adj() * (1.0 / M.det());
}

// Normal-based isotropic variants (TK21 §5), from the world- (or any orthonormal-) space normal derivatives Δ_u n,
// Δ_v n and, for iso_rect, the tangent-plane components of the slope derivative of the normal. Returns the kernel
// roughness² k ≥ 0 added to both axes (ᾱ² = α² + k, saturated):
//   iso_max  (Eq. 10): min(2 λ_max(Σ⊥), κ), Σ⊥ eigenvalues = σ² × eigenvalues of the Gram matrix of Δn (spec §3.6 [S])
//   iso_sum  (Eq. 13): min(2σ² (‖Δ_u n‖² + ‖Δ_v n‖²), κ)
//   iso_mean (Eq. 14): min(σ² (‖Δ_u n‖² + ‖Δ_v n‖²), κ)
//   iso_rect (K16 Listing 4): min(2σ² w², κ), w = max component of fwidth of the normal's tangent-space slope
inline double isotropicKernel(Filter f, const D3& dnu, const D3& dnv, const FilterParams& p) {
    double uu = glm::dot(dnu, dnu), vv = glm::dot(dnv, dnv), uv = glm::dot(dnu, dnv);
    switch (f) {
        case Filter::IsoMax: return std::min(2.0 * p.sigma2 * Sym2{uu, uv, vv}.eigMax(), p.kappa);
        case Filter::IsoSum: return std::min(2.0 * p.sigma2 * (uu + vv), p.kappa);
        case Filter::IsoMean: return std::min(p.sigma2 * (uu + vv), p.kappa);
        case Filter::IsoRect: {
            // Slope of n in the local frame: (n_x, n_y)/n_z; at n = z its derivative is (Δn_x, Δn_y).
            double w = std::max(std::abs(dnu.x) + std::abs(dnv.x), std::abs(dnu.y) + std::abs(dnv.y));
            return std::min(2.0 * p.sigma2 * w * w, p.kappa);
        }
        default: return 0.0;
    }
}
inline Sym2 filterIsotropic(const Sym2& A, double k) { return k == 0.0 ? A : Sym2{saturate(A.a + k), A.c, saturate(A.d + k)}; }

// ---- Half-vector derivatives (spec §5.1) ---------------------------------------------------------------------------

// Screen-space differentials of the shading point in the lobe's local frame (per one-pixel step along x, y).
struct Differentials {
    bool valid = false;
    D3 dwo[2]{};  // dwo/dx, dwo/dy
    D3 dn[2]{};   // dn/dx, dn/dy (of the shading normal; ⊥ n)
    D3 dp[2]{};   // dp/dx, dp/dy
};

// One neighbour of a 2×2 quad (CPU emulation of GPU dFdxFine/dFdyFine, spec §5.2), in this lobe's local frame.
struct QuadNeighbour {
    bool valid = false;
    double sign = 1.0;   // Δ = sign·(q(neighbour) − q(self)): +1 when this pixel is the quad's x0 (or y0)
    D3 dp{0.0};          // p(neighbour) − p(self)
    D3 wo{0.0};          // its view direction
    D3 t{1, 0, 0}, b{0, 1, 0}, n{0, 0, 1};  // its shading frame
};

// d wi / dx for a light sample at finite distance: −P(wi) dp/dx / |y − p|; zero for directional lights, environment
// and BSDF-sampled directions (invDist = 0).
inline D3 lightDirectionDerivative(const D3& wi, const D3& dp, double invDist) {
    if (invDist == 0.0) return D3(0.0);
    return -(dp - wi * glm::dot(wi, dp)) * invDist;
}

// q = h⊥ (projected, TK21 Eq. 3 / reading (a) of Listing 2) or h∥ = −h⊥/h_z (slope, K16 / reading (b)) for a
// half vector expressed in the frame (t, b, n).
inline D2 halfVectorQ(const D3& h, const D3& t, const D3& b, const D3& n, bool slope) {
    D2 q(glm::dot(h, t), glm::dot(h, b));
    if (!slope) return q;
    double hz = glm::dot(h, n);
    return -q / std::max(std::abs(hz), 1e-12);
}

// Analytic Δ_k q from the ray differentials (spec §5.1): dh = P(h)(dwo + dwi)/|H|,
// Δh⊥ = (dh·t − h_z dn·t, dh·b − h_z dn·b), Δh∥ = −(Δh⊥ h_z − h⊥ dh_z)/h_z² with dh_z = dh·n + h·dn.
// This form takes the half vector h = H/|H| and 1/|H| from the caller (the lobe has them already): one division
// fewer per axis than dividing by |H|, which matters because divisions are most of a filtered evaluation's cost.
inline void halfVectorDeltasAnalytic(const D3& h, double invLen, const D3& wi, const Differentials& df, double invLightDist,
                                     bool slope, D2 out[2]) {
    const double invHz2 = slope ? 1.0 / (std::max(h.z, 1e-12) * std::max(h.z, 1e-12)) : 0.0;
    for (int k = 0; k < 2; ++k) {
        D3 dH = df.dwo[k] + lightDirectionDerivative(wi, df.dp[k], invLightDist);
        D3 dh = (dH - h * glm::dot(h, dH)) * invLen;
        D2 dperp(dh.x - h.z * df.dn[k].x, dh.y - h.z * df.dn[k].y);
        if (!slope) {
            out[k] = dperp;
        } else {
            double dhz = dh.z + glm::dot(h, df.dn[k]);
            double hz = std::max(h.z, 1e-12);
            out[k] = -(dperp * hz - D2(h.x, h.y) * dhz) * invHz2;
        }
    }
}
inline void halfVectorDeltasAnalytic(const D3& wo, const D3& wi, const Differentials& df, double invLightDist, bool slope,
                                     D2 out[2]) {
    D3 H = wo + wi;
    double invLen = 1.0 / glm::length(H);
    halfVectorDeltasAnalytic(H * invLen, invLen, wi, df, invLightDist, slope, out);
}

// Quad Δ_k q (spec §5.2): q evaluated at the neighbour pixel with its own wo, wi (same light sample position) and
// frame, minus q here; fine rule via QuadNeighbour::sign.
inline bool halfVectorDeltaQuad(const D3& wi, const D2& qSelf, const QuadNeighbour& nb, double invLightDist, bool slope, D2& out) {
    if (!nb.valid) return false;
    D3 wiN = wi;
    if (invLightDist != 0.0) wiN = glm::normalize(wi / invLightDist - nb.dp);
    D3 H = nb.wo + wiN;
    double len = glm::length(H);
    if (!(len > 0.0)) return false;
    D2 qN = halfVectorQ(H / len, nb.t, nb.b, nb.n, slope);
    out = (qN - qSelf) * nb.sign;
    return true;
}

// ---- Float evaluation of projected_approx (issue 37 item 2) -------------------------------------------------------

// f·cos and pdf of the projected_approx lobe (analytic derivatives) in float, written for a short chain of dependent
// divisions and square roots (error against long double: test FilteredGgxMath.FastEvaluationEqualsLongDoubleReference).
// - The half vector stays unnormalised, H = wo + wi, l = |H|²: everything below is homogeneous in H, so no square
//   root of l is on the way, and wo·h = |H|/2 because wo·H = 1 + wo·wi = l/2.
// - Half-vector derivative (spec §5.1) with the light distance t = |y − p| multiplied through instead of divided:
//   l t |H| Δh⊥ = P̂ = l (t Δwo⊥ − (P(wi) Δp)⊥ − t H_z Δn⊥) − H⊥ (t H·Δwo − H·P(wi) Δp), from ΔH = Δwo − P(wi) Δp / t,
//   so 2Σ⊥ = 2σ² (P̂_u P̂_uᵀ + P̂_v P̂_vᵀ) / (l³ t²) and 2σ² fwidth² = 2σ² (|P̂_u| + |P̂_v|)² / (l³ t²) (TK21 Eq. 9,
//   Listing 3): the one division, of that scale, runs beside the derivatives instead of before them.
// - With E = H⊥ᵀ adj(Ā) H⊥ + H_z² d (d = max(det Ā, τ)) the bracket of TK21 Eq. 1 is E/(d l), so D = d^{3/2} l² / (π E²)
//   needs no inverse of Ā; with R(w) = sqrt(w_z² + w⊥ᵀ Ā w⊥), 1 + 2Λ(w) = R/w_z (TK21 A.3), so 1/G2 (Heitz 2014
//   Eq. 99) = X / (2 o_z i_z) with X = i_z R(o) + o_z R(i), and 1/G1_s(o) = Y / (2 o_z) with Y = o_z + R_s(o). Then
//     f·cos = F D G2 / (4 o_z) = F d sqrt(d) l² i_z / (2π E² X),   pdf = D_s G1_s / (4 o_z) = norm_s l² / (2 E_s² Y)
//   (E_s = H⊥ᵀ Ā_s⁻¹ H⊥ + H_z²): one two-lane division, and the four square roots (d, R(o), R(i), R_s(o)) are one
//   vector instruction.
// Float loses about eps·(a d + c²)/det Ā relative (cancellation in det and in the quadratic forms of a non-diagonal
// Ā), so a query whose filtered matrix has a d > kMaxConditionFloat · det Ā goes back to the double form; diagonal
// matrices (axis-aligned kernel, no covariance: the default) never do.
#if SPECULA_FGGX_FLOAT_PATH
struct FloatProjectedApprox {
    static constexpr float kMaxConditionFloat = 4.f;
    bool enabled = false;
    bool fullKernel = false;
    float a = 0, c = 0, d = 0, tau = 0;  // unfiltered A, clamp τ
    float twoSigma2 = 0, kappa = 0;
    float sa = 0, sc = 0, sd = 0;        // sampling matrix Ā_s (for Λ)
    float ia = 0, ic = 0, id = 0;        // Ā_s⁻¹ (for the NDF bracket)
    float halfNormS = 0;                 // 1 / (2π sqrt(max(det Ā_s, τ)))
    // The screen derivatives (k = u, v) as lanes: [Δ_u x, Δ_u y, Δ_v x, Δ_v y] of Δwo, Δp and Δn (tangent-plane
    // part), and each component of Δwo, Δp repeated over its derivative's two lanes ([Δ_u x, Δ_u x, Δ_v x, Δ_v x], ...).
    float lanesDwo[4]{}, lanesDp[4]{}, lanesDn[4]{};
    float lanesDwoX[4]{}, lanesDwoY[4]{}, lanesDwoZ[4]{}, lanesDpX[4]{}, lanesDpY[4]{}, lanesDpZ[4]{};

    void setDerivatives(const D3 dwo[2], const D3 dp[2], const D3 dn[2]) {
        for (int k = 0; k < 2; ++k)
            for (int j = 0; j < 2; ++j) {
                const int lane = 2 * k + j;
                lanesDwo[lane] = float(dwo[k][j]), lanesDp[lane] = float(dp[k][j]), lanesDn[lane] = float(dn[k][j]);
                lanesDwoX[lane] = float(dwo[k].x), lanesDwoY[lane] = float(dwo[k].y), lanesDwoZ[lane] = float(dwo[k].z);
                lanesDpX[lane] = float(dp[k].x), lanesDpY[lane] = float(dp[k].y), lanesDpZ[lane] = float(dp[k].z);
            }
    }

    // Returns false (caller evaluates in double) where float is not accurate enough or out of range.
    bool eval(const Vec3& wo, const Vec3& wi, float lightDistance, float& fScale, float& pdf, float& woh) const {
        const Vec3 H = wo + wi;
        const float l = glm::dot(H, H);
        if (!(l > 1e-6f)) return false;
        // Directional lights, the environment and BSDF samples (no finite distance) have Δwi = 0: t = 1 and the
        // P(wi) Δp terms weighted 0; t ≥ 1e12 goes to double (t² must stay in range).
        const bool pointLight = lightDistance > 0.f && lightDistance < std::numeric_limits<float>::infinity();
        if (pointLight && !(lightDistance < 1e12f)) return false;
        const float t = pointLight ? lightDistance : 1.f, pw = pointLight ? 1.f : 0.f;
        const float scale = twoSigma2 / (l * l * l * t * t);  // 2σ² / (l³ t²)
        // Both derivatives at once, lanes [u x, u y, v x, v y]: P̂ = l t P.
        const __m128 hx = _mm_set1_ps(H.x), hy = _mm_set1_ps(H.y), hz = _mm_set1_ps(H.z), tv = _mm_set1_ps(t);
        const __m128 dpx = _mm_loadu_ps(lanesDpX), dpy = _mm_loadu_ps(lanesDpY), dpz = _mm_loadu_ps(lanesDpZ);
        const __m128 wdp = _mm_mul_ps(_mm_set1_ps(pw),  // wi·Δp (0 without a point light)
                                      _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(wi.x), dpx), _mm_mul_ps(_mm_set1_ps(wi.y), dpy)),
                                                 _mm_mul_ps(_mm_set1_ps(wi.z), dpz)));
        const __m128 wodp = _mm_mul_ps(_mm_set1_ps(pw),  // wo·Δp
                                       _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(wo.x), dpx), _mm_mul_ps(_mm_set1_ps(wo.y), dpy)),
                                                  _mm_mul_ps(_mm_set1_ps(wo.z), dpz)));
        const __m128 hdwo = _mm_add_ps(_mm_add_ps(_mm_mul_ps(hx, _mm_loadu_ps(lanesDwoX)), _mm_mul_ps(hy, _mm_loadu_ps(lanesDwoY))),
                                       _mm_mul_ps(hz, _mm_loadu_ps(lanesDwoZ)));               // H·Δwo
        // H·P(wi)Δp = H·Δp − (H·wi)(wi·Δp) with H·wi = 1 + wo·wi = l/2
        const __m128 hproj = _mm_add_ps(wodp, _mm_mul_ps(wdp, _mm_set1_ps(1.f - 0.5f * l)));
        const __m128 proj = _mm_sub_ps(_mm_mul_ps(_mm_set1_ps(pw), _mm_loadu_ps(lanesDp)),   // (P(wi)Δp)⊥
                                       _mm_mul_ps(_mm_setr_ps(wi.x, wi.y, wi.x, wi.y), wdp));
        const __m128 tHdH = _mm_sub_ps(_mm_mul_ps(tv, hdwo), hproj);  // t H·ΔH
        const __m128 P = _mm_sub_ps(
            _mm_mul_ps(_mm_set1_ps(l), _mm_sub_ps(_mm_mul_ps(tv, _mm_sub_ps(_mm_loadu_ps(lanesDwo), _mm_mul_ps(hz, _mm_loadu_ps(lanesDn)))), proj)),
            _mm_mul_ps(_mm_setr_ps(H.x, H.y, H.x, H.y), tHdH));
        // Ā as lanes [ā_xx, ā_yy, ·, ·] plus ā_xy, kept in registers: every lane below is the same sequence of float
        // operations as the scalar form, only without the moves between scalar and vector registers on the way from
        // the filter to the division (that chain is the evaluation's latency).
        __m128 F;
        float fc = c;
        if (fullKernel) {
            const __m128 P2 = _mm_mul_ps(P, P);
            const __m128 diag = _mm_add_ps(P2, _mm_movehl_ps(P2, P2));  // [Σ P_x², Σ P_y², ...]
            const __m128 cross = _mm_mul_ps(P, _mm_shuffle_ps(P, P, _MM_SHUFFLE(2, 3, 0, 1)));
            F = _mm_add_ps(_mm_setr_ps(a, d, a, d), _mm_mul_ps(_mm_set1_ps(scale), diag));
            fc = c + scale * (_mm_cvtss_f32(cross) + _mm_cvtss_f32(_mm_movehl_ps(cross, cross)));
        } else {  // Listing 3: min(2σ² fwidth², κ) per axis, saturated
            const __m128 absP = _mm_andnot_ps(_mm_set1_ps(-0.f), P);
            const __m128 w = _mm_add_ps(absP, _mm_movehl_ps(absP, absP));  // [fwidth x, fwidth y, ...] · l t
            F = _mm_min_ps(_mm_add_ps(_mm_setr_ps(a, d, a, d), _mm_min_ps(_mm_mul_ps(_mm_set1_ps(scale), _mm_mul_ps(w, w)),
                                                                         _mm_set1_ps(kappa))),
                           _mm_set1_ps(1.f));
        }
        const __m128 FA = _mm_shuffle_ps(F, F, _MM_SHUFFLE(0, 0, 0, 0)), FD = _mm_shuffle_ps(F, F, _MM_SHUFFLE(1, 1, 1, 1));
        const float fa = _mm_cvtss_f32(F), fd = _mm_cvtss_f32(FD);
        const float ad = fa * fd, det = ad - fc * fc;
        if (ad > kMaxConditionFloat * det) return false;
        const float dc = std::max(det, tau);
        // Lanes [d, R(o)², R(i)², R_s(o)²] → one square root; R_s(o)² does not depend on the filter and is added as a
        // whole (0 + x = x: the same bits as a lane of its own).
        const float rs2 = std::max(sa * (wo.x * wo.x) + (2.f * sc) * (wo.x * wo.y) + sd * (wo.y * wo.y), 0.f) + wo.z * wo.z;
        const __m128 wx = _mm_setr_ps(0.f, wo.x, wi.x, 0.f), wy = _mm_setr_ps(0.f, wo.y, wi.y, 0.f);
        const __m128 wz = _mm_setr_ps(0.f, wo.z, wi.z, 0.f);
        const __m128 quad = _mm_add_ps(_mm_add_ps(_mm_mul_ps(FA, _mm_mul_ps(wx, wx)), _mm_mul_ps(_mm_set1_ps(2.f * fc), _mm_mul_ps(wx, wy))),
                                       _mm_mul_ps(FD, _mm_mul_ps(wy, wy)));
        const __m128 rad = _mm_move_ss(_mm_add_ps(_mm_max_ps(quad, _mm_setzero_ps()), _mm_add_ps(_mm_mul_ps(wz, wz), _mm_setr_ps(0.f, 0.f, 0.f, rs2))),
                                       _mm_set_ss(dc));
        const __m128 r = _mm_sqrt_ps(rad);
        // [i_z R(o), o_z R(i), R_s(o)] in lanes 1–3 → [X, Y] = [i_z R(o) + o_z R(i), R_s(o) + o_z] in lanes 0–1
        const __m128 zr = _mm_mul_ps(r, _mm_setr_ps(0.f, wi.z, wo.z, 1.f));
        const __m128 XY = _mm_add_ps(_mm_shuffle_ps(zr, zr, _MM_SHUFFLE(3, 3, 3, 1)), _mm_unpackhi_ps(zr, _mm_set1_ps(wo.z)));
        // Lanes [E, E_s]
        const float Hz2 = H.z * H.z, l2 = l * l;
        const __m128 c1 = _mm_unpacklo_ps(FD, _mm_set_ss(ia)), c2 = _mm_unpacklo_ps(_mm_set1_ps(-2.f * fc), _mm_set_ss(2.f * ic));
        const __m128 c3 = _mm_unpacklo_ps(FA, _mm_set_ss(id));
        const __m128 c4 = _mm_move_ss(_mm_setr_ps(0.f, Hz2, 1.f, 1.f), _mm_set_ss(Hz2 * dc));
        const __m128 Ev = _mm_add_ps(_mm_add_ps(_mm_mul_ps(c1, _mm_set1_ps(H.x * H.x)), _mm_mul_ps(c2, _mm_set1_ps(H.x * H.y))),
                                     _mm_add_ps(_mm_mul_ps(c3, _mm_set1_ps(H.y * H.y)), c4));
        const __m128 den = _mm_mul_ps(_mm_mul_ps(Ev, Ev), XY);  // [E² X, E_s² Y]
        const __m128 inRange = _mm_and_ps(_mm_cmpgt_ps(den, _mm_set1_ps(1e-30f)), _mm_cmplt_ps(den, _mm_set1_ps(1e30f)));
        if ((_mm_movemask_ps(inRange) & 3) != 3) return false;
        const float numF = dc * _mm_cvtss_f32(r) * l2 * wi.z * float(1.0 / (2.0 * kPiD));
        if (!(numF > 1e-30f)) return false;  // d^{3/2} of a τ near float's range, at a grazing wi
        const __m128 res = _mm_div_ps(_mm_setr_ps(numF, halfNormS * l2, 1.f, 1.f), den);
        fScale = _mm_cvtss_f32(res);
        pdf = _mm_cvtss_f32(_mm_shuffle_ps(res, res, _MM_SHUFFLE(1, 1, 1, 1)));
        woh = 0.5f * std::sqrt(l);
        return true;
    }
};
#endif

// ---- The lobe ------------------------------------------------------------------------------------------------------

// A = diag(α_x², α_y²) + 2Σ with Σ made positive semi-definite (|Σ_xy| ≤ sqrt(Σ_xx Σ_yy)); α clamped to
// [1e-4, 0.999] (the projected variants need α < 1, spec §3.3).
inline Sym2 roughnessMatrix(Vec2 alpha, Vec3 cov) {
    double ax = std::clamp(double(alpha.x), 1e-4, 0.999), ay = std::clamp(double(alpha.y), 1e-4, 0.999);
    // Σ packed as (var_x, var_y, cov_xy), the layout of texture.lean's covariance output.
    double sxx = std::max(double(cov.x), 0.0), syy = std::max(double(cov.y), 0.0);
    double lim = std::sqrt(sxx * syy);
    double sxy = std::clamp(double(cov.z), -lim, lim);
    return {ax * ax + 2.0 * sxx, 2.0 * sxy, ay * ay + 2.0 * syy};
}

// Everything a FilteredGgxLobe needs besides (wo, wi): the unfiltered roughness matrix, the filter, derivatives.
struct LobeSetup {
    Sym2 A = Sym2::diag(0.01, 0.01);  // unfiltered roughness matrix (A + 2Σ_LEAN allowed)
    FilterParams params;
    Differentials diff;               // analytic derivatives (spec §5.1)
    bool quad = false;                // use quad neighbours (spec §5.2) where valid, analytic otherwise
    QuadNeighbour nb[2];
};

// GGX reflection with a filtered roughness matrix Ā(wo, wi). eval returns f·cos = F(wo·h) D_Ā(h) G2_Ā(wo, wi)/(4 wo_z).
// Half-vector filters depend on wi, so the lobe samples a fixed matrix Ā_s (the filter evaluated at the mirror
// configuration h = n with a directional light) and pdf() returns exactly the density of that sampling: the
// estimator stays unbiased under MIS for any Ā(wo, wi) (support is the whole hemisphere). Normal-based filters
// and `none` give Ā independent of wi, so there Ā_s = Ā and sampling is the lobe's exact VNDF.
class FilteredGgxLobe final : public ltc::GgxPolygonLobe<FilteredGgxLobe> {
public:
    FilteredGgxLobe(const LobeSetup& s, const Fresnel& fresnel, const Color3& tint = Color3(1.f)) : FilteredGgxLobe(s, fresnel, tint, nullptr) {}
    // The same lobe after setSamplingFromMirror(mirrorWo), prepared once (the node knows wo when it makes the lobe; the
    // unfiltered preparation that setSamplingFromMirror would replace is a tenth of a filtered frame's extra time).
    FilteredGgxLobe(const LobeSetup& s, const Fresnel& fresnel, const Color3& tint, const D3& mirrorWo)
        : FilteredGgxLobe(s, fresnel, tint, &mirrorWo) {}

private:
    FilteredGgxLobe(const LobeSetup& s, const Fresnel& fresnel, const Color3& tint, const D3* mirrorWo)
        : s_(s), fresnel_(fresnel), tint_(tint) {
        // τ = det of the unfiltered matrix (A.4; det Ā ≥ det A must hold).
        tau_ = std::max(s_.A.det(), 1e-300);
        const Filter f = s_.params.filter;
        halfVector_ = isHalfVectorFilter(f) && (s_.diff.valid || s_.quad);
        fixed_ = s_.A;
        if (f != Filter::None && !isHalfVectorFilter(f) && (s_.diff.valid || s_.quad)) {
            D3 dn[2] = {s_.diff.valid ? s_.diff.dn[0] : D3(0.0), s_.diff.valid ? s_.diff.dn[1] : D3(0.0)};
            for (int k = 0; k < 2; ++k)
                if (s_.quad && s_.nb[k].valid) dn[k] = (s_.nb[k].n - D3(0, 0, 1)) * s_.nb[k].sign;
            fixed_ = filterIsotropic(s_.A, isotropicKernel(f, dn[0], dn[1], s_.params));
        }
        const Sym2 S = mirrorWo && halfVector_ && mirrorWo->z > 0.0 ? mirrorFilter(*mirrorWo) : fixed_;
        sampling_ = PreparedGgx(S, tau_);
        samplingL_ = cholesky(S);
        prepareFloat();
    }

public:

    LobeKind kind() const override { return LobeKind::Specular; }
    using BsdfLobe::sample;

    // Ā for (wo, wi) (spec §3): the filtered matrix the NDF and G2 use.
    // useQuad = false: analytic derivatives only (the sampling matrix).
    Sym2 filtered(const D3& wo, const D3& wi, double invLightDist, bool useQuad = true) const {
        if (!halfVector_) return fixed_;
        D3 H = wo + wi;
        double invLen = 1.0 / glm::length(H);
        return filteredAt(H * invLen, invLen, wi, invLightDist, useQuad);
    }

    // f·cos = F(wo·h) D_Ā(h) G2_Ā(wo, wi) / (4 wo_z); pdf = D_wo(h; Ā_s) / (4 wo·h) = D_Ā_s(h) G1_Ā_s(wo) / (4 wo_z)
    // (Heitz 2018 Eq. 1: the wo·h of the VNDF cancels the reflection Jacobian's). Written for few divisions (they
    // are most of the cost): both values share one reciprocal, and the matrices that do not depend on wi are prepared
    // once (test FilteredGgxMath.FastEvaluationEqualsLongDoubleReference checks it against Eq. 1 and Eq. 99 directly).
    // projected_approx with analytic derivatives takes the float form FloatProjectedApprox first (its filter costs
    // what the rest of the evaluation costs; bench_filtered_ggx) and comes back here where that form declines.
    LobeValue evalPdf(const LobeQuery& q) const override {
        if (q.wo.z <= 0.f || q.wi.z <= 0.f) return {};
#if SPECULA_FGGX_FLOAT_PATH
        if (float_.enabled) {
            float fScale, pdf, woh;
            if (float_.eval(q.wo, q.wi, q.lightDistance, fScale, pdf, woh)) {
                LobeValue r;
                r.f = tint_ * fresnel_.eval(woh) * fScale;
                r.pdf = pdf;
                return r;
            }
        }
#endif
        // The double form (every variant; the fallback of the float one).
        const D3 wo(q.wo), wi(q.wi);
        const D3 H = wo + wi;
        const double len = glm::length(H);
        if (len == 0.0) return {};
        const double invLen = 1.0 / len;
        const D3 h = H * invLen;
        const double invWoZ2 = 1.0 / (wo.z * wo.z), invWiZ2 = 1.0 / (wi.z * wi.z);
        PreparedGgx filteredHere;
        if (halfVector_) filteredHere = PreparedGgx(filteredAt(h, invLen, wi, invLightDistance(q.lightDistance), true), tau_);
        const PreparedGgx& P = halfVector_ ? filteredHere : sampling_;
        const double e = P.ndfBracket(h);
        const double lo = P.lambda(wo, invWoZ2);
        const double x = 1.0 + lo + P.lambda(wi, invWiZ2);  // 1/G2
        double y, es;                                        // 1/G1 and the bracket under the sampling matrix
        if (halfVector_) {
            y = 1.0 + sampling_.lambda(wo, invWoZ2);
            es = sampling_.ndfBracket(h);
        } else {
            y = 1.0 + lo;
            es = e;
        }
        // f·cos = norm/(e² x 4 wo_z), pdf = norm_s/(e_s² y 4 wo_z): one reciprocal of the product.
        const double e2 = e * e, es2 = es * es;
        const double inv = 1.0 / (4.0 * wo.z * e2 * es2 * x * y);
        LobeValue r;
        r.f = tint_ * fresnel_.eval(float(glm::dot(wo, h))) * float(P.norm * es2 * y * inv);
        r.pdf = float(sampling_.norm * e2 * x * inv);
        return r;
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        if (q.wo.z <= 0.f) return false;
        D3 wo(q.wo);
        D3 m = sampleVisibleNormal(wo, u, samplingL_);
        D3 r = 2.0 * glm::dot(wo, m) * m - wo;
        wi = Vec3(r);
        return wi.z > 0.f;
    }
    Color3 albedo(const Vec3& wo) const override { return tint_ * fresnel_.eval(std::max(wo.z, 0.f)); }

    const char* modelName() const override { return "ggx_filtered"; }
    // Roughness matrices as (a, c, d) of [[a, c], [c, d]]: unfiltered A, filtered Ā for the query, sampling Ā_s.
    void parameters(const LobeQuery& q, LobeParameters& out) const override {
        Sym2 Ab = filtered(D3(q.wo), D3(q.wi), invLightDistance(q.lightDistance));
        out.push_back({"roughness_matrix", {s_.A.a, s_.A.c, s_.A.d}});
        out.push_back({"filtered_roughness_matrix", {Ab.a, Ab.c, Ab.d}});
        out.push_back({"sampling_roughness_matrix", {sampling_.A.a, sampling_.A.c, sampling_.A.d}});
        out.push_back({"filtered_alpha", {std::sqrt(Ab.a), std::sqrt(Ab.d)}});
    }

    // Quad lights (ltc::GgxPolygonLobe): the LTC of GGX with the sampling matrix Ā_s (for normal-based filters and
    // `none` the exact filtered matrix; for half-vector filters the filter at the mirror configuration, which is what
    // the lobe samples), via its principal axes in the anisotropic table (ltc::ggxRoughnessMatrix).
    ltc::Ltc computePolygonLtc(const Vec3& wo) const {
        return ltc::ggxRoughnessMatrix(ltc::builtinTables(), sampling_.A.a, sampling_.A.c, sampling_.A.d, wo);
    }
    const Fresnel& polygonFresnel() const { return fresnel_; }
    Color3 polygonTint() const { return tint_; }

    const Sym2& unfiltered() const { return s_.A; }
    const Sym2& samplingMatrix() const { return sampling_.A; }
    double tau() const { return tau_; }
    // Filtered matrix at the mirror configuration (the sampling matrix; debug output filtered_alpha).
    void setSamplingFromMirror(const D3& wo) {
        if (!halfVector_ || wo.z <= 0.0) return;
        Sym2 s = mirrorFilter(wo);
        sampling_ = PreparedGgx(s, tau_);
        samplingL_ = cholesky(s);
        prepareFloat();
        invalidatePolygonLtc();
    }
    // Whether evalPdf takes the float form (FloatProjectedApprox) for queries whose filtered matrix allows it.
    bool usesFloat() const {
#if SPECULA_FGGX_FLOAT_PATH
        return float_.enabled;
#else
        return false;
#endif
    }

private:
    // The filter at the mirror configuration wi = (−wo_x, −wo_y, wo_z) with a directional light (the sampling matrix).
    Sym2 mirrorFilter(const D3& wo) const { return filtered(wo, D3(-wo.x, -wo.y, wo.z), 0.0, false); }
    // Float copies for FloatProjectedApprox: projected_approx with analytic derivatives only (quad neighbours and the
    // eigenvalue clamp of the full kernel stay in double), unfiltered and sampling matrices whose condition float can
    // carry, and τ ≥ 1e-17 (α ≥ 1e-4 on both axes, the clamp of roughnessMatrix, gives τ ≥ 1e-16), so that d^{3/2}
    // stays a normal float.
    void prepareFloat() {
#if SPECULA_FGGX_FLOAT_PATH
        FloatProjectedApprox& F = float_;
        const FilterParams& p = s_.params;
        const Sym2& S = sampling_.A;
        F.enabled = halfVector_ && p.filter == Filter::ProjectedApprox && s_.diff.valid && !s_.quad &&
                    !(p.kernel == Kernel::Full && p.clampFullKernel) && tau_ >= 1e-17 && S.det() > 0.0 &&
                    S.a * S.d <= double(FloatProjectedApprox::kMaxConditionFloat) * S.det() &&
                    s_.A.a * s_.A.d <= double(FloatProjectedApprox::kMaxConditionFloat) * s_.A.det();
        if (!F.enabled) return;
        F.fullKernel = p.kernel == Kernel::Full;
        F.a = float(s_.A.a), F.c = float(s_.A.c), F.d = float(s_.A.d), F.tau = float(tau_);
        F.twoSigma2 = float(2.0 * p.sigma2), F.kappa = float(p.kappa);
        F.setDerivatives(s_.diff.dwo, s_.diff.dp, s_.diff.dn);
        F.sa = float(S.a), F.sc = float(S.c), F.sd = float(S.d);
        F.ia = float(sampling_.inv.a), F.ic = float(sampling_.inv.c), F.id = float(sampling_.inv.d);
        F.halfNormS = float(0.5 * sampling_.norm);
#endif
    }
    // The half-vector filter for h = (wo + wi)/|wo + wi| given with 1/|wo + wi|.
    Sym2 filteredAt(const D3& h, double invLen, const D3& wi, double invLightDist, bool useQuad) const {
        const bool slope = s_.params.filter == Filter::Slope;
        D2 dq[2] = {D2(0.0), D2(0.0)};
        if (s_.diff.valid) halfVectorDeltasAnalytic(h, invLen, wi, s_.diff, invLightDist, slope, dq);
        if (s_.quad && useQuad) {
            D2 qSelf = halfVectorQ(h, D3(1, 0, 0), D3(0, 1, 0), D3(0, 0, 1), slope);
            for (int k = 0; k < 2; ++k) halfVectorDeltaQuad(wi, qSelf, s_.nb[k], invLightDist, slope, dq[k]);
        }
        if (s_.params.filter == Filter::Projected) return filterProjected(s_.A, dq[0], dq[1], s_.params);
        return filterAdditive(s_.A, dq[0], dq[1], s_.params);
    }
    static double invLightDistance(float dist) {
        return (std::isfinite(dist) && dist > 0.f) ? 1.0 / double(dist) : 0.0;
    }
    LobeSetup s_;
    Fresnel fresnel_;
    Color3 tint_;
    double tau_ = 0;
    bool halfVector_ = false;
    Sym2 fixed_;
    PreparedGgx sampling_;  // Ā_s, prepared (equal to fixed_ unless the filter depends on the half vector)
    Chol2 samplingL_;
#if SPECULA_FGGX_FLOAT_PATH
    FloatProjectedApprox float_;
#endif
};

}  // namespace specula::fggx
