// MIS Monte Carlo references and T6 statistics for LTC quad-light accuracy (ltc-filtering.md §6 T6), shared by the
// tests and tools/ltc-report so every number on docs/validation/ltc.md is computed one way.
#include "core/ltc/ltc_reference.h"

#include "core/render/sampler.h"

#include <algorithm>
#include <cmath>

namespace specula::ltc {

double nextUniform(uint64_t& s) { return double(mix64(++s) >> 11) * 0x1.0p-53; }

std::array<Vec3, 4> RefQuad::polygon() const {
    std::array<Vec3, 4> q = {c - a - b, c + a - b, c + a + b, c - a + b};
    if (glm::dot(glm::cross(q[1] - q[0], q[2] - q[0]), c) < 0.f) std::swap(q[1], q[3]);
    return q;
}

namespace {
bool hitQuad(const Vec3& w, const std::array<Vec3, 4>& v, float& t) {
    Vec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
    float den = glm::dot(w, n);
    if (den == 0.f) return false;
    t = glm::dot(v[0], n) / den;
    if (t <= 0.f) return false;
    Vec3 p = w * t;
    float s0 = 0.f;
    for (int i = 0; i < 4; ++i) {
        float s = glm::dot(glm::cross(v[(i + 1) % 4] - v[i], p - v[i]), n);
        if (i == 0) s0 = s;
        else if (s * s0 < 0.f) return false;
    }
    return true;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}
}  // namespace

double monteCarloPolygonIntegral(const BsdfLobe& lobe, const Vec3& wo, const RefQuad& quad, int n, uint64_t seed) {
    const auto v = quad.polygon();
    const Vec3 e1 = 2.f * quad.a, e2 = 2.f * quad.b, corner = quad.c - quad.a - quad.b;
    Vec3 nrm = glm::cross(e1, e2);
    const float area = glm::length(nrm);
    nrm /= area;
    uint64_t s = seed * 0x9E3779B97F4A7C15ULL;
    double sum = 0;
    for (int i = 0; i < n; ++i) {
        // Light strategy: a uniform point of the quad, pdf_ω = d²/(A |cos θ_l|).
        float u0 = float(nextUniform(s)), u1 = float(nextUniform(s));
        Vec3 p = corner + e1 * u0 + e2 * u1;
        float d2 = glm::dot(p, p);
        Vec3 wi = p / std::sqrt(d2);
        float pl = d2 / (area * std::abs(glm::dot(wi, nrm)));
        LobeValue lv = lobe.evalPdf(LobeQuery{wo, wi});
        if (wi.z > 0.f) sum += lv.f.y / (pl + lv.pdf);
        // Lobe strategy.
        Vec3 ws;
        float u2 = float(nextUniform(s)), u3 = float(nextUniform(s));
        if (lobe.sample(wo, Vec2(u2, u3), ws)) {
            float t;
            if (hitQuad(ws, v, t)) {
                LobeValue sv = lobe.evalPdf(LobeQuery{wo, ws});
                float plb = t * t / (area * std::abs(glm::dot(ws, nrm)));
                if (sv.pdf > 0.f) sum += sv.f.y / (plb + sv.pdf);
            }
        }
    }
    return sum / n;
}

RefQuad randomRefQuad(uint64_t& s) {
    for (;;) {
        double el = 0.0872664626 + 1.3962634016 * nextUniform(s), az = 6.283185307179586 * nextUniform(s);
        double dist = 0.6 + 1.6 * nextUniform(s);
        Vec3 c(float(dist * std::cos(el) * std::cos(az)), float(dist * std::cos(el) * std::sin(az)), float(dist * std::sin(el)));
        Vec3 jitter(float(nextUniform(s) - 0.5), float(nextUniform(s) - 0.5), float(nextUniform(s) - 0.5));
        Vec3 axis = glm::normalize(-c + jitter);
        Vec3 t = glm::normalize(glm::cross(axis, std::abs(axis.z) < 0.9f ? Vec3(0, 0, 1) : Vec3(1, 0, 0)));
        Vec3 b = glm::cross(axis, t);
        float ha = float(0.15 + 1.0 * nextUniform(s)), hb = float(0.15 + 1.0 * nextUniform(s));
        RefQuad q{c, t * ha, b * hb};
        auto p = q.polygon();
        if (std::all_of(p.begin(), p.end(), [](const Vec3& x) { return x.z > 0.02f; })) return q;
    }
}

double BandErrors::meanAbs(int band) const {
    const auto& v = absOverAlbedo[band];
    double m = 0;
    for (double x : v) m += x;
    return v.empty() ? 0.0 : m / double(v.size());
}
double BandErrors::medianRelative(int band) const { return median(relative[band]); }

BandErrors measureQuadErrors(const LobeFactory& make, int perBand, int mcSamples, uint64_t seed, uint8_t horizon) {
    BandErrors e;
    uint64_t s = seed;
    for (int band = 0; band < 3; ++band) {
        const double lo = band == 0 ? 0.0 : band == 1 ? 30.0 : 60.0, hi = band == 0 ? 30.0 : band == 1 ? 60.0 : 88.0;
        for (int k = 0; k < perBand; ++k) {
            double th = (lo + (hi - lo) * nextUniform(s)) * 0.017453292519943295, ph = 6.283185307179586 * nextUniform(s);
            Vec3 wo(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th)));
            LobeUnderTest c = make(s, wo);
            RefQuad q = randomRefQuad(s);
            auto p = q.polygon();
            Color3 ltc(0.f);
            LobeQuery lq{wo, wo};
            lq.polygonHorizon = horizon;
            if (!c.lobe->integratePolygon(lq, p.data(), 4, ltc)) ltc = Color3(std::nanf(""));
            double mc = monteCarloPolygonIntegral(*c.lobe, wo, q, mcSamples, seed * 1000 + uint64_t(band) * 100 + uint64_t(k));
            double err = std::abs(double(ltc.y) - mc);
            e.absOverAlbedo[band].push_back(err / c.albedo);
            if (mc >= 0.1 * c.albedo) e.relative[band].push_back(err / mc);
        }
    }
    return e;
}

}  // namespace specula::ltc
