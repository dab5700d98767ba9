// Tests for the LTC fits and tables (core/ltc/ltc_fit, core/ltc/ltc_tables): the Student-t EM fit, and the
// acceptance invariants of ltc-filtering.md §6 that concern the tables (T1, T4, T8, T9, T10, T11, golden hash, drift).
#include "core/ltc/ltc_fit.h"
#include "core/ltc/ltc_tables.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <thread>
#include <vector>

using namespace specula;
using namespace specula::ltc;

namespace {

constexpr double kPiD = 3.14159265358979323846;
using DMat3 = glm::dmat3;

// D(w) of an LTC given its inverse (HDHN16 Eq. 1); computed here in double so the tests do not depend on ltc.cpp.
double ltcDensity(const DMat3& invM, const DVec3& w) {
    DVec3 wo = invM * w;
    double l = glm::length(wo);
    double z = wo.z / l;
    if (z <= 0.0) return 0.0;
    return z / kPiD * std::abs(glm::determinant(invM)) / (l * l * l);
}

// Cosine-distributed direction for stratified u (Malley's method).
DVec3 cosineDir(double u1, double u2) {
    double r = std::sqrt(u1), ph = 2.0 * kPiD * u2;
    return {r * std::cos(ph), r * std::sin(ph), std::sqrt(std::max(0.0, 1.0 - u1))};
}

}  // namespace

// §5.2: samples drawn from a known LTC (M = Q·K with μ = 0, so its weighted mean is exactly Q's axis and the t-EM model
// is exact) give back the same density: ∫|D_fit − D_true| (importance-sampled from D_true) below 2%.
TEST(LtcFit, StudentTRecoversKnownLtc) {
    DMat3 K(1.0);
    K[0][0] = 0.35;  // A11
    K[0][1] = 0.12;  // A21 (shear)
    K[1][1] = 0.6;   // A22
    DVec3 Z = glm::normalize(DVec3(0.3, -0.2, 0.9));
    DVec3 X = glm::normalize(glm::cross(DVec3(0, 1, 0), Z));
    DVec3 Y = glm::cross(Z, X);
    DMat3 M = DMat3(X, Y, Z) * K;
    DMat3 invTrue = glm::inverse(M);
    const int n = 128;
    std::vector<WeightedDirection> s;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            DVec3 w = glm::normalize(M * cosineDir((i + 0.5) / n, (j + 0.5) / n));
            s.push_back({Vec3(w), 0.75f});
        }
    Ltc fit = fitStudentT(s, Vec3(1, 0, 0));
    EXPECT_NEAR(fit.magnitude, 0.75f, 1e-6f);
    EXPECT_NEAR(glm::determinant(fit.invM), 1.f, 1e-4f);  // documented normalisation
    DMat3 invFit(fit.invM);
    double l1 = 0.0;
    const int m = 64;
    for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i) {
            DVec3 w = glm::normalize(M * cosineDir((i + 0.37) / m, (j + 0.61) / m));
            double dt = ltcDensity(invTrue, w), df = ltcDensity(invFit, w);
            l1 += std::abs(df / dt - 1.0);
        }
    l1 /= m * m;
    EXPECT_LT(l1, 0.02);
}

// Non-uniform weights: a weighted sample set equals the density it represents (cosine samples reweighted towards a
// narrower LTC would need the exact ratio; here half the samples get weight 0 — they must not move the fit — and the
// magnitude still averages over all of them).
TEST(LtcFit, StudentTZeroWeightsIgnoredButCounted) {
    DMat3 K(1.0);
    K[0][0] = 0.2;
    K[1][1] = 0.2;
    DMat3 M = K;
    const int n = 64;
    std::vector<WeightedDirection> a, b;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Vec3 w(glm::normalize(M * cosineDir((i + 0.5) / n, (j + 0.5) / n)));
            a.push_back({w, 1.f});
            b.push_back({w, 1.f});
            b.push_back({Vec3(0.6f, 0.f, 0.8f), 0.f});
        }
    Ltc fa = fitStudentT(a, Vec3(1, 0, 0)), fb = fitStudentT(b, Vec3(1, 0, 0));
    EXPECT_NEAR(fa.magnitude, 1.f, 1e-6f);
    EXPECT_NEAR(fb.magnitude, 0.5f, 1e-6f);
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) EXPECT_NEAR(fa.invM[c][r], fb.invM[c][r], 1e-5f);
    // The isotropic lobe M = diag(0.2, 0.2, 1) normalised to det 1: invM = diag(5, 5, 1)/25^(1/3).
    double k = 1.0 / std::cbrt(25.0);
    EXPECT_NEAR(fa.invM[0][0], 5 * k, 0.02 * 5 * k);
    EXPECT_NEAR(fa.invM[1][1], 5 * k, 0.02 * 5 * k);
    EXPECT_NEAR(fa.invM[2][2], k, 0.02 * k);
}

