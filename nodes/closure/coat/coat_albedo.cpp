// The coat albedo table of coat_albedo.h: built by quadrature on first use, looked up trilinearly, and repacked as
// the GPU resource coat.glsl reads.
#include "nodes/closure/coat/coat_albedo.h"

#include "core/render/lobes/ggx.h"

#include <tbb/parallel_for.h>

#include <mutex>

namespace specula::coat {

namespace {
constexpr double kPiD = 3.14159265358979323846;
}

void albedoQuadrature(float mu, float alpha, const float* iors, int count, int n, float* out) {
    mu = std::clamp(mu, 1e-4f, 1.f);
    alpha = std::max(alpha, ggx::kMinAlpha);
    const Vec3 wo(std::sqrt(std::max(0.f, 1.f - mu * mu)), 0.f, mu);
    const float g1o = ggx::g1(wo, alpha, alpha);
    std::vector<double> sums(size_t(count), 0.0);
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            // The sampler's disk point has radius √u.x and height √(1 − u.x) (Heitz 2018, Listing 1): both have
            // square-root singularities at the ends of u.x. With u.x = sin²θ (du.x = sin 2θ dθ) radius sin θ and
            // height cos θ are smooth, so midpoints in θ converge fast (measured: 32² is within 1e-4 of 256²
            // where the plain u.x midpoints were 1e-3 off).
            const double th = (a + 0.5) / n * (0.5 * kPiD);
            const Vec2 u(float(sqr(std::sin(th))), (b + 0.5f) / n);
            const double jac = std::sin(2.0 * th) * (0.5 * kPiD);
            const Vec3 h = ggx::sampleVisibleNormal(wo, u, alpha, alpha);
            const Vec3 wi = ggx::reflect(wo, h);
            if (wi.z <= 0.f) continue;  // reflected below the surface: the lobe is zero there
            // VNDF sampling: f·cos / pdf = F D G2 /(4 μo) · 4 (wo·h) μo / (G1 (wo·h) D) = F G2 / G1 (Heitz 2018, §3).
            // Only F depends on the IOR: the half vector and the masking are shared by every IOR of the call.
            const float g2 = ggx::g2(wo, wi, alpha, alpha), woh = glm::dot(wo, h);
            for (int k = 0; k < count; ++k) sums[size_t(k)] += jac * fresnelDielectric(woh, iors[k]) * g2 / g1o;
        }
    for (int k = 0; k < count; ++k) out[k] = float(sums[size_t(k)] / (double(n) * n));
}

float albedoQuadrature(float mu, float alpha, float ior, int n) {
    float e = 0.f;
    albedoQuadrature(mu, alpha, &ior, 1, n, &e);
    return e;
}

namespace {
float iorOfF0(float f0) {
    const float s = std::sqrt(std::clamp(f0, 0.f, 0.999f));
    return (1.f + s) / (1.f - s);
}
float f0OfIor(float ior) {
    const float r = (ior - 1.f) / (ior + 1.f);
    return r * r;
}
// Position of v on an axis of n nodes over [0, 1]: the lower node and the weight of the upper one.
void axis(float v, int n, int& i0, float& t) {
    const float x = std::clamp(v, 0.f, 1.f) * float(n - 1);
    i0 = std::min(int(x), n - 2);
    t = x - float(i0);
}
}  // namespace

const std::vector<float>& albedoTable() {
    static std::vector<float> table;
    static std::once_flag once;
    std::call_once(once, [] {
        table.assign(size_t(kMu) * kRough * kF0, 0.f);
        float iors[kF0];
        for (int k = 0; k < kF0; ++k) iors[k] = iorOfF0(float(k) / (kF0 - 1) * kMaxF0);
        // One quadrature per (μo, r) node serves all kF0 IORs: 16× fewer visible-normal samples, the same sums.
        tbb::parallel_for(0, kRough * kMu, [&iors](int node) {
            const int j = node / kMu, i = node % kMu;
            const float r = float(j) / (kRough - 1);
            float e[kF0];
            albedoQuadrature(float(i) / (kMu - 1), r * r, iors, kF0, kQuad, e);
            for (int k = 0; k < kF0; ++k) table[(size_t(k) * kRough + j) * kMu + i] = e[k];
        });
    });
    return table;
}

float albedo(float mu, float roughness, float ior) {
    if (!(mu > 0.f)) return 0.f;
    const std::vector<float>& t = albedoTable();
    int i, j, k;
    float ti, tj, tk;
    axis(mu, kMu, i, ti);
    axis(roughness, kRough, j, tj);
    axis(f0OfIor(std::clamp(ior, kMinIor, kMaxIor)) / kMaxF0, kF0, k, tk);
    auto at = [&](int a, int b, int c) { return t[(size_t(c) * kRough + b) * kMu + a]; };
    auto bil = [&](int c) {
        const float e0 = at(i, j, c) + ti * (at(i + 1, j, c) - at(i, j, c));
        const float e1 = at(i, j + 1, c) + ti * (at(i + 1, j + 1, c) - at(i, j + 1, c));
        return e0 + tj * (e1 - e0);
    };
    const float a = bil(k), b = bil(k + 1);
    return a + tk * (b - a);
}

namespace {
graph::ResourceImage albedoImage(const void*) {
    const std::vector<float>& t = albedoTable();
    graph::ResourceImage r;
    graph::ResourceImage::Level lv;
    lv.width = kMu;
    lv.height = kRough * kF0;
    lv.rgba.assign(size_t(lv.width) * lv.height * 4, 0.f);
    for (size_t c = 0; c < t.size(); ++c) lv.rgba[c * 4] = t[c];  // rows (k·kRough + j), texels i: the table's order
    r.levels.push_back(std::move(lv));
    r.minFilter = r.magFilter = "nearest";
    r.wrapS = r.wrapT = "clamp_to_edge";
    return r;
}
}  // namespace

graph::ResourceSpec albedoResource() {
    return {"coat_albedo", "sampler2D", graph::ResourceSpec::Kind::BuiltinTable,
            "directional albedo of the dielectric GGX coat E(mu_o, roughness, F0(ior)): 32 x (32 x 16) RGBA32F, texel "
            "(mu index, F0 index * 32 + roughness index) = (E, 0, 0, 0); nearest, clamp_to_edge, interpolated in the "
            "shader with texelFetch",
            &albedoImage};
}

}  // namespace specula::coat
