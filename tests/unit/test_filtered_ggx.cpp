// Property tests of the filtered GGX math (nodes/bsdf/ggx_filtered/filtered_ggx.h, spec filtered-ggx.md §7):
// analytic identities of the matrix GGX (TK21 Eqs. 1, 4–7, A.2–A.4), filter invariants, and sampling checked
// against independent quadrature and cosine-weighted Monte Carlo.
#include "nodes/bsdf/ggx_filtered/filtered_ggx.h"

#include "core/render/lobes/ggx.h"

#include <gtest/gtest.h>

#include <random>

using namespace specula;
using namespace specula::fggx;

namespace {

// Deterministic uniform numbers for the Monte Carlo checks (independent of the lobe's own arithmetic).
struct Rng {
    std::mt19937_64 g;
    explicit Rng(uint64_t seed) : g(seed) {}
    Vec2 next2() {
        std::uniform_real_distribution<float> u(0.f, 1.f);
        float a = u(g);
        return {a, u(g)};
    }
};

std::mt19937_64& rng() {
    static std::mt19937_64 r(20210531);
    return r;
}
double uni(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng()); }
// Draws are sequenced explicitly: the order in which a call's arguments are evaluated is unspecified (gcc goes right
// to left, clang left to right), and a test's random inputs must not depend on the compiler. The order kept is the one
// the gcc-built suite always had.
D3 randDir() {
    std::normal_distribution<double> n;
    const double z = n(rng()), y = n(rng()), x = n(rng());
    return glm::normalize(D3(x, y, z));
}
D3 randUpper(double minZ = 0.05) {
    D3 v;
    do v = randDir();
    while (std::abs(v.z) < minZ);
    if (v.z < 0) v.z = -v.z;
    return v;
}
// Random SPD matrix with eigenvalues in [lo, hi] and random orientation.
Sym2 randSpd(double lo, double hi) {
    double l1 = uni(lo, hi), l2 = uni(lo, hi), th = uni(0, kPiD);
    double c = std::cos(th), s = std::sin(th);
    return {l1 * c * c + l2 * s * s, (l1 - l2) * c * s, l1 * s * s + l2 * c * c};
}
Differentials randDiff(double scale) {
    Differentials d;
    d.valid = true;
    auto scaledDir = [scale] {  // (as randDir: the length is drawn first)
        const double length = uni(0, scale);
        return randDir() * length;
    };
    for (int k = 0; k < 2; ++k) {
        d.dwo[k] = scaledDir();
        D3 dn = scaledDir();
        dn.z = 0;  // ⊥ n
        d.dn[k] = dn;
        d.dp[k] = scaledDir();
    }
    return d;
}

// ∫ D(h) h_z dω over the hemisphere, by a deterministic product rule in (θ, φ) with θ = atan(σ tan(πx/2)), which
// concentrates nodes in the lobe (σ = sqrt of A's largest eigenvalue); independent of the slope-space identity.
double projectedIntegral(const Sym2& A, double tau, int nx = 1500, int nphi = 192) {
    double sigma = std::sqrt(A.eigMax());
    double sum = 0;
    for (int i = 0; i < nx; ++i) {
        double x = (i + 0.5) / nx;
        double t = std::tan(0.5 * kPiD * x);
        double theta = std::atan(sigma * t);
        double dthdx = sigma * 0.5 * kPiD * (1 + t * t) / (1 + sigma * sigma * t * t);
        double ct = std::cos(theta), st = std::sin(theta);
        double ring = 0;
        for (int j = 0; j < nphi; ++j) {
            double phi = 2 * kPiD * (j + 0.5) / nphi;
            ring += ndf(D3(st * std::cos(phi), st * std::sin(phi), ct), A, tau);
        }
        sum += ring * (2 * kPiD / nphi) * ct * st * dthdx / nx;
    }
    return sum;
}

// A diagonal A = diag(αx², αy²) with αx, αy uniform in [lo, hi) (αx drawn first).
Sym2 randDiagonal(double lo, double hi) {
    const double ax = uni(lo, hi), ay = uni(lo, hi);
    return Sym2::diag(ax * ax, ay * ay);
}

FilterParams params(Filter f, Kernel k) {
    FilterParams p;
    p.filter = f;
    p.kernel = k;
    return p;
}

const Filter kAllFilters[] = {Filter::None,    Filter::Slope,  Filter::Projected, Filter::ProjectedApprox,
                              Filter::IsoMax,  Filter::IsoSum, Filter::IsoMean,   Filter::IsoRect};

}  // namespace

// Eq. 1 with A = diag(αx², αy²) is the axis-aligned GGX of A.2; Λ (A.3) likewise; Λ is rotation invariant.
TEST(FilteredGgxMath, MatrixGgxEqualsAxisAlignedForDiagonalA) {
    for (int it = 0; it < 500; ++it) {
        double ax = uni(0.01, 0.9), ay = uni(0.01, 0.9);
        Sym2 A = Sym2::diag(ax * ax, ay * ay);
        D3 h = randUpper(0.02), w = randUpper(0.02);
        double ref = ggx::ndf(Vec3(h), float(ax), float(ay));
        EXPECT_NEAR(ndf(h, A, A.det()) / ref, 1.0, 2e-5);
        EXPECT_NEAR(lambda(w, A), ggx::lambda(Vec3(w), float(ax), float(ay)), 1e-5 * (1 + lambda(w, A)));
        // Rotation: A → R A Rᵀ, w⊥ → R w⊥ leaves Λ and D unchanged.
        double th = uni(0, 2 * kPiD), c = std::cos(th), s = std::sin(th);
        Sym2 RA{A.a * c * c + A.d * s * s, (A.a - A.d) * c * s, A.a * s * s + A.d * c * c};
        D3 Rw(c * w.x - s * w.y, s * w.x + c * w.y, w.z), Rh(c * h.x - s * h.y, s * h.x + c * h.y, h.z);
        EXPECT_NEAR(lambda(Rw, RA), lambda(w, A), 1e-9 * (1 + lambda(w, A)));
        EXPECT_NEAR(ndf(Rh, RA, RA.det()) / ndf(h, A, A.det()), 1.0, 1e-9);
        double g = g2(w, h, RA);
        EXPECT_GE(g, 0.0);
        EXPECT_LE(g, 1.0);
    }
}