// ---- The tables ----------------------------------------------------------------------------------------------------

namespace {

const char* kRegenerate =
    "cmake --build build --target ltc-fit && build/bin/ltc-fit --out core/ltc/ltc_tables_data.cpp";

// Independent double-precision anisotropic GGX, the §2 target: f·cos = D G2/(4 v_z), F = 1 (Walter et al. 2007;
// Heitz 2014 Eq. 86 for Λ).
struct Ggx {
    double ax, ay;
    double D(const DVec3& h) const {
        if (h.z <= 0.0) return 0.0;
        double e = h.x * h.x / (ax * ax) + h.y * h.y / (ay * ay) + h.z * h.z;
        return 1.0 / (kPiD * ax * ay * e * e);
    }
    double lambda(const DVec3& w) const {
        double z2 = w.z * w.z;
        if (z2 <= 0.0) return 1e300;
        return 0.5 * (-1.0 + std::sqrt(1.0 + (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / z2));
    }
    double fcos(const DVec3& v, const DVec3& l) const {
        if (l.z <= 0.0 || v.z <= 0.0) return 0.0;
        DVec3 h = glm::normalize(v + l);
        return D(h) / (1.0 + lambda(v) + lambda(l)) / (4.0 * v.z);
    }
    // VNDF sampler (Heitz 2018) and its pdf D_v(h)/(4 v·h).
    DVec3 sample(const DVec3& v, double u1, double u2) const {
        DVec3 vh = glm::normalize(DVec3(ax * v.x, ay * v.y, v.z));
        double lensq = vh.x * vh.x + vh.y * vh.y;
        DVec3 t1 = lensq > 0 ? DVec3(-vh.y, vh.x, 0) / std::sqrt(lensq) : DVec3(1, 0, 0);
        DVec3 t2 = glm::cross(vh, t1);
        double r = std::sqrt(u1), ph = 2 * kPiD * u2;
        double p1 = r * std::cos(ph), p2 = r * std::sin(ph);
        double s = 0.5 * (1 + vh.z);
        p2 = (1 - s) * std::sqrt(std::max(0.0, 1 - p1 * p1)) + s * p2;
        DVec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0, 1 - p1 * p1 - p2 * p2)) * vh;
        DVec3 h = glm::normalize(DVec3(ax * nh.x, ay * nh.y, std::max(1e-12, nh.z)));
        return 2 * glm::dot(v, h) * h - v;
    }
    double pdf(const DVec3& v, const DVec3& l) const {
        DVec3 h = v + l;
        double len = glm::length(h);
        if (len <= 0) return 0.0;
        h /= len;
        if (glm::dot(v, h) <= 0 || v.z <= 0) return 0.0;
        return D(h) / (1.0 + lambda(v)) / (4.0 * v.z);
    }
};
double ggxFcos(const DVec3& v, const DVec3& l, double a) { return Ggx{a, a}.fcos(v, l); }
DVec3 ggxSampleVndf(const DVec3& v, double a, double u1, double u2) { return Ggx{a, a}.sample(v, u1, u2); }
double ggxPdfVndf(const DVec3& v, const DVec3& l, double a) { return Ggx{a, a}.pdf(v, l); }
DVec3 ltcSample(const DMat3& M, double u1, double u2) { return glm::normalize(M * cosineDir(u1, u2)); }

