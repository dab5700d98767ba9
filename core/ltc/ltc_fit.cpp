// Fitting LTCs: the Student-t (ν = 2) EM fit of weighted directions (ltc-filtering.md §5.2) and, built on it and on
// the Nelder-Mead L3 fit of ltc_code (§2), the isotropic/anisotropic GGX tables and the sphere table (§3 step 5).
#include "core/ltc/ltc_fit.h"

#include "core/render/lobes/ggx.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <thread>

namespace specula::ltc {

namespace {

using DMat3 = glm::dmat3;
using DVec2 = glm::dvec2;

// Symmetric 2×2 matrix (s00, s01; s01, s11) with its eigenvalues clamped to >= lo (§5.2 step 3: keeps S invertible
// when the samples are (nearly) collinear, e.g. a mirror-like lobe fitted from few distinct directions).
void clampEigen2(double& s00, double& s01, double& s11, double lo) {
    double tr = 0.5 * (s00 + s11);
    double d = 0.5 * (s00 - s11);
    double r = std::sqrt(d * d + s01 * s01);
    double l0 = tr + r, l1 = tr - r;  // l0 >= l1
    if (l1 >= lo) return;
    // Eigenvector of l0: (cos c, sin c) with tan 2c = 2 s01 / (s00 − s11).
    double c = 0.5 * std::atan2(2.0 * s01, s00 - s11);
    double ca = std::cos(c), sa = std::sin(c);
    l0 = std::max(l0, lo);
    l1 = std::max(l1, lo);
    s00 = l0 * ca * ca + l1 * sa * sa;
    s11 = l0 * sa * sa + l1 * ca * ca;
    s01 = (l0 - l1) * ca * sa;
}

}  // namespace

Ltc fitStudentT(const std::vector<WeightedDirection>& samples, const Vec3& tangentHint, int iterations) {
    Ltc out;
    out.invM = Mat3(1.f);
    out.fresnel = 0.f;
    const size_t n = samples.size();
    if (n == 0) {
        out.magnitude = 0.f;
        return out;
    }
    // Magnitude = mean sample weight over ALL samples, dropped ones included (§5.2 step 4): with weights f·cos/pdf it
    // is the Monte Carlo estimate of the albedo.
    double wSum = 0.0;
    DVec3 mean(0.0);
    for (const WeightedDirection& s : samples) {
        wSum += double(s.weight);
        mean += double(s.weight) * DVec3(s.w);
    }
    out.magnitude = float(wSum / double(n));
    double meanLen = glm::length(mean);
    if (!(wSum > 0.0) || !(meanLen > 0.0)) return out;

    // Step 1: axis Z = normalised weighted mean; X = Gram-Schmidt of the hint, so that neighbouring fits share a frame
    // (no KHDN22 alignment pass needed); Y = Z × X.
    DVec3 Z = mean / meanLen;
    DVec3 X = DVec3(tangentHint) - Z * glm::dot(Z, DVec3(tangentHint));
    if (!(glm::dot(X, X) > 1e-20)) {
        // Hint parallel to the axis: any deterministic perpendicular.
        DVec3 a = std::abs(Z.x) < 0.9 ? DVec3(1, 0, 0) : DVec3(0, 1, 0);
        X = a - Z * glm::dot(Z, a);
    }
    X = glm::normalize(X);
    DVec3 Y = glm::cross(Z, X);

    // Step 2: gnomonic projection p = (w·X, w·Y)/(w·Z); samples with w·Z <= 1e-4 are dropped (their weight still counts
    // in the magnitude above).
    std::vector<DVec2> p;
    std::vector<double> om;
    p.reserve(n);
    om.reserve(n);
    double omSum = 0.0;
    for (const WeightedDirection& s : samples) {
        DVec3 w(s.w);
        double wz = glm::dot(w, Z);
        if (wz <= 1e-4 || !(s.weight > 0.f)) continue;  // weight 0 samples carry no information
        p.emplace_back(glm::dot(w, X) / wz, glm::dot(w, Y) / wz);
        om.push_back(double(s.weight));
        omSum += double(s.weight);
    }
    if (p.empty() || !(omSum > 0.0)) return out;

    // Step 3: Liu & Rubin (1995) EM for a bivariate Student-t with ν = 2 fixed: E-step weight (ν + 2)/(ν + δ) = 4/(2 + δ).
    // Start: μ = 0, S = ½·median(|p|²)·I (the median of the unweighted kept samples; the upper median for an even count).
    std::vector<double> r2(p.size());
    for (size_t i = 0; i < p.size(); ++i) r2[i] = glm::dot(p[i], p[i]);
    std::nth_element(r2.begin(), r2.begin() + r2.size() / 2, r2.end());
    double med = r2[r2.size() / 2];
    const double kEigMin = 1e-14;
    DVec2 mu(0.0);
    double s00 = std::max(0.5 * med, kEigMin), s01 = 0.0, s11 = s00;
    std::vector<double> wt(p.size());
    for (int it = 0; it < iterations; ++it) {
        double det = s00 * s11 - s01 * s01;
        double i00 = s11 / det, i01 = -s01 / det, i11 = s00 / det;
        double sw = 0.0;
        DVec2 m(0.0);
        for (size_t i = 0; i < p.size(); ++i) {
            DVec2 d = p[i] - mu;
            double delta = d.x * d.x * i00 + 2.0 * d.x * d.y * i01 + d.y * d.y * i11;
            wt[i] = om[i] * 4.0 / (2.0 + delta);
            sw += wt[i];
            m += wt[i] * p[i];
        }
        mu = m / sw;
        double a00 = 0.0, a01 = 0.0, a11 = 0.0;
        for (size_t i = 0; i < p.size(); ++i) {
            DVec2 d = p[i] - mu;
            a00 += wt[i] * d.x * d.x;
            a01 += wt[i] * d.x * d.y;
            a11 += wt[i] * d.y * d.y;
        }
        s00 = a00 / omSum;
        s01 = a01 / omSum;
        s11 = a11 / omSum;
        clampEigen2(s00, s01, s11, kEigMin);
    }

    // Step 4: p = A u + μ with u ~ t₂(0, I/2) (the clamped cosine in gnomonic coordinates, §1), so A Aᵀ = 2S:
    // A = lower Cholesky of 2S; K rows (A11, 0, μx), (A21, A22, μy), (0, 0, 1); M = [X Y Z]·K.
    double c00 = 2.0 * s00, c01 = 2.0 * s01, c11 = 2.0 * s11;
    double A11 = std::sqrt(c00);
    double A21 = c01 / A11;
    double A22 = std::sqrt(std::max(c11 - A21 * A21, kEigMin));
    DMat3 K(1.0);  // glm: K[col][row]
    K[0][0] = A11;
    K[0][1] = A21;
    K[1][1] = A22;
    K[2][0] = mu.x;
    K[2][1] = mu.y;
    K[2][2] = 1.0;
    K[0][2] = 0.0;
    K[1][0] = 0.0;
    K[1][2] = 0.0;
    DMat3 Q(X, Y, Z);
    DMat3 M = Q * K;
    DMat3 inv = glm::inverse(M);
    // Normalisation: the LTC is invariant to the scale of invM; we scale it to determinant 1 (det M = A11·A22 > 0), which
    // keeps the entries O(1/α^(1/3))..O(α^(2/3)) — well inside float range for any lobe — and makes tables interpolate
    // between consistently scaled neighbours.
    double det = glm::determinant(inv);
    inv *= 1.0 / std::cbrt(det);
    out.invM = Mat3(inv);
    return out;
}


// ---- Shared helpers of the table fits ------------------------------------------------------------------------------

namespace {

constexpr double kPiD = 3.14159265358979323846;

// Runs body(i) for i in [0, count) on 'threads' threads. Every i writes only its own outputs, so the result does not
// depend on the thread count or on which thread takes which i (T9).
void parallelFor(int count, int threads, const std::function<void(int)>& body) {
    threads = std::max(1, std::min(threads, count));
    if (threads == 1) {
        for (int i = 0; i < count; ++i) body(i);
        return;
    }
    std::atomic<int> next{0};
    std::vector<std::thread> pool;
    for (int k = 0; k < threads; ++k)
        pool.emplace_back([&] {
            for (int i = next.fetch_add(1); i < count; i = next.fetch_add(1)) body(i);
        });
    for (std::thread& th : pool) th.join();
}

double seconds(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// GGX f·cos and the VNDF pdf of direction l (§2 "Target": F = 1, height-correlated G2), from ggx.h's functions.
// The pdf is that of the sampler (Heitz 2018: D_v(h)/(4 v·h) = G1(v) D(h)/(4 v_z)), also below the horizon where
// the sampler does put directions (f = 0 there): the balance heuristic of the MIS objective needs the true density.
struct GgxCell {
    Vec3 v;
    float ax, ay;
    float g1v;
    GgxCell(const Vec3& v_, float ax_, float ay_) : v(v_), ax(ax_), ay(ay_), g1v(ggx::g1(v_, ax_, ay_)) {}
    void eval(const Vec3& l, double& f, double& pdf) const {
        f = 0.0;
        pdf = 0.0;
        Vec3 h = v + l;
        float len = glm::length(h);
        if (!(len > 0.f)) return;
        h /= len;
        if (glm::dot(v, h) <= 0.f) return;
        double d = ggx::ndf(h, ax, ay);
        pdf = double(g1v) * d / (4.0 * double(v.z));
        if (l.z > 0.f) f = d * double(ggx::g2(v, l, ax, ay)) / (4.0 * double(v.z));
    }
};

// Stratified VNDF samples of one cell, u = ((i + ½)/n, (j + ½)/n): direction, weight f·cos/pdf = G2/G1(v) (0 below the
// horizon) and the Schlick term (1 − v·h)⁵.
struct VndfSample {
    Vec3 l;
    float weight;
    float schlick;
};
void vndfSamples(const Vec3& v, float ax, float ay, int n, std::vector<VndfSample>& out) {
    out.resize(size_t(n) * n);
    float g1v = ggx::g1(v, ax, ay);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec2 u((i + 0.5f) / n, (j + 0.5f) / n);
            Vec3 h = ggx::sampleVisibleNormal(v, u, ax, ay);
            Vec3 l = ggx::reflect(v, h);
            VndfSample& s = out[size_t(j) * n + i];
            s.l = l;
            s.weight = l.z > 0.f ? ggx::g2(v, l, ax, ay) / g1v : 0.f;
            s.schlick = float(std::pow(1.0 - std::clamp(double(glm::dot(v, h)), 0.0, 1.0), 5.0));
        }
}

// mag = ∫ f·cos, fres = ∫ f·cos·(1 − v·h)⁵ and the f·cos-weighted mean direction (ltc_code computeAvgTerms), estimated
// with n² stratified VNDF samples.
struct Moments {
    double mag = 0, fres = 0;
    DVec3 avg{0.0};
};
Moments moments(const Vec3& v, float ax, float ay, int n) {
    std::vector<VndfSample> s;
    vndfSamples(v, ax, ay, n, s);
    Moments m;
    for (const VndfSample& x : s) {
        m.mag += x.weight;
        m.fres += double(x.weight) * x.schlick;
        m.avg += double(x.weight) * DVec3(x.l);
    }
    m.mag /= double(s.size());
    m.fres /= double(s.size());
    return m;
}

Vec3 isoView(int t) {
    double c = isoCosTheta(t);
    return Vec3(float(std::sqrt(std::max(0.0, 1.0 - c * c))), 0.f, float(c));
}

// Nelder-Mead simplex minimiser (Nelder & Mead 1965) with the constants and the stopping rule of §2 "Optimizer":
// reflect 1, expand 2, contract 0.5, shrink 0.5, initial simplex start + delta per axis, stop when
// 2|f_lo − f_hi| < (|f_lo| + |f_hi|)·tol or after maxIter iterations. Deterministic (stable ordering of ties).
template <int D, class F>
void nelderMead(double* x, double delta, double tol, int maxIter, F&& f) {
    double s[D + 1][D];
    double fv[D + 1];
    for (int k = 0; k <= D; ++k) {
        for (int d = 0; d < D; ++d) s[k][d] = x[d];
        if (k > 0) s[k][k - 1] += delta;
        fv[k] = f(s[k]);
    }
    for (int it = 0; it < maxIter; ++it) {
        int lo = 0, hi = 0;
        for (int k = 1; k <= D; ++k) {
            if (fv[k] < fv[lo]) lo = k;
            if (fv[k] > fv[hi]) hi = k;
        }
        if (lo == hi) hi = (lo + 1) % (D + 1);  // all equal: any other vertex is "highest"
        int nh = lo;
        for (int k = 0; k <= D; ++k)
            if (k != hi && fv[k] > fv[nh]) nh = k;
        double a = std::abs(fv[lo]), b = std::abs(fv[hi]);
        if (2.0 * std::abs(a - b) < (a + b) * tol) break;
        double o[D] = {};
        for (int k = 0; k <= D; ++k)
            if (k != hi)
                for (int d = 0; d < D; ++d) o[d] += s[k][d] / D;
        auto along = [&](double c, const double* from, double* out) {  // out = o + c·(o − from)
            for (int d = 0; d < D; ++d) out[d] = o[d] + c * (o[d] - from[d]);
        };
        auto replaceHi = [&](const double* p, double fp) {
            for (int d = 0; d < D; ++d) s[hi][d] = p[d];
            fv[hi] = fp;
        };
        double r[D];
        along(1.0, s[hi], r);
        double fr = f(r);
        if (fr < fv[lo]) {
            double e[D];
            along(2.0, s[hi], e);
            double fe = f(e);
            if (fe < fr)
                replaceHi(e, fe);
            else
                replaceHi(r, fr);
        } else if (fr < fv[nh]) {
            replaceHi(r, fr);
        } else {
            double c[D];
            bool outside = fr < fv[hi];
            along(outside ? 0.5 : -0.5, s[hi], c);  // outside: o + ½(r − o); inside: o + ½(x_hi − o)
            double fc = f(c);
            if (fc < (outside ? fr : fv[hi])) {
                replaceHi(c, fc);
            } else {
                for (int k = 0; k <= D; ++k) {
                    if (k == lo) continue;
                    for (int d = 0; d < D; ++d) s[k][d] = s[lo][d] + 0.5 * (s[k][d] - s[lo][d]);
                    fv[k] = f(s[k]);
                }
            }
        }
    }
    int lo = 0;
    for (int k = 1; k <= D; ++k)
        if (fv[k] < fv[lo]) lo = k;
    for (int d = 0; d < D; ++d) x[d] = s[lo][d];
}

// One cell of the Nelder-Mead table: M = [X Y Z]·K_loc with K_loc rows (m11, 0, m13), (0, m22, 0), (0, 0, 1) (§2
// "Matrix form"), and the MIS L3 objective (§2 "Objective").
struct NmCell {
    GgxCell brdf;
    double mag;
    DMat3 frame;                       // [X Y Z]
    const std::vector<DVec3>* cosDirs;  // Ns² stratified cosine directions (shared by all cells)
    std::vector<DVec3> bl;              // the Ns² BRDF samples, fixed during the fit: direction, f·cos, pdf
    std::vector<double> bf, bp;