// The lobe with filter none and diagonal A equals core's GgxLobe (float), including Fresnel and G2.
TEST(FilteredGgxMath, LobeEqualsGgxLobeWhenDiagonalAndUnfiltered) {
    Fresnel fr = Fresnel::schlick(Color3(0.9f, 0.6f, 0.3f));
    for (int it = 0; it < 300; ++it) {
        float ax = float(uni(0.01, 0.8)), ay = float(uni(0.01, 0.8));
        LobeSetup s;
        s.A = Sym2::diag(double(ax) * ax, double(ay) * ay);
        s.params.filter = Filter::None;
        FilteredGgxLobe lobe(s, fr);
        GgxLobe ref(ax, ay, fr);
        Vec3 wo(randUpper()), wi(randUpper());
        Color3 a = lobe.eval(wo, wi), b = ref.eval(wo, wi);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 5e-5f * std::max(b[c], 1e-3f));
        EXPECT_NEAR(lobe.pdf(wo, wi), ref.pdf(wo, wi), 5e-5f * std::max(ref.pdf(wo, wi), 1e-3f));
    }
}

// §7.1: zero derivatives give Ā = A bit-exactly for every variant, and the lobe's values equal filter none exactly.
TEST(FilteredGgxMath, ZeroDerivativesReproduceUnfilteredExactly) {
    Fresnel fr = Fresnel::schlick(Color3(0.04f));
    for (Filter f : kAllFilters)
        for (Kernel k : {Kernel::Full, Kernel::AxisAligned})
            for (int it = 0; it < 50; ++it) {
                LobeSetup s;
                s.A = randDiagonal(0.01, 0.5);
                s.diff.valid = true;  // all derivatives zero
                s.params = params(f, k);
                FilteredGgxLobe lobe(s, fr);
                LobeSetup s0 = s;
                s0.params.filter = Filter::None;
                FilteredGgxLobe none(s0, fr);
                D3 wo = randUpper(), wi = randUpper();
                EXPECT_TRUE(lobe.filtered(wo, wi, 0.0) == s.A) << filterName(f);
                EXPECT_TRUE(lobe.filtered(wo, wi, 0.3) == s.A) << filterName(f);
                // Ā is bit-identical (above); the float results may differ by an ulp only because -O3 vectorises the
                // two inlined call sites differently.
                Vec3 o(wo), i(wi);
                EXPECT_NEAR(lobe.eval(o, i).x, none.eval(o, i).x, 1e-6f * none.eval(o, i).x) << filterName(f);
                EXPECT_NEAR(lobe.pdf(o, i), none.pdf(o, i), 1e-6f * none.pdf(o, i)) << filterName(f);
            }
}

// §7.2 / §7.3: ∫ D_Ā h_z dω = 1 within 2% for the filtered matrices of every variant; det Ā ≥ det A (so the A.4
// clamp τ = det A is inactive); Ā − A non-negative definite for the half-vector variants.
TEST(FilteredGgxMath, FilteredMatricesAreNormalisedAndNeverSharper) {
    double worst = 0;
    int checked = 0;
    for (Filter f : kAllFilters)
        for (Kernel k : {Kernel::Full, Kernel::AxisAligned})
            for (int it = 0; it < 6; ++it) {
                LobeSetup s;
                s.A = randDiagonal(0.01, 0.3);
                s.diff = randDiff(uni(0.001, 0.2));
                s.params = params(f, k);
                FilteredGgxLobe lobe(s, Fresnel::one());
                D3 wo = randUpper(0.2), wi = randUpper(0.2);
                Sym2 Ab = lobe.filtered(wo, wi, uni(0, 1));
                EXPECT_GE(Ab.det(), s.A.det() * (1 - 1e-12)) << filterName(f);
                Sym2 diff = Ab - s.A;
                EXPECT_GE(diff.eigMin(), -1e-12) << filterName(f);
                double I = projectedIntegral(Ab, lobe.tau());
                worst = std::max(worst, std::abs(I - 1));
                EXPECT_NEAR(I, 1.0, 0.02) << filterName(f) << " A=(" << Ab.a << "," << Ab.c << "," << Ab.d << ")";
                ++checked;
            }
    // Non-axis-aligned unfiltered matrices (LEAN-style A + 2Σ) too.
    for (int it = 0; it < 10; ++it) {
        Sym2 A = randSpd(1e-4, 0.2);
        double I = projectedIntegral(A, A.det());
        worst = std::max(worst, std::abs(I - 1));
        EXPECT_NEAR(I, 1.0, 0.02);
    }
    std::printf("normalisation: %d filtered matrices, worst |∫D cos − 1| = %.2e\n", checked, worst);
}