// Fast deterministic uniform numbers (splitmix64), so the tests do not depend on a library's distributions.
struct Rng {
    uint64_t s;
    explicit Rng(uint64_t seed) : s(seed) {}
    double operator()() {
        uint64_t z = (s += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        z ^= z >> 31;
        return (double(z >> 11) + 0.5) * (1.0 / 9007199254740992.0);
    }
};

DVec3 viewAt(double cosTheta) { return {std::sqrt(std::max(0.0, 1 - cosTheta * cosTheta)), 0.0, cosTheta}; }

// The table's LTC at a node, through the public lookup (wo in the xz plane: the lobe frame is the view frame).
Ltc nodeLtc(const LtcTables& t, int a, int ti) {
    return ggxIsotropic(t, float(isoAlpha(a)), Vec3(viewAt(isoCosTheta(ti))));
}

// L1/mag = ∫|f·cos − mag·D| / mag by MIS (VNDF + LTC samples, balance heuristic) (T10).
double l1OverMag(const Ltc& ltc, double alpha, const DVec3& v, int n, uint64_t seed) {
    DMat3 inv(ltc.invM), M = glm::inverse(inv);
    double mag = ltc.magnitude, sum = 0.0;
    Rng rng(seed);
    for (int k = 0; k < n; ++k) {
        DVec3 l1 = ggxSampleVndf(v, alpha, rng(), rng());
        DVec3 l2 = ltcSample(M, rng(), rng());
        for (const DVec3& l : {l1, l2}) {
            double d = ltcDensity(inv, l), p = ggxPdfVndf(v, l, alpha);
            if (d + p > 0) sum += std::abs(ggxFcos(v, l, alpha) - mag * d) / (d + p);
        }
    }
    return sum / n / mag;
}

// ∫_P D over a polygon (lobe-frame vertices), exact: transform by invM, clip to z > 0, Lambert's edge sum (§3 steps
// 2 and 4), two-sided. An independent cross-check of ltc::integrate.
double polygonIntegral(const DMat3& inv, const DVec3* p, int n) {
    DVec3 v[8], c[9];
    for (int i = 0; i < n; ++i) v[i] = inv * p[i];
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const DVec3& a = v[i];
        const DVec3& b = v[(i + 1) % n];
        if (a.z > 0) c[m++] = a;
        if ((a.z > 0) != (b.z > 0)) c[m++] = a + (b - a) * (a.z / (a.z - b.z));
    }
    if (m < 3) return 0.0;
    double e = 0.0;
    for (int i = 0; i < m; ++i) {
        DVec3 a = glm::normalize(c[i]), b = glm::normalize(c[(i + 1) % m]);
        DVec3 x = glm::cross(a, b);
        double s = glm::length(x);
        if (s < 1e-15) continue;
        e += std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0)) * x.z / s;
    }
    return std::abs(e) / (2 * kPiD);
}

// A quad (parallelogram o + s·e1 + t·e2) fully above the horizon, and an MIS Monte Carlo of ∫_quad f·cos
// (n light-area samples plus n VNDF samples, balance heuristic) (T6's reference).
struct Quad {
    DVec3 o, e1, e2;
    DVec3 vertex(int i) const { return i == 0 ? o : i == 1 ? o + e1 : i == 2 ? o + e1 + e2 : o + e2; }
};
Quad randomQuad(Rng& rng) {
    for (;;) {
        double elev = (10 + 75 * rng()) * kPiD / 180, az = 2 * kPiD * rng(), dist = 1 + 2 * rng();
        DVec3 c = dist * DVec3(std::cos(elev) * std::cos(az), std::cos(elev) * std::sin(az), std::sin(elev));
        DVec3 nrm = glm::normalize(-c + 0.6 * DVec3(rng() - 0.5, rng() - 0.5, rng() - 0.5));
        DVec3 a = glm::normalize(glm::cross(nrm, DVec3(0.3, 0.5, 0.8)));
        DVec3 b = glm::cross(nrm, a);
        double w = 0.2 + 1.3 * rng(), h = 0.2 + 1.3 * rng();
        Quad q{c - 0.5 * w * a - 0.5 * h * b, w * a, h * b};
        bool ok = true;
        for (int i = 0; i < 4; ++i) ok = ok && glm::normalize(q.vertex(i)).z > 0.02;
        if (ok) return q;
    }
}
double quadMc(const Quad& q, const DVec3& v, const Ggx& g, int n, Rng& rng) {
    DVec3 nrm = glm::cross(q.e1, q.e2);
    double area = glm::length(nrm);
    nrm /= area;
    auto lightPdf = [&](const DVec3& p) {  // solid-angle pdf of the uniform area sample at p
        double d2 = glm::dot(p, p);
        double c = std::abs(glm::dot(nrm, p)) / std::sqrt(d2);
        return c > 0 ? d2 / (area * c) : 0.0;
    };
    double sum = 0.0;
    for (int k = 0; k < n; ++k) {
        DVec3 p = q.o + rng() * q.e1 + rng() * q.e2;
        DVec3 l = glm::normalize(p);
        double pl = lightPdf(p), pb = g.pdf(v, l);
        sum += g.fcos(v, l) / (pl + pb);
        DVec3 lb = g.sample(v, rng(), rng());
        double den = glm::dot(nrm, lb);
        if (std::abs(den) > 1e-12) {
            double tt = glm::dot(nrm, q.o) / den;
            if (tt > 0) {
                DVec3 hit = tt * lb - q.o;
                // Parallelogram coordinates of the hit.
                double e11 = glm::dot(q.e1, q.e1), e12 = glm::dot(q.e1, q.e2), e22 = glm::dot(q.e2, q.e2);
                double h1 = glm::dot(hit, q.e1), h2 = glm::dot(hit, q.e2), det = e11 * e22 - e12 * e12;
                double s = (h1 * e22 - h2 * e12) / det, t = (h2 * e11 - h1 * e12) / det;
                if (s >= 0 && s <= 1 && t >= 0 && t <= 1) {
                    double pl2 = lightPdf(tt * lb), pb2 = g.pdf(v, lb);
                    sum += g.fcos(v, lb) / (pl2 + pb2);
                }
            }
        }
    }
    return sum / n;
}