    NmCell(const Vec3& v, float alpha, double mag_, const DMat3& frame_, const std::vector<DVec3>& cd, int ns)
        : brdf(v, alpha, alpha), mag(mag_), frame(frame_), cosDirs(&cd) {
        std::vector<VndfSample> s;
        vndfSamples(v, alpha, alpha, ns, s);
        bl.resize(s.size());
        bf.resize(s.size());
        bp.resize(s.size());
        for (size_t k = 0; k < s.size(); ++k) {
            bl[k] = DVec3(s[k].l);
            brdf.eval(s[k].l, bf[k], bp[k]);
        }
    }
    static DMat3 kLoc(double m11, double m22, double m13) {
        DMat3 K(1.0);
        K[0][0] = m11;
        K[1][1] = m22;
        K[2][0] = m13;  // glm [col][row]: row 0, col 2
        return K;
    }
    double error(double m11, double m22, double m13) const {
        DMat3 M = frame * kLoc(m11, m22, m13);
        DMat3 inv = glm::inverse(M);
        double invDet = 1.0 / (m11 * m22);  // |det M⁻¹| (the frame is a rotation)
        double err = 0.0;
        const size_t n = bl.size();
        for (size_t k = 0; k < n; ++k) {
            // LTC sample: L = M w_o/|M w_o|, D(L) = D_o(w_o)·|det M⁻¹|·|M w_o|³ (§1).
            const DVec3& wo = (*cosDirs)[k];
            DVec3 mw = M * wo;
            double len = glm::length(mw);
            DVec3 L = mw / len;
            double dl = wo.z / kPiD * invDet * len * len * len;
            double f, pb;
            brdf.eval(Vec3(L), f, pb);
            double e = std::abs(f - mag * dl);
            if (dl + pb > 0.0) err += e * e * e / (dl + pb);
        }
        for (size_t k = 0; k < n; ++k) {
            // BRDF sample: D(L) = D_o(M⁻¹L/|M⁻¹L|)·|det M⁻¹|/|M⁻¹L|³ (HDHN16 Eq. 1).
            DVec3 lo = inv * bl[k];
            double len = glm::length(lo);
            double dl = lo.z > 0.0 ? lo.z / len / kPiD * invDet / (len * len * len) : 0.0;
            double e = std::abs(bf[k] - mag * dl);
            if (dl + bp[k] > 0.0) err += e * e * e / (dl + bp[k]);
        }
        return err / double(n);
    }
};

struct NmParams {
    double m11 = 1, m22 = 1, m13 = 0;
};

// Fits one cell from 'p' (warm start) and returns the clamped parameters (m11, m22 >= 1e-7, §2 "Matrix form").
NmParams fitNmCell(const NmCell& cell, const NmParams& p, bool isotropic) {
    const double kDelta = 0.05, kTol = 1e-5;
    const int kMaxIter = 100;
    NmParams out;
    if (isotropic) {
        double x[1] = {p.m11};
        nelderMead<1>(x, kDelta, kTol, kMaxIter, [&](const double* q) {
            double m = std::max(q[0], 1e-7);
            return cell.error(m, m, 0.0);
        });
        out.m11 = out.m22 = std::max(x[0], 1e-7);
        out.m13 = 0.0;
    } else {
        double x[3] = {p.m11, p.m22, p.m13};
        nelderMead<3>(x, kDelta, kTol, kMaxIter, [&](const double* q) {
            return cell.error(std::max(q[0], 1e-7), std::max(q[1], 1e-7), q[2]);
        });
        out.m11 = std::max(x[0], 1e-7);
        out.m22 = std::max(x[1], 1e-7);
        out.m13 = x[2];
    }
    return out;
}

// Packs inv(M) of the view-aligned frame as ltc_code's texture 1 (§2 "Packing"): divided by its (1,1) entry, the
// entries (row, col) = (0,0), (2,0), (0,2), (2,2). The y-couplings are zero by construction (or zeroed: t-EM).
void packIso(const DMat3& invM, float* out) {
    DMat3 m = invM / invM[1][1];
    out[0] = float(m[0][0]);  // (0,0)
    out[1] = float(m[0][2]);  // (2,0): glm [col][row]
    out[2] = float(m[2][0]);  // (0,2)
    out[3] = float(m[2][2]);  // (2,2)
}

std::vector<DVec3> cosineDirections(int ns) {
    // ltc_code's LTC sampler: cos θ = √u1, φ = 2π u2 (a cosine-distributed direction).
    std::vector<DVec3> d(size_t(ns) * ns);
    for (int j = 0; j < ns; ++j)
        for (int i = 0; i < ns; ++i) {
            double u1 = (i + 0.5) / ns, u2 = (j + 0.5) / ns;
            double ct = std::sqrt(u1), st = std::sqrt(1.0 - u1), ph = 2.0 * kPiD * u2;
            d[size_t(j) * ns + i] = DVec3(st * std::cos(ph), st * std::sin(ph), ct);
        }
    return d;
}

}  // namespace

double isoAlpha(int a) {
    double r = a / 63.0;
    return std::max(r * r, 1e-5);
}

double isoCosTheta(int t) {
    double x = t / 63.0;
    return std::max(1.0 - x * x, std::cos(1.57));
}

IsoTable fitGgxIsoNelderMead(const IsoFitOptions& opt) {
    const int N = LtcTables::kIsoSize;
    const int aMin = std::clamp(opt.aMin, 0, N - 1);
    const int rows = N - aMin;
    IsoTable tab;
    tab.inv.assign(size_t(N) * N * 4, 0.f);
    tab.magFres.assign(size_t(N) * N * 2, 0.f);
    const std::vector<DVec3> cosDirs = cosineDirections(opt.ns);

    // mag, fres, mean direction of every cell (independent, rows in parallel).
    std::vector<Moments> mom(size_t(N) * N);
    parallelFor(rows, opt.threads, [&](int r) {
        int a = N - 1 - r;
        float alpha = float(isoAlpha(a));
        for (int t = 0; t < N; ++t) {
            Moments m = moments(isoView(t), alpha, alpha, opt.momentsN);
            mom[size_t(t) * N + a] = m;
            tab.magFres[(size_t(t) * N + a) * 2 + 0] = float(m.mag);
            tab.magFres[(size_t(t) * N + a) * 2 + 1] = float(m.fres);
        }
    });

    auto cellFrame = [&](int a, int t) {
        if (t == 0) return DMat3(1.0);  // §2: identity frame at normal incidence
        DVec3 z = mom[size_t(t) * N + a].avg;
        z.y = 0.0;
        z = glm::normalize(z);
        return DMat3(DVec3(z.z, 0.0, -z.x), DVec3(0.0, 1.0, 0.0), z);  // X = (Z_z, 0, −Z_x), Y = (0, 1, 0)
    };
    auto store = [&](int a, int t, const NmParams& p, const DMat3& frame) {
        DMat3 M = frame * NmCell::kLoc(p.m11, p.m22, p.m13);
        packIso(glm::inverse(M), &tab.inv[(size_t(t) * N + a) * 4]);
    };

    // The t = 0 column, rough to smooth, each cell warm-started from the rougher one (first: m11 = m22 = 1), 1 parameter.
    std::vector<NmParams> col(N);
    NmParams p;
    for (int a = N - 1; a >= aMin; --a) {
        float alpha = float(isoAlpha(a));
        NmCell cell(isoView(0), alpha, mom[size_t(a)].mag, cellFrame(a, 0), cosDirs, opt.ns);
        p = fitNmCell(cell, p, true);
        col[a] = p;
        store(a, 0, p, cell.frame);
    }
    // Each row t = 1..63 from its t = 0 result, warm start from the previous cell; rows are independent.
    parallelFor(rows, opt.threads, [&](int r) {
        int a = N - 1 - r;
        float alpha = float(isoAlpha(a));
        NmParams q = col[a];
        for (int t = 1; t < N; ++t) {
            DMat3 frame = cellFrame(a, t);
            NmCell cell(isoView(t), alpha, mom[size_t(t) * N + a].mag, frame, cosDirs, opt.ns);
            q = fitNmCell(cell, q, false);
            store(a, t, q, frame);
        }
    });
    return tab;
}

IsoTable fitGgxIsoStudentT(int samplesPerAxis, int threads) {
    const int N = LtcTables::kIsoSize;
    IsoTable tab;
    tab.inv.assign(size_t(N) * N * 4, 0.f);
    tab.magFres.assign(size_t(N) * N * 2, 0.f);
    parallelFor(N, threads, [&](int a) {
        float alpha = float(isoAlpha(a));
        std::vector<VndfSample> s;
        std::vector<WeightedDirection> w;
        for (int t = 0; t < N; ++t) {
            vndfSamples(isoView(t), alpha, alpha, samplesPerAxis, s);
            w.resize(s.size());
            double fres = 0.0;
            for (size_t k = 0; k < s.size(); ++k) {
                w[k] = {s[k].l, s[k].weight};
                fres += double(s[k].weight) * s[k].schlick;
            }
            Ltc l = fitStudentT(w, Vec3(1, 0, 0));
            DMat3 inv(l.invM);
            // The target is symmetric in y: zero the y-couplings (sampling noise) as the reference does (§2).
            inv[1][0] = inv[0][1] = inv[2][1] = inv[1][2] = 0.0;
            size_t c = size_t(t) * N + a;
            packIso(inv, &tab.inv[c * 4]);
            tab.magFres[c * 2 + 0] = l.magnitude;
            tab.magFres[c * 2 + 1] = float(fres / double(s.size()));
        }
    });
    return tab;
}

double capFormFactorSnyder(double omega, double sigma) {
    // Snyder 1996 (ltc-filtering.md §3 step 5), s = sin²σ; normalised so that the whole hemisphere gives 1.
    if (sigma <= 0.0) return 0.0;
    double s = std::sin(sigma) * std::sin(sigma);
    double co = std::cos(omega), so = std::sin(omega), cs = std::cos(sigma), ss = std::sin(sigma);
    if (omega <= 0.5 * kPiD - sigma) return co * s;
    if (omega >= 0.5 * kPiD + sigma) return 0.0;
    double g = std::asin(std::clamp(cs / so, -1.0, 1.0));
    double cg = std::cos(g), sg = std::sin(g);
    double G = -2.0 * so * cs * cg + 0.5 * kPiD - g + sg * cg;
    double H = co * (cg * std::sqrt(std::max(0.0, s - cg * cg)) + s * std::asin(std::clamp(cg / ss, -1.0, 1.0)));
    if (omega < 0.5 * kPiD) return (kPiD * co * s + G - H) / kPiD;
    return (G + H) / kPiD;
}

std::vector<float> fitSphereTable() {
    const int N = LtcTables::kIsoSize;
    std::vector<float> tab(size_t(N) * N);
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
            double z = 2.0 * i / (N - 1) - 1.0, len = double(j) / (N - 1);
            double v;
            if (len <= 0.0) {
                v = std::max(z, 0.0);  // σ = 0: F/len → max(z, 0)
            } else {
                double sigma = std::asin(std::min(1.0, std::sqrt(len)));
                double omega = std::acos(std::clamp(z, -1.0, 1.0));
                v = capFormFactorSnyder(omega, sigma) / len;
            }
            tab[size_t(j) * N + i] = float(v);
        }
    return tab;
}