// §7.3: larger derivatives never lower the filtered roughness (scaling the derivatives up).
TEST(FilteredGgxMath, LargerDerivativesNeverSharpen) {
    for (Filter f : {Filter::Slope, Filter::Projected, Filter::ProjectedApprox})
        for (Kernel k : {Kernel::Full, Kernel::AxisAligned})
            for (int it = 0; it < 200; ++it) {
                Sym2 A = Sym2::diag(std::pow(uni(0.01, 0.5), 2), std::pow(uni(0.01, 0.5), 2));
                D2 du(uni(-0.3, 0.3), uni(-0.3, 0.3)), dv(uni(-0.3, 0.3), uni(-0.3, 0.3));
                FilterParams p = params(f, k);
                auto run = [&](double s) {
                    return f == Filter::Projected ? filterProjected(A, du * s, dv * s, p) : filterAdditive(A, du * s, dv * s, p);
                };
                Sym2 a1 = run(1.0), a2 = run(1.7);
                EXPECT_GE(a2.det(), a1.det() * (1 - 1e-12));
                EXPECT_GE(a2.trace(), a1.trace() * (1 - 1e-12));
            }
}

// §7.5 / §7.7: κ bounds of the axis-aligned and isotropic kernels; huge kernels give exactly min(α² + κ, 1);
// the rectangle kernel bounds the full one: (2Σ)_ii ≤ 2σ² w_i² ≤ 2 (2Σ)_ii.
TEST(FilteredGgxMath, KappaClampAndBoundingRectangle) {
    FilterParams p = params(Filter::ProjectedApprox, Kernel::AxisAligned);
    for (int it = 0; it < 500; ++it) {
        double ax2 = std::pow(uni(0.01, 0.9), 2), ay2 = std::pow(uni(0.01, 0.9), 2);
        Sym2 A = Sym2::diag(ax2, ay2);
        D2 du(uni(-1, 1), uni(-1, 1)), dv(uni(-1, 1), uni(-1, 1));
        Sym2 Ab = filterAdditive(A, du, dv, p);
        EXPECT_GE(Ab.a - ax2, 0.0);
        EXPECT_LE(Ab.a - ax2, p.kappa + 1e-15);
        EXPECT_LE(Ab.a, 1.0);
        Sym2 K = kernelOf(du, dv, p.sigma2) * 2.0;
        double wx = std::abs(du.x) + std::abs(dv.x);
        EXPECT_LE(K.a, 2 * p.sigma2 * wx * wx + 1e-15);
        EXPECT_LE(2 * p.sigma2 * wx * wx, 2 * K.a + 1e-15);
        Sym2 huge = filterAdditive(A, D2(1e6, 1e6), D2(0, 0), p);
        EXPECT_EQ(huge.a, std::min(ax2 + p.kappa, 1.0));
        EXPECT_EQ(huge.d, std::min(ay2 + p.kappa, 1.0));
        for (Filter f : {Filter::IsoMax, Filter::IsoSum, Filter::IsoMean, Filter::IsoRect}) {
            double k = isotropicKernel(f, randDir() * uni(0, 2), randDir() * uni(0, 2), p);
            EXPECT_GE(k, 0.0);
            EXPECT_LE(k, p.kappa);
        }
    }
}

// §7.6: isotropic kernels ordered sum ≥ max ≥ mean (before and after the κ clamp), sum = 2·mean; max = sum for
// parallel derivatives, max = mean for orthogonal equal-length ones; iso_max from the world-space Gram matrix equals
// the largest eigenvalue of the tangent-frame Σ⊥.
TEST(FilteredGgxMath, IsotropicKernelsAreOrdered) {
    FilterParams noClamp = params(Filter::IsoMax, Kernel::Full);
    noClamp.kappa = 1e30;
    FilterParams clamp = params(Filter::IsoMax, Kernel::Full);
    for (int it = 0; it < 2000; ++it) {
        D3 n = randDir();
        Frame fr = Frame::fromNormal(Vec3(n));
        D3 t(fr.t), b(fr.b);
        auto tangential = [&](double s) {
            D3 v = randDir() * s;
            return v - n * glm::dot(v, n);
        };
        D3 du = tangential(uni(0, 1)), dv = tangential(uni(0, 1));
        for (const FilterParams& p : {noClamp, clamp}) {
            double mx = isotropicKernel(Filter::IsoMax, du, dv, p), sm = isotropicKernel(Filter::IsoSum, du, dv, p),
                   mn = isotropicKernel(Filter::IsoMean, du, dv, p);
            EXPECT_GE(sm, mx * (1 - 1e-12));
            EXPECT_GE(mx, mn * (1 - 1e-12));
            EXPECT_GE(mn, 0.0);
            if (&p == &noClamp) {
                EXPECT_NEAR(sm, 2 * mn, 1e-12 * sm);
                // Tangent-frame Σ⊥ of the projected normal: Δn⊥ = (Δn·t, Δn·b).
                Sym2 S = kernelOf(D2(glm::dot(du, t), glm::dot(du, b)), D2(glm::dot(dv, t), glm::dot(dv, b)), p.sigma2);
                EXPECT_NEAR(mx, 2 * S.eigMax(), 1e-12 * (1 + mx));
            }
        }
        D3 par = du * uni(-2, 2);
        EXPECT_NEAR(isotropicKernel(Filter::IsoMax, du, par, noClamp), isotropicKernel(Filter::IsoSum, du, par, noClamp),
                    1e-9 * (1 + glm::dot(du, du)));
        // Equal eigenvalues: λ = tr/2 ± sqrt(rounding), so the agreement is sqrt(ε)-limited.
        D3 orth = glm::cross(n, du);
        EXPECT_NEAR(isotropicKernel(Filter::IsoMax, du, orth, noClamp), isotropicKernel(Filter::IsoMean, du, orth, noClamp),
                    1e-7 * (1 + glm::dot(du, du)));
    }
}