// T6 metrics per θ band (< 30°, 30-60°, 60-88°) over random quads fully above the horizon: mean |LTC·mag − MC|/mag
// and the median relative error of quads capturing >= 10% of mag; for several lookups at once (same quads, same
// references). Views at a random azimuth (so the lookups' frame rotation and mirror symmetries are exercised);
// roughness cycles through 'rough' (αx = r², αy = r²·aniso).
using Lookup = std::function<Ltc(float, float, const Vec3&)>;
struct BandErrors {
    std::vector<double> abs[3], rel[3], est[3];  // est: LTC·mag per quad (to compare two lookups)
    double mean(int b) const {
        double s = 0;
        for (double x : abs[b]) s += x;
        return s / std::max<size_t>(1, abs[b].size());
    }
    double medianRel(int b) const {
        std::vector<double> r = rel[b];
        if (r.empty()) return 0.0;
        std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
        return r[r.size() / 2];
    }
};
std::vector<BandErrors> bandErrors(const std::vector<Lookup>& lookups, int quadsPerBand, int mcSamples,
                                   double aniso = 1.0, uint64_t seed = 12345) {
    std::vector<BandErrors> out(lookups.size());
    Rng rng(seed);
    const double bandLo[3] = {0, 30, 60}, bandHi[3] = {30, 60, 88};
    const double rough[3] = {0.3, 0.5, 0.8};
    for (int b = 0; b < 3; ++b)
        for (int k = 0; k < quadsPerBand; ++k) {
            double r = rough[k % 3];
            Ggx g{r * r, r * r * aniso};
            double th = (bandLo[b] + (bandHi[b] - bandLo[b]) * rng()) * kPiD / 180, ph = 2 * kPiD * rng();
            DVec3 v(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
            Quad q = randomQuad(rng);
            double ref = quadMc(q, v, g, mcSamples, rng);
            DVec3 p[4] = {q.vertex(0), q.vertex(1), q.vertex(2), q.vertex(3)};
            Vec3 pf[4] = {Vec3(p[0]), Vec3(p[1]), Vec3(p[2]), Vec3(p[3])};
            for (size_t i = 0; i < lookups.size(); ++i) {
                Ltc l = lookups[i](float(g.ax), float(g.ay), Vec3(v));
                // The integrator's exact path (ltc.cpp), cross-checked against this file's own edge sum.
                double pi = integrate(l, pf, 4, true, Horizon::Clip, nullptr);
                EXPECT_NEAR(pi, polygonIntegral(DMat3(l.invM), p, 4), 1e-4 + 1e-3 * pi);
                double est = l.magnitude * pi;
                out[i].abs[b].push_back(std::abs(est - ref) / l.magnitude);
                out[i].est[b].push_back(est / l.magnitude);
                if (ref >= 0.1 * l.magnitude) out[i].rel[b].push_back(std::abs(est - ref) / ref);
            }
        }
    return out;
}
const char* kBandNames[3] = {"<30", "30-60", "60-88"};

LtcTables isoOnly(const IsoTable& t) {
    LtcTables x;
    x.ggxInv = t.inv;
    x.ggxMagFres = t.magFres;
    return x;
}

}  // namespace

// Golden hash: the compiled-in tables are the committed generated source, intact.
TEST(LtcTables, GoldenHash) {
    const LtcTables& t = builtinTables();
    ASSERT_EQ(t.ggxInv.size(), size_t(64 * 64 * 4));
    ASSERT_EQ(t.ggxMagFres.size(), size_t(64 * 64 * 2));
    ASSERT_EQ(t.sphere.size(), size_t(64 * 64));
    ASSERT_EQ(t.anisoInv.size(), size_t(t.anisoSize) * t.anisoSize * t.anisoSize * t.anisoPhiSize * 9);
    EXPECT_EQ(t.hash(), std::string(generated::kHash))
        << "core/ltc/ltc_tables_data.cpp was edited by hand or corrupted; regenerate it with `" << kRegenerate << "`";
}