double anisoAlpha(int i, int n) {
    double r = double(i) / (n - 1);
    return std::max(r * r, 1e-3);
}
double anisoCosTheta(int t, int n) {
    double x = double(t) / (n - 1);
    return std::max(1.0 - x * x, std::cos(0.9999 * 0.5 * kPiD));
}
double anisoPhi(int k, int nPhi) { return nPhi > 1 ? double(k) / (nPhi - 1) * 0.5 * kPiD : 0.0; }

void fitGgxAnisotropic(int n, int nPhi, int samplesPerAxis, int threads, LtcTables& out) {
    out.anisoSize = n;
    out.anisoPhiSize = nPhi;
    const size_t cells = size_t(n) * n * n * nPhi;
    out.anisoInv.assign(cells * 9, 0.f);
    out.anisoMagFres.assign(cells * 2, 0.f);
    // One task per (φ, θ) pair: all (αx, αy) of it.
    parallelFor(n * nPhi, threads, [&](int task) {
        int k = task / n, t = task % n;
        double c = anisoCosTheta(t, n), st = std::sqrt(std::max(0.0, 1.0 - c * c)), ph = anisoPhi(k, nPhi);
        Vec3 v(float(st * std::cos(ph)), float(st * std::sin(ph)), float(c));
        std::vector<VndfSample> s;
        std::vector<WeightedDirection> w;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                vndfSamples(v, float(anisoAlpha(i, n)), float(anisoAlpha(j, n)), samplesPerAxis, s);
                w.resize(s.size());
                double fres = 0.0;
                for (size_t q = 0; q < s.size(); ++q) {
                    w[q] = {s[q].l, s[q].weight};
                    fres += double(s[q].weight) * s[q].schlick;
                }
                Ltc l = fitStudentT(w, Vec3(1, 0, 0));
                size_t cell = ((size_t(k) * n + t) * n + j) * n + i;
                for (int col = 0; col < 3; ++col)
                    for (int row = 0; row < 3; ++row) out.anisoInv[cell * 9 + col * 3 + row] = l.invM[col][row];
                out.anisoMagFres[cell * 2 + 0] = l.magnitude;
                out.anisoMagFres[cell * 2 + 1] = float(fres / double(s.size()));
            }
    });
}

LtcTables fitAllTables(int threads, FitTimes* times) {
    LtcTables t;
    FitTimes ft;
    auto t0 = std::chrono::steady_clock::now();
    IsoFitOptions opt;
    opt.ns = kShippedNs;
    opt.threads = threads;
    IsoTable iso = fitGgxIsoNelderMead(opt);
    t.ggxInv = std::move(iso.inv);
    t.ggxMagFres = std::move(iso.magFres);
    ft.iso = seconds(t0);
    t0 = std::chrono::steady_clock::now();
    t.sphere = fitSphereTable();
    ft.sphere = seconds(t0);
    t0 = std::chrono::steady_clock::now();
    fitGgxAnisotropic(kShippedAnisoSize, kShippedAnisoPhiSize, kShippedAnisoSamples, threads, t);
    ft.aniso = seconds(t0);
    if (times) *times = ft;
    return t;
}

}  // namespace specula::ltc