// §7.8: B = A(I − A)⁻¹ (Eq. 4) satisfies Eq. 5, D(h) = sqrt(det B/det A) P(h⊥, B); sqrt(det B/det A) =
// 1/∫_Ω P(x, y, B) over the unit disk; the App. D form equals (B̄⁻¹ + I)⁻¹ (Eq. 7).
TEST(FilteredGgxMath, ProjectedSpaceIdentities) {
    auto P = [](double x, double y, const Sym2& B) {
        double e = B.adj().quad(x, y) / B.det() + 1.0;
        return 1.0 / (kPiD * std::sqrt(B.det()) * e * e);
    };
    for (int it = 0; it < 300; ++it) {
        Sym2 A = randSpd(1e-3, 0.9);
        Sym2 B = projectedRoughness(A);
        D3 h = randUpper(0.02);
        EXPECT_NEAR(std::sqrt(B.det() / A.det()) * P(h.x, h.y, B) / ndf(h, A, A.det()), 1.0, 1e-10);
        Sym2 K = kernelOf(D2(uni(-0.5, 0.5), uni(-0.5, 0.5)), D2(uni(-0.5, 0.5), uni(-0.5, 0.5)), kDefaultSigma2) * 2.0;
        Sym2 Bb = B + K;
        Sym2 ref = unprojectRoughness(Bb);
        Sym2 M = Bb * (1.0 / Bb.det()) + Sym2::diag(1, 1);
        Sym2 appD = M * (1.0 / M.det());
        EXPECT_NEAR(appD.a, ref.a, 1e-12 * (1 + std::abs(ref.a)));
        EXPECT_NEAR(appD.c, ref.c, 1e-12 * (1 + std::abs(ref.a)));
        EXPECT_NEAR(appD.d, ref.d, 1e-12 * (1 + std::abs(ref.d)));
    }
    // 1/∫_Ω P(x, y, B): polar quadrature over the unit disk.
    for (int it = 0; it < 5; ++it) {
        Sym2 A = randSpd(0.01, 0.5);
        Sym2 B = projectedRoughness(A);
        const int nr = 2000, nphi = 256;
        double sum = 0;
        for (int i = 0; i < nr; ++i) {
            double r = (i + 0.5) / nr;
            for (int j = 0; j < nphi; ++j) {
                double phi = 2 * kPiD * (j + 0.5) / nphi;
                sum += P(r * std::cos(phi), r * std::sin(phi), B) * r;
            }
        }
        sum *= (1.0 / nr) * (2 * kPiD / nphi);
        EXPECT_NEAR(std::sqrt(B.det() / A.det()), 1.0 / sum, 1e-4);
    }
}

// §7.4: exact vs approximation. At Σ⊥ = 0 the derivative of Ā_exact along S is 2(I − A) S (I − A); for small A and
// small kernels ‖Ā_exact − Ā_approx‖_max ≤ 0.03 tr(2Σ⊥); Ā_exact ≼ Ā_approx for isotropic A; tr and det of the exact
// result never exceed the approximation's for diagonal A.
TEST(FilteredGgxMath, ProjectedAndApproxAgreeToFirstOrder) {
    FilterParams full = params(Filter::Projected, Kernel::Full);
    for (int it = 0; it < 300; ++it) {
        Sym2 A = Sym2::diag(std::pow(uni(0.02, 0.6), 2), std::pow(uni(0.02, 0.6), 2));
        D2 du(uni(-1, 1), uni(-1, 1)), dv(uni(-1, 1), uni(-1, 1));
        const double eps = 1e-5;
        Sym2 S = kernelOf(du, dv, full.sigma2);
        Sym2 fd = (filterProjected(A, du * std::sqrt(eps), dv * std::sqrt(eps), full) - A) * (1.0 / eps);
        Sym2 IA{1 - A.a, -A.c, 1 - A.d};
        Sym2 expect = sandwich(IA, S) * 2.0;
        double scale = std::abs(expect.a) + std::abs(expect.c) + std::abs(expect.d) + 1e-12;
        EXPECT_NEAR(fd.a, expect.a, 1e-4 * scale);
        EXPECT_NEAR(fd.c, expect.c, 1e-4 * scale);
        EXPECT_NEAR(fd.d, expect.d, 1e-4 * scale);
    }
    double worstRatio = 0;
    for (int it = 0; it < 2000; ++it) {
        Sym2 A = Sym2::diag(uni(1e-4, 1e-2), uni(1e-4, 1e-2));
        double s = uni(1e-4, 0.05);
        D2 du(uni(-s, s), uni(-s, s)), dv(uni(-s, s), uni(-s, s));
        Sym2 K = kernelOf(du, dv, full.sigma2) * 2.0;
        if (K.trace() > 1e-3) continue;
        Sym2 ex = filterProjected(A, du, dv, full);
        Sym2 ap = filterAdditive(A, du, dv, params(Filter::ProjectedApprox, Kernel::Full));
        double m = std::max({std::abs(ex.a - ap.a), std::abs(ex.c - ap.c), std::abs(ex.d - ap.d)});
        if (K.trace() > 0) worstRatio = std::max(worstRatio, m / K.trace());
        EXPECT_LE(m, 0.03 * K.trace() + 1e-15);
        EXPECT_LE(ex.trace(), ap.trace() * (1 + 1e-12));
        EXPECT_LE(ex.det(), ap.det() * (1 + 1e-12));
    }
    std::printf("small kernels: max |Ā_exact − Ā_approx| / tr(2Σ⊥) = %.4f (bound 0.03)\n", worstRatio);
    for (int it = 0; it < 500; ++it) {
        double a2 = std::pow(uni(0.01, 0.7), 2);
        Sym2 A = Sym2::diag(a2, a2);
        D2 du(uni(-1, 1), uni(-1, 1)), dv(uni(-1, 1), uni(-1, 1));
        Sym2 ex = filterProjected(A, du, dv, full);
        Sym2 ap = filterAdditive(A, du, dv, params(Filter::ProjectedApprox, Kernel::Full));
        EXPECT_GE((ap - ex).eigMin(), -1e-12);  // Loewner order
    }
}