// Drift: re-running the fit today gives exactly the committed tables (same build; libm differences across platforms
// would show here too — then regenerate and commit on the reference platform).
TEST(LtcTables, DriftFullRefitMatchesCommitted) {
    int threads = int(std::max(2u, std::thread::hardware_concurrency()));
    LtcTables t = fitAllTables(threads);
    EXPECT_EQ(t.hash(), builtinTables().hash())
        << "the LTC fit no longer reproduces the committed tables (fit code or its dependencies changed): regenerate "
           "with `"
        << kRegenerate << "` and commit core/ltc/ltc_tables_data.cpp (check: build/bin/ltc-fit --check)";
}

// T9: a sub-range of the Nelder-Mead table (rows a = 59..63, warm starts included), fitted twice with 1 thread and
// once with 2, is bit-identical, and equal to the committed rows.
TEST(LtcTables, T9DeterministicAcrossThreads) {
    IsoFitOptions o;
    o.aMin = 59;
    o.threads = 1;
    IsoTable a = fitGgxIsoNelderMead(o), b = fitGgxIsoNelderMead(o);
    o.threads = 2;
    IsoTable c = fitGgxIsoNelderMead(o);
    EXPECT_TRUE(a.inv == b.inv && a.magFres == b.magFres);
    EXPECT_TRUE(a.inv == c.inv && a.magFres == c.magFres);
    const LtcTables& t = builtinTables();
    int diff = 0;
    for (int ti = 0; ti < 64; ++ti)
        for (int ai = 59; ai < 64; ++ai) {
            size_t cell = size_t(ti) * 64 + ai;
            for (int k = 0; k < 4; ++k) diff += a.inv[cell * 4 + k] != t.ggxInv[cell * 4 + k];
            for (int k = 0; k < 2; ++k) diff += a.magFres[cell * 2 + k] != t.ggxMagFres[cell * 2 + k];
        }
    EXPECT_EQ(diff, 0) << "committed rows differ from a re-fit: regenerate with `" << kRegenerate << "`";
}

// T1: the normalised LTC of every 9th cell with roughness >= 0.14 integrates to 1 within 5e-3 (MIS, 4e5 samples:
// half from the LTC, half uniform on the sphere).
TEST(LtcTables, T1Normalisation) {
    const LtcTables& t = builtinTables();
    Rng rng(7);
    const int half = 200000;
    double worst = 0.0;
    int cells = 0;
    for (int c = 0; c < 64 * 64; c += 9) {
        int a = c % 64, ti = c / 64;
        if (a / 63.0 < 0.14) continue;
        Ltc l = nodeLtc(t, a, ti);
        DMat3 inv(l.invM), M = glm::inverse(inv);
        const double pu = 1.0 / (4 * kPiD);
        double sum = 0.0;
        for (int k = 0; k < half; ++k) {
            DVec3 w1 = ltcSample(M, rng(), rng());
            double z = 2 * rng() - 1, ph = 2 * kPiD * rng(), s = std::sqrt(std::max(0.0, 1 - z * z));
            DVec3 w2(s * std::cos(ph), s * std::sin(ph), z);
            for (const DVec3& w : {w1, w2}) {
                double d = ltcDensity(inv, w);
                sum += d / (d + pu);
            }
        }
        double integral = sum / half;
        worst = std::max(worst, std::abs(integral - 1.0));
        EXPECT_NEAR(integral, 1.0, 5e-3) << "cell a=" << a << " t=" << ti;
        ++cells;
    }
    EXPECT_GT(cells, 350);
    std::printf("T1: %d cells, worst |∫D − 1| = %.2e\n", cells, worst);
}

// T4: mag matches a brute-force albedo (stratified uniform hemisphere, 2e6 samples) within 1e-2 at the §2 anchors, and
// fres(t = 0) < 1e-3.
TEST(LtcTables, T4MagnitudeAnchors) {
    const LtcTables& t = builtinTables();
    struct Anchor {
        double alpha, theta, mag;
    } anchors[] = {{0.1, 0, 0.99}, {0.5, 0, 0.688}, {1.0, 0, 0.307}, {1.0, 1.5, 0.808}};
    for (const Anchor& an : anchors) {
        DVec3 v = viewAt(std::cos(an.theta));
        const int n = 1414;
        double sum = 0.0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                double z = (i + 0.5) / n, ph = 2 * kPiD * (j + 0.5) / n, s = std::sqrt(1 - z * z);
                sum += ggxFcos(v, DVec3(s * std::cos(ph), s * std::sin(ph), z), an.alpha);
            }
        double brute = sum * 2 * kPiD / (double(n) * n);
        Ltc l = ggxIsotropic(t, float(an.alpha), Vec3(v));
        EXPECT_NEAR(brute, an.mag, 1e-2) << "brute force vs the spec anchor, alpha=" << an.alpha;
        EXPECT_NEAR(l.magnitude, brute, 1e-2) << "table vs brute force, alpha=" << an.alpha << " theta=" << an.theta;
        std::printf("T4: alpha %.1f theta %.1f: table %.4f brute %.4f (spec %.3f)\n", an.alpha, an.theta, l.magnitude,
                    brute, an.mag);
    }
    for (int a = 0; a < 64; ++a) EXPECT_LT(t.ggxMagFres[size_t(a) * 2 + 1], 1e-3f) << "fres(t=0), a=" << a;
}