// Reciprocity: with derivatives that depend only on h (normal derivatives, static view/light), f(i, o) = f(o, i).
TEST(FilteredGgxMath, Reciprocity) {
    for (Filter f : kAllFilters)
        for (int it = 0; it < 100; ++it) {
            LobeSetup s;
            s.A = randSpd(1e-3, 0.3);
            s.diff.valid = true;
            for (int k = 0; k < 2; ++k) s.diff.dn[k] = D3(uni(-0.2, 0.2), uni(-0.2, 0.2), 0);
            s.params = params(f, it % 2 ? Kernel::Full : Kernel::AxisAligned);
            FilteredGgxLobe lobe(s, Fresnel::dielectric(1.5f));
            Vec3 o(randUpper()), i(randUpper());
            float a = lobe.eval(o, i).x / i.z, b = lobe.eval(i, o).x / o.z;
            EXPECT_NEAR(a, b, 2e-5f * std::max(a, 1e-3f)) << filterName(f);
        }
}

// One evaluation routine for both lobes of the test below. Inlined into the test at two call sites, GCC 12 -O3 compiled
// the double form differently at each (superword vectorisation; -fno-tree-slp-vectorize or -fno-ipa-cp removed it),
// and the first site's pdf differed in the last bit for the same object and query (every later call gave the second
// site's bits): the test compares the lobes' states through their values, so both go through the same code.
namespace {
[[gnu::noinline]] LobeValue evalPdfOutOfLine(const FilteredGgxLobe& lobe, const LobeQuery& q) { return lobe.evalPdf(q); }
[[gnu::noinline]] bool sampleOutOfLine(const FilteredGgxLobe& lobe, const LobeQuery& q, const Vec2& u, Vec3& wi) {
    return lobe.sample(q, u, wi);
}
}  // namespace

// The constructor that takes wo prepares the lobe that construction followed by setSamplingFromMirror(wo) gives (the
// node's one preparation instead of two): the same sampling matrix, float path, values and samples, bit for bit.
TEST(FilteredGgxMath, MirrorConstructorEqualsSetSamplingFromMirror) {
    // The shared generator is restored at the end, so that the tests after this one draw the inputs they always drew.
    const std::mt19937_64 savedRng = rng();
    const Fresnel fresnel = Fresnel::schlick(Color3(0.9f, 0.6f, 0.5f));
    int differentFromUnfiltered = 0;
    for (Filter f : kAllFilters)
        for (int it = 0; it < 40; ++it) {
            LobeSetup s;
            s.A = it % 3 == 0 ? randSpd(1e-4, 0.5) : randDiagonal(0.003, 0.8);
            s.diff = randDiff(uni(0.0, 0.1));
            s.params = params(f, it % 2 ? Kernel::Full : Kernel::AxisAligned);
            const D3 wo = randUpper(0.02);
            FilteredGgxLobe twoSteps(s, fresnel);
            twoSteps.setSamplingFromMirror(wo);
            const FilteredGgxLobe oneStep(s, fresnel, Color3(1.f), wo);
            EXPECT_TRUE(oneStep.samplingMatrix() == twoSteps.samplingMatrix()) << filterName(f) << " it " << it;
            EXPECT_EQ(oneStep.usesFloat(), twoSteps.usesFloat()) << filterName(f) << " it " << it;
            if (!(oneStep.samplingMatrix() == FilteredGgxLobe(s, fresnel).samplingMatrix())) ++differentFromUnfiltered;
            for (int q = 0; q < 8; ++q) {
                const LobeQuery query{Vec3(wo), Vec3(randUpper(0.02)), q % 2 ? 3.f : std::numeric_limits<float>::infinity()};
                const LobeValue a = evalPdfOutOfLine(oneStep, query), b = evalPdfOutOfLine(twoSteps, query);
                EXPECT_EQ(a.f.x, b.f.x) << filterName(f) << " it " << it;
                EXPECT_EQ(a.f.z, b.f.z) << filterName(f) << " it " << it;
                EXPECT_EQ(a.pdf, b.pdf) << filterName(f) << " it " << it;
                const Vec2 u(float(uni(0.0, 1.0)), float(uni(0.0, 1.0)));
                Vec3 wa, wb;
                const bool sa = sampleOutOfLine(oneStep, query, u, wa), sb = sampleOutOfLine(twoSteps, query, u, wb);
                EXPECT_EQ(sa, sb);
                if (sa && sb) EXPECT_TRUE(wa == wb) << filterName(f) << " it " << it;
            }
        }
    EXPECT_GT(differentFromUnfiltered, 100) << "the half-vector filters must sample a filtered matrix";
    rng() = savedRng;
}

namespace {
struct LobeCase {
    Sym2 A;
    Filter filter;
    Kernel kernel;
    double diffScale;
};
FilteredGgxLobe makeLobe(const LobeCase& c, const D3& wo) {
    LobeSetup s;
    s.A = c.A;
    s.params = params(c.filter, c.kernel);
    s.diff = randDiff(c.diffScale);
    FilteredGgxLobe lobe(s, Fresnel::schlick(Color3(0.5f)));
    lobe.setSamplingFromMirror(wo);
    return lobe;
}
}  // namespace

// Sampling: the pdf integrates to the acceptance rate of sample() (≤ 1), the sample histogram matches the pdf, and the
// importance-sampled estimate of ∫ f cos equals an independent cosine-sampled estimate, also for filtered lobes whose
// Ā depends on wi (so MIS with light sampling stays unbiased).
TEST(FilteredGgxSampling, PdfMatchesSamplerAndEstimatorsAgree) {
    const float lightDist = 3.f;
    std::vector<LobeCase> cases = {
        {Sym2::diag(0.04, 0.04), Filter::None, Kernel::Full, 0},
        {Sym2{0.09, 0.03, 0.02}, Filter::None, Kernel::Full, 0},
        {Sym2::diag(0.01, 0.0025), Filter::ProjectedApprox, Kernel::AxisAligned, 0.1},
        {Sym2::diag(0.01, 0.04), Filter::Projected, Kernel::Full, 0.1},
        {Sym2::diag(0.0025, 0.0025), Filter::Slope, Kernel::Full, 0.1},
        {Sym2::diag(0.01, 0.01), Filter::IsoSum, Kernel::Full, 0.2},
    };
    Rng r{77};
    for (const LobeCase& c : cases) {
        for (double thetaDeg : {20.0, 60.0, 80.0}) {
            double th = thetaDeg * kPiD / 180;
            D3 wo(std::sin(th) * 0.8, std::sin(th) * 0.6, std::cos(th));
            FilteredGgxLobe lobe = makeLobe(c, wo);
            Vec3 wof(wo);
            // (1) pdf over the sphere (product rule, z = cos θ, fine near the lobe via many nodes).
            const int NB = 8;  // 8×8 bins in (cos θ, φ)
            std::vector<double> binPdf(NB * NB, 0.0), binHist(NB * NB, 0.0);
            const int nz = 1200, nphi = 600;
            double total = 0;
            for (int i = 0; i < nz; ++i) {
                double z = (i + 0.5) / nz, s = std::sqrt(1 - z * z);
                for (int j = 0; j < nphi; ++j) {
                    double phi = 2 * kPiD * (j + 0.5) / nphi;
                    Vec3 wi(float(s * std::cos(phi)), float(s * std::sin(phi)), float(z));
                    double v = lobe.pdf(wof, wi) * (1.0 / nz) * (2 * kPiD / nphi);
                    total += v;
                    binPdf[(i * NB / nz) * NB + j * NB / nphi] += v;
                }
            }
            // (2) histogram and estimators.
            const int N = 400000;
            int accepted = 0;
            double isSum = 0, isSum2 = 0, cosSum = 0, cosSum2 = 0, isMax = 0;
            Vec3 isMaxWi(0.f);
            for (int k = 0; k < N; ++k) {
                Vec3 wi;
                if (lobe.sample(wof, r.next2(), wi)) {
                    ++accepted;
                    float p = lobe.pdf(wof, wi);
                    double v = p > 0 ? lobe.evalPdf(LobeQuery{wof, wi, lightDist}).f.x / p : 0.0;
                    isSum += v, isSum2 += v * v;
                    if (v > isMax) isMax = v, isMaxWi = wi;
                    double z = std::min(std::max(double(wi.z), 0.0), 1 - 1e-12);
                    double phi = std::atan2(double(wi.y), double(wi.x));
                    if (phi < 0) phi += 2 * kPiD;
                    int bi = std::min(NB - 1, int(z * NB)), bj = std::min(NB - 1, int(phi / (2 * kPiD) * NB));
                    binHist[bi * NB + bj] += 1.0 / N;
                }
                // Cosine-weighted sampling: pdf = cos/π.
                Vec2 u = r.next2();
                double rr = std::sqrt(u.x), ph = 2 * kPiD * u.y;
                Vec3 wc(float(rr * std::cos(ph)), float(rr * std::sin(ph)), float(std::sqrt(std::max(0.0, 1.0 - u.x))));
                double v = wc.z > 0 ? lobe.evalPdf(LobeQuery{wof, wc, lightDist}).f.x * kPiD / wc.z : 0.0;
                cosSum += v, cosSum2 += v * v;
            }
            double acc = double(accepted) / N;
            EXPECT_LE(total, 1.0 + 0.01);
            EXPECT_NEAR(total, acc, 0.01) << filterName(c.filter) << " θ=" << thetaDeg;
            double l1 = 0;
            for (int b = 0; b < NB * NB; ++b) l1 += std::abs(binPdf[b] - binHist[b]);
            EXPECT_LE(l1, 0.02) << filterName(c.filter) << " θ=" << thetaDeg;
            double mIs = isSum / N, vIs = (isSum2 / N - mIs * mIs) / N;
            double mCos = cosSum / N, vCos = (cosSum2 / N - mCos * mCos) / N;
            double sd = std::sqrt(vIs + vCos);
            std::printf("  %-16s θ=%2.0f: ∫pdf %.4f (accepted %.4f), IS %.4f ± %.4f, cosine %.4f ± %.4f\n",
                        filterName(c.filter), thetaDeg, total, acc, mIs, std::sqrt(vIs), mCos, std::sqrt(vCos));
            EXPECT_NEAR(mIs, mCos, 4 * sd + 1e-4) << filterName(c.filter) << " θ=" << thetaDeg;
            EXPECT_LE(mIs, 1.0) << filterName(c.filter) << " θ=" << thetaDeg << ": largest weight f/pdf " << isMax
                                << " at wi (" << isMaxWi.x << ", " << isMaxWi.y << ", " << isMaxWi.z << "), pdf "
                                << lobe.pdf(wof, isMaxWi);
        }
    }
}