// T8: scale(z = 1, len) = 1, scale(z = −1, len > 0) = 0, monotonic in z; and Snyder's cap formula against a Monte
// Carlo estimate of the horizon-clipped cap's form factor.
TEST(LtcTables, T8SphereTable) {
    const LtcTables& t = builtinTables();
    for (int j = 0; j < 64; ++j) {
        float len = j / 63.f;
        EXPECT_NEAR(sphereScale(t, 1.f, len), 1.f, 1e-5f) << "len=" << len;
        if (j > 0) EXPECT_NEAR(sphereScale(t, -1.f, len), 0.f, 1e-6f) << "len=" << len;
        for (int i = 1; i < 64; ++i)
            EXPECT_GE(t.sphere[size_t(j) * 64 + i], t.sphere[size_t(j) * 64 + i - 1]) << "i=" << i << " j=" << j;
    }
    Rng rng(3);
    for (double omega : {0.3, 1.2, 1.6, 2.2})
        for (double sigma : {0.2, 0.6, 1.0}) {
            DVec3 axis(std::sin(omega), 0, std::cos(omega));
            const int n = 200000;
            double cs = std::cos(sigma), sum = 0.0;
            for (int k = 0; k < n; ++k) {  // uniform on the cap, weight max(z, 0)/π · cap solid angle
                double z = 1 - rng() * (1 - cs), ph = 2 * kPiD * rng(), s = std::sqrt(1 - z * z);
                DVec3 x = glm::normalize(glm::cross(axis, DVec3(0, 1, 0))), y = glm::cross(axis, x);
                DVec3 w = z * axis + s * std::cos(ph) * x + s * std::sin(ph) * y;
                sum += std::max(w.z, 0.0);
            }
            double mc = sum / n * 2 * kPiD * (1 - cs) / kPiD;
            EXPECT_NEAR(capFormFactorSnyder(omega, sigma), mc, 5e-3) << "omega=" << omega << " sigma=" << sigma;
            EXPECT_NEAR(capFormFactorSnyder(omega, sigma), capFormFactor(omega, sigma), 1e-12);  // ltc.cpp's copy
        }
}

// T10: L1/mag at the spec anchors within ±1.5 points.
TEST(LtcTables, T10FitQualityAnchors) {
    const LtcTables& t = builtinTables();
    struct Anchor {
        double r;
        int ti;
        double l1;
    } anchors[] = {{0.25, 0, 0.01}, {0.51, 0, 0.035}, {0.51, 32, 0.125}, {0.51, 60, 0.60}, {0.51, 63, 0.73}, {1.0, 0, 0.03}};
    for (const Anchor& an : anchors) {
        double alpha = an.r * an.r;
        DVec3 v = viewAt(isoCosTheta(an.ti));
        Ltc l = ggxIsotropic(t, float(alpha), Vec3(v));
        double e = l1OverMag(l, alpha, v, 200000, 99);
        EXPECT_NEAR(e, an.l1, 0.015) << "roughness " << an.r << " t=" << an.ti;
        std::printf("T10: roughness %.2f t=%d: L1/mag %.2f%% (spec %.1f%%)\n", an.r, an.ti, 100 * e, 100 * an.l1);
    }
}