// §5.1 / §5.2: the analytic half-vector derivatives (chain rule through dwo, dwi = −P(wi) dp/|y − p|, dn and the
// Gram-Schmidt frame) equal central finite differences of q(x) computed from scratch along a synthetic screen path,
// and the quad (one-sided neighbour) difference agrees with them to first order.
TEST(FilteredGgxDerivatives, AnalyticMatchesFiniteDifferencesAndQuad) {
    for (int it = 0; it < 200; ++it) {
        const D3 eye = randDir() * 4.0, light = randDir() * 3.0 + D3(0, 0, 2);
        D3 p0 = randDir() * 0.3, dp = randDir() * 0.01;
        D3 n0 = randDir(), dnRaw = randDir() * 0.05;
        // Reference tangent in the tangent plane at x = 0: Gram-Schmidt then has no first-order twist about n
        // (the spec ignores tangent-field twist, §5.1).
        const D3 refT = glm::normalize(D3(1, 0.3, -0.2) - n0 * glm::dot(n0, D3(1, 0.3, -0.2)));
        if (glm::dot(n0, glm::normalize(eye - p0)) < 0.2 || glm::dot(n0, glm::normalize(light - p0)) < 0.2) continue;
        auto normalAt = [&](double x) { return glm::normalize(n0 + x * dnRaw); };
        auto frameAt = [&](double x, D3& t, D3& b, D3& n) {
            n = normalAt(x);
            t = glm::normalize(refT - n * glm::dot(n, refT));
            b = glm::cross(n, t);
        };
        for (bool slope : {false, true}) {
            auto q = [&](double x) {
                D3 p = p0 + x * dp, t, b, n;
                frameAt(x, t, b, n);
                D3 h = glm::normalize(glm::normalize(eye - p) + glm::normalize(light - p));
                return halfVectorQ(h, t, b, n, slope);
            };
            const double e = 1e-4;
            D2 fd = (q(e) - q(-e)) / (2 * e);
            // Analytic, in the local frame at x = 0.
            D3 t, b, n;
            frameAt(0, t, b, n);
            auto loc = [&](const D3& v) { return D3(glm::dot(v, t), glm::dot(v, b), glm::dot(v, n)); };
            D3 wo = glm::normalize(eye - p0), wi = glm::normalize(light - p0);
            Differentials df;
            df.valid = true;
            df.dp[0] = df.dp[1] = loc(dp);
            df.dwo[0] = df.dwo[1] = loc(-(dp - wo * glm::dot(wo, dp)) / glm::length(eye - p0));
            D3 dn = (dnRaw - n0 * glm::dot(n0, dnRaw)) / glm::length(n0);
            df.dn[0] = df.dn[1] = loc(dn);
            D2 an[2];
            halfVectorDeltasAnalytic(loc(wo), loc(wi), df, 1.0 / glm::length(light - p0), slope, an);
            double scale = glm::length(fd) + 1e-6;
            EXPECT_NEAR(an[0].x, fd.x, 1e-5 * scale + 1e-9) << slope;
            EXPECT_NEAR(an[0].y, fd.y, 1e-5 * scale + 1e-9) << slope;
            // Quad neighbour one step (x = 1) away; this pixel is the quad's x0 (sign +1).
            QuadNeighbour nb;
            nb.valid = true;
            D3 t1, b1, n1;
            frameAt(1.0 * 0.01, t1, b1, n1);
            nb.t = loc(t1), nb.b = loc(b1), nb.n = loc(n1);
            nb.dp = loc(dp * 0.01);
            nb.wo = loc(glm::normalize(eye - (p0 + dp * 0.01)));
            D2 qd;
            D3 hl = glm::normalize(loc(wo) + loc(wi));
            ASSERT_TRUE(halfVectorDeltaQuad(loc(wi), halfVectorQ(hl, D3(1, 0, 0), D3(0, 1, 0), D3(0, 0, 1), slope), nb,
                                            1.0 / glm::length(light - p0), slope, qd));
            qd /= 0.01;  // the neighbour was placed 0.01 steps away
            EXPECT_NEAR(qd.x, fd.x, 2e-2 * scale + 1e-7) << slope;
            EXPECT_NEAR(qd.y, fd.y, 2e-2 * scale + 1e-7) << slope;
        }
    }
}

// The evaluation used by the renderer (one reciprocal, prepared matrices; double, or float for projected_approx with
// analytic derivatives) against an independent long-double evaluation of the paper's formulas for the same filtered
// matrices (those of the double filter): D (TK21 Eq. 1 with the A.4 clamp), height-correlated G2 (Heitz 2014
// Eq. 99), pdf = D_Ā_s(h) G1(wo) / (4 wo_z) (Heitz 2018 Eq. 1 over the reflection Jacobian), for every filter,
// kernel, derivative source and light distance. Fresnel and tint are one.
// Double: the pdf measured within 1 float ulp, f within 5 (2.9e-7: the NDF's quadratic form of a filtered, nearly
// singular Ā loses a few bits in double); asserted 1e-6 relative.
// Float (FloatProjectedApprox): the filter, det Ā and the quadratic forms of Ā, Ā⁻¹ and Ā_s lose about
// eps·κ each, κ = (a d + c²)/(a d − c²) the condition of det Ā = a d − c² (1 for a diagonal matrix; at most 7 where the
// float form runs, a d ≤ 4 det Ā), and about 20 roundings follow in series: asserted 32 eps κ with eps = 2⁻²⁴.
// The measured worst of each variant and path is printed (relative, and in units of eps κ for the float path).
TEST(FilteredGgxMath, FastEvaluationEqualsLongDoubleReference) {
    using LD = long double;
    // The shared generator is restored at the end, so that the tests after this one draw the inputs they always drew.
    const std::mt19937_64 savedRng = rng();
    auto referenceD = [](const LD h[3], const Sym2& A, double tau) {
        LD det = std::max(LD(A.a) * A.d - LD(A.c) * A.c, LD(tau));
        LD q = (LD(A.d) * h[0] * h[0] - 2 * LD(A.c) * h[0] * h[1] + LD(A.a) * h[1] * h[1]) / det + h[2] * h[2];
        return 1 / (3.14159265358979323846264338327950288L * std::sqrt(det) * q * q);
    };
    auto referenceLambda = [](const LD w[3], const Sym2& A) {
        LD q = LD(A.a) * w[0] * w[0] + 2 * LD(A.c) * w[0] * w[1] + LD(A.d) * w[1] * w[1];
        return (std::sqrt(1 + q / (w[2] * w[2])) - 1) / 2;
    };
    double worstF = 0, worstPdf = 0;
    int checked = 0;
    for (Filter f : kAllFilters)
        for (Kernel k : {Kernel::Full, Kernel::AxisAligned}) {
            // Worst relative errors of this variant: double path (f, pdf), float path (f, pdf, in units of eps κ).
            double wD[2] = {0, 0}, wF[2] = {0, 0}, wFk = 0;
            int floatQueries = 0;
            for (int it = 0; it < 200; ++it) {
                LobeSetup s;
                if (it % 3 == 0) {
                    s.A = randSpd(1e-6, 0.6);
                } else {
                    s.A = randDiagonal(0.003, 0.9);
                }
                s.diff = randDiff(uni(0.0, 0.1));
                s.params = params(f, k);
                if (it % 4 == 1) {  // quad neighbours as well as analytic derivatives
                    s.quad = true;
                    for (int n = 0; n < 2; ++n) {
                        QuadNeighbour& nb = s.nb[n];
                        nb.valid = true;
                        nb.sign = n == 0 ? 1.0 : -1.0;
                        nb.dp = randDir() * 0.01;
                        nb.wo = randUpper(0.2);
                        nb.n = glm::normalize(D3(0, 0, 1) + randDir() * 0.02);
                        nb.t = glm::normalize(D3(1, 0, 0) - nb.n * nb.n.x);
                        nb.b = glm::cross(nb.n, nb.t);
                    }
                }
                FilteredGgxLobe lobe(s, Fresnel::one());
                const D3 woD = randUpper(0.02);
                if (it % 2) lobe.setSamplingFromMirror(woD);
                const D3 wiD = randUpper(0.02);
                const float dist = it % 5 == 0 ? std::numeric_limits<float>::infinity() : float(uni(0.5, 20));
                const LobeQuery q{Vec3(woD), Vec3(wiD), dist};
                const LobeValue fast = lobe.evalPdf(q);
                // Reference, from the float directions the lobe sees.
                const D3 wo(q.wo), wi(q.wi);
                const Sym2 Ab = lobe.filtered(wo, wi, std::isfinite(dist) ? 1.0 / dist : 0.0), As = lobe.samplingMatrix();
                const LD o[3] = {wo.x, wo.y, wo.z}, i[3] = {wi.x, wi.y, wi.z};
                LD H[3] = {o[0] + i[0], o[1] + i[1], o[2] + i[2]};
                const LD len = std::sqrt(H[0] * H[0] + H[1] * H[1] + H[2] * H[2]);
                const LD h[3] = {H[0] / len, H[1] / len, H[2] / len};
                const LD refF = referenceD(h, Ab, lobe.tau()) / (1 + referenceLambda(o, Ab) + referenceLambda(i, Ab)) / (4 * o[2]);
                const LD refPdf = referenceD(h, As, lobe.tau()) / (1 + referenceLambda(o, As)) / (4 * o[2]);
                ASSERT_GT(refPdf, 0);
                const double ef = double(std::abs(fast.f.x - refF) / refF), ep = double(std::abs(fast.pdf - refPdf) / refPdf);
                worstF = std::max(worstF, ef), worstPdf = std::max(worstPdf, ep);
                if (lobe.usesFloat()) {
                    auto condition = [](const Sym2& M) { return (M.a * M.d + M.c * M.c) / M.det(); };
                    const double kappa = std::max(condition(Ab), condition(As));
                    const double bound = 32.0 * std::ldexp(1.0, -24) * kappa;
                    EXPECT_LE(ef, bound) << filterName(f) << " it " << it << " kappa " << kappa;
                    EXPECT_LE(ep, bound) << filterName(f) << " it " << it << " kappa " << kappa;
                    wF[0] = std::max(wF[0], ef), wF[1] = std::max(wF[1], ep);
                    wFk = std::max(wFk, std::max(ef, ep) / (std::ldexp(1.0, -24) * kappa));
                    ++floatQueries;
                } else {
                    EXPECT_LE(ef, 1e-6) << filterName(f) << " it " << it;
                    EXPECT_LE(ep, 1e-6) << filterName(f) << " it " << it;
                    wD[0] = std::max(wD[0], ef), wD[1] = std::max(wD[1], ep);
                }
                ++checked;
            }
            std::printf("  %-16s %-12s double: f %.2e pdf %.2e | float lobes (%3d of 200): f %.2e pdf %.2e, %.1f eps*kappa\n",
                        filterName(f), k == Kernel::Full ? "full" : "axis_aligned", wD[0], wD[1], floatQueries, wF[0], wF[1], wFk);
            if (f == Filter::ProjectedApprox) EXPECT_GT(floatQueries, 20) << "the float path must be exercised";
        }
    std::printf("fast evaluation vs long-double reference, %d queries: worst relative error f %.2e, pdf %.2e\n", checked,
                worstF, worstPdf);
    rng() = savedRng;
}