// T11: the t-EM variant of the table (§5.2) against the Nelder-Mead one: the T6 band errors within 2x of each other.
TEST(LtcTables, T11StudentTVersusNelderMead) {
    const LtcTables& nm = builtinTables();
    auto t0 = std::chrono::steady_clock::now();
    LtcTables em = isoOnly(fitGgxIsoStudentT(16, 2));
    std::printf("T11: t-EM table fitted in %.3f s (2 threads)\n",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    std::vector<Lookup> lookups = {[&](float a, float, const Vec3& v) { return ggxIsotropic(nm, a, v); },
                                   [&](float a, float, const Vec3& v) { return ggxIsotropic(em, a, v); }};
    std::vector<BandErrors> e = bandErrors(lookups, 24, 60000);
    for (int b = 0; b < 3; ++b) {
        double x = e[0].mean(b), y = e[1].mean(b);
        std::printf("T11: band %s deg: mean |err|/mag NM %.4f, t-EM %.4f; median rel err (>= 10%% of mag) NM %.3f, "
                    "t-EM %.3f\n",
                    kBandNames[b], x, y, e[0].medianRel(b), e[1].medianRel(b));
        EXPECT_LE(std::max(x, y), 2.0 * std::min(x, y)) << "band " << kBandNames[b];
    }
}

// Mean |a − b| of two lookups' normalised quad estimates (LTC·mag/mag) in band b.
double meanDiff(const BandErrors& x, const BandErrors& y, int b) {
    double s = 0;
    for (size_t i = 0; i < x.est[b].size(); ++i) s += std::abs(x.est[b][i] - y.est[b][i]);
    return s / std::max<size_t>(1, x.est[b].size());
}

// The anisotropic t-EM table: at αx = αy against the isotropic Nelder-Mead table and Monte Carlo, and at αy = 0.4·αx
// against Monte Carlo (views at random azimuths, so the mirror symmetries are used). Limits: the T6 mean |err|/mag
// bounds of ltc-filtering.md §6 (0.005 / 0.015 / 0.03).
TEST(LtcTables, AnisotropicTable) {
    const LtcTables& t = builtinTables();
    std::vector<Lookup> lookups = {[&](float ax, float, const Vec3& v) { return ggxIsotropic(t, ax, v); },
                                   [&](float ax, float ay, const Vec3& v) { return ggxAnisotropic(t, ax, ay, v); }};
    const double limit[3] = {0.005, 0.015, 0.03};
    std::vector<BandErrors> e = bandErrors(lookups, 24, 40000);
    for (int b = 0; b < 3; ++b) {
        std::printf("aniso ax=ay: band %s deg: mean |err|/mag iso-NM %.4f, aniso %.4f; mean |aniso − iso|/mag %.4f\n",
                    kBandNames[b], e[0].mean(b), e[1].mean(b), meanDiff(e[0], e[1], b));
        EXPECT_LE(e[1].mean(b), limit[b]) << "band " << kBandNames[b];
    }
    std::vector<BandErrors> f = bandErrors({lookups[1]}, 24, 40000, 0.4, 777);
    for (int b = 0; b < 3; ++b) {
        std::printf("aniso ay=0.4ax: band %s deg: mean |err|/mag %.4f, median rel err (>= 10%% of mag) %.3f\n",
                    kBandNames[b], f[0].mean(b), f[0].medianRel(b));
        EXPECT_LE(f[0].mean(b), limit[b]) << "band " << kBandNames[b];
    }
    // Mirror symmetry of the lookup: wo -> (−x, y) and (x, −y) mirror the lobe; det invM stays positive.
    Vec3 wo = glm::normalize(Vec3(0.5f, 0.3f, 0.6f));
    Ltc base = ggxAnisotropic(t, 0.2f, 0.5f, wo);
    for (Vec3 s : {Vec3(-1, 1, 1), Vec3(1, -1, 1), Vec3(-1, -1, 1)}) {
        Ltc m = ggxAnisotropic(t, 0.2f, 0.5f, wo * s);
        EXPECT_GT(glm::determinant(m.invM), 0.f);
        EXPECT_FLOAT_EQ(m.magnitude, base.magnitude);
        for (Vec3 w : {Vec3(0.1f, 0.2f, 0.9f), Vec3(-0.6f, -0.3f, 0.5f), Vec3(0.4f, -0.5f, 0.3f)}) {
            w = glm::normalize(w);
            double a = ltcDensity(DMat3(base.invM), DVec3(w)), b = ltcDensity(DMat3(m.invM), DVec3(w * s));
            EXPECT_NEAR(a, b, 1e-4 * std::max(1.0, a));
        }
    }
}

// Grid-size study of the anisotropic table (docs/ltc-tables.md); run with --gtest_also_run_disabled_tests.
TEST(LtcTables, DISABLED_AnisotropicGridStudy) {
    for (int n : {6, 8, 10, 12, 16}) {
        LtcTables t;
        auto t0 = std::chrono::steady_clock::now();
        fitGgxAnisotropic(n, 8, kShippedAnisoSamples, 2, t);
        double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        Lookup l = [&](float ax, float ay, const Vec3& v) { return ggxAnisotropic(t, ax, ay, v); };
        std::vector<BandErrors> e = bandErrors({l}, 24, 40000), f = bandErrors({l}, 24, 40000, 0.4, 777);
        std::printf("grid %d^3x8 (%zu floats, %.2f s): ax=ay %.4f %.4f %.4f; ay=0.4ax %.4f %.4f %.4f\n", n,
                    t.anisoInv.size() + t.anisoMagFres.size(), sec, e[0].mean(0), e[0].mean(1), e[0].mean(2),
                    f[0].mean(0), f[0].mean(1), f[0].mean(2));
    }
}

// ggxIsotropic folds the view-frame rotation into invM: the lobe for a view at azimuth φ is the φ = 0 lobe rotated
// by φ about the normal; at a node the GL-style bilinear returns the node's entries; wo along the normal uses T1 = x.
TEST(LtcTables, IsotropicLookupFrameAndNodes) {
    const LtcTables& t = builtinTables();
    const float alpha = 0.3f;
    Vec3 wo0 = glm::normalize(Vec3(0.7f, 0.f, 0.5f));
    Ltc l0 = ggxIsotropic(t, alpha, wo0);
    for (float ph : {0.4f, 1.9f, -2.5f}) {
        float c = std::cos(ph), s = std::sin(ph);
        auto rot = [&](const Vec3& w) { return Vec3(c * w.x - s * w.y, s * w.x + c * w.y, w.z); };
        Ltc l = ggxIsotropic(t, alpha, rot(wo0));
        EXPECT_FLOAT_EQ(l.magnitude, l0.magnitude);
        for (Vec3 w : {Vec3(-0.5f, 0.1f, 0.8f), Vec3(0.2f, -0.4f, 0.6f), Vec3(-0.9f, 0.05f, 0.3f)}) {
            w = glm::normalize(w);
            double a = ltcDensity(DMat3(l0.invM), DVec3(w)), b = ltcDensity(DMat3(l.invM), DVec3(rot(w)));
            EXPECT_NEAR(a, b, 1e-4 * std::max(1.0, a)) << "phi=" << ph;
        }
    }
    // (Not t = 63: that node is fitted at θ = 1.57 but sits at coordinate √(1 − 0) = 1, as in ltc_code, so a view at
    // exactly θ = 1.57 reads 2.5% of the way from t = 62.)
    for (int a : {5, 32, 63})
        for (int ti : {0, 20, 62}) {
            Ltc l = nodeLtc(t, a, ti);
            const float* e = &t.ggxInv[(size_t(ti) * 64 + a) * 4];
            EXPECT_NEAR(l.invM[0][0], e[0], 1e-4f * (1 + std::abs(e[0])));
            EXPECT_NEAR(l.invM[0][2], e[1], 1e-4f * (1 + std::abs(e[1])));
            EXPECT_NEAR(l.invM[2][0], e[2], 1e-4f * (1 + std::abs(e[2])));
            EXPECT_NEAR(l.invM[2][2], e[3], 1e-4f * (1 + std::abs(e[3])));
            EXPECT_NEAR(l.magnitude, t.ggxMagFres[(size_t(ti) * 64 + a) * 2], 1e-4f);
        }
    Ltc n = ggxIsotropic(t, alpha, Vec3(0, 0, 1));
    EXPECT_TRUE(std::isfinite(n.invM[0][0]) && n.invM[1][1] == 1.f);
}

// The tabulated clip-free horizon (len·sphereScale) against the exact cap formula: float-exact where the equivalent cap
// is fully above the horizon (the table holds z there and bilinear interpolation of a linear function is exact up to
// rounding), and within the bilinear error elsewhere (reported for docs/ltc-tables.md).
TEST(LtcTables, SphereTableAgainstCapFormula) {
    const LtcTables& t = builtinTables();
    Rng rng(5);
    double worstVisible = 0.0, worst = 0.0, sum = 0.0, worstZ = 0.0, worstLen = 0.0;
    int n = 0;
    for (int k = 0; k < 200000; ++k) {
        double z = 2 * rng() - 1, len = rng();
        double sigma = std::asin(std::sqrt(len)), omega = std::acos(z);
        double exact = capFormFactor(omega, sigma), tab = len * sphereScale(t, float(z), float(len));
        double e = std::abs(tab - exact);
        // Fully visible for this cap and for the caps of the 4 surrounding nodes: the bilinear stencil is exact.
        double x = (z + 1) / 2 * 63, y = len * 63;
        double zLo = 2 * std::floor(x) / 63 - 1, lenHi = std::min(1.0, (std::floor(y) + 1) / 63);
        if (std::acos(std::max(-1.0, zLo)) <= 0.5 * kPiD - std::asin(std::sqrt(lenHi))) {
            worstVisible = std::max(worstVisible, e);
        } else {
            if (e > worst) worst = e, worstZ = z, worstLen = len;
            sum += e;
            ++n;
        }
    }
    EXPECT_LT(worstVisible, 1e-6);
    std::printf("sphere table: fully visible max |len·scale − F_cap| %.2e; partly clipped: max %.2e (z %.3f, len %.3f), "
                "mean %.2e\n",
                worstVisible, worst, worstZ, worstLen, sum / std::max(1, n));
}
