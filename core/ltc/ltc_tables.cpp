// The committed LTC tables (built once from core/ltc/ltc_tables_data.cpp) and their run-time lookups: GL-style
// bilinear isotropic GGX + mag/fres and sphere tables (ltc-filtering.md §2 "Packing", §3), quadrilinear anisotropic GGX.
#include "core/ltc/ltc_tables.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

namespace specula::ltc {

namespace {

void fnv(uint64_t& h, const void* data, size_t bytes) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) {
        h ^= p[i];
        h *= 1099511628211ull;  // FNV-1a 64 prime
    }
}
void fnvVector(uint64_t& h, const std::vector<float>& v) {
    uint64_t n = v.size();
    fnv(h, &n, sizeof n);
    if (!v.empty()) fnv(h, v.data(), v.size() * sizeof(float));
}

// ltc_code's LUT_SCALE/LUT_BIAS: node coordinate c in [0, 1] -> texture coordinate of an n-texel axis.
float lutCoord(float c, int n) { return c * float(n - 1) / float(n) + 0.5f / float(n); }

}  // namespace

std::string LtcTables::hash() const {
    uint64_t h = 14695981039346656037ull;  // FNV-1a 64 offset basis
    fnvVector(h, ggxInv);
    fnvVector(h, ggxMagFres);
    fnvVector(h, sphere);
    fnvVector(h, anisoInv);
    fnvVector(h, anisoMagFres);
    int32_t dims[2] = {anisoSize, anisoPhiSize};
    fnv(h, dims, sizeof dims);
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

const LtcTables& builtinTables() {
    // A function-local static: built once, thread-safe (C++11 magic statics).
    static const LtcTables tables = [] {
        using namespace generated;
        LtcTables t;
        t.ggxInv.assign(kGgxInv, kGgxInv + kGgxInvCount);
        t.ggxMagFres.assign(kGgxMagFres, kGgxMagFres + kGgxMagFresCount);
        t.sphere.assign(kSphere, kSphere + kSphereCount);
        t.anisoSize = kAnisoSize;
        t.anisoPhiSize = kAnisoPhiSize;
        t.anisoInv.assign(kAnisoInv, kAnisoInv + kAnisoInvCount);
        t.anisoMagFres.assign(kAnisoMagFres, kAnisoMagFres + kAnisoMagFresCount);
        return t;
    }();
    return tables;
}

void sampleBilinear(const float* table, int n, int channels, float u, float v, float* out) {
    // GL_LINEAR with CLAMP_TO_EDGE: texel i has its centre at (i + 0.5)/n; weights from the texel-space position.
    float x = u * float(n) - 0.5f, y = v * float(n) - 0.5f;
    float fx0 = std::floor(x), fy0 = std::floor(y);
    float fx = x - fx0, fy = y - fy0;
    int x0 = int(fx0), y0 = int(fy0);
    int xa = std::clamp(x0, 0, n - 1), xb = std::clamp(x0 + 1, 0, n - 1);
    int ya = std::clamp(y0, 0, n - 1), yb = std::clamp(y0 + 1, 0, n - 1);
    const float* p00 = table + (size_t(ya) * n + xa) * channels;
    const float* p10 = table + (size_t(ya) * n + xb) * channels;
    const float* p01 = table + (size_t(yb) * n + xa) * channels;
    const float* p11 = table + (size_t(yb) * n + xb) * channels;
    for (int c = 0; c < channels; ++c) {
        float a = p00[c] + (p10[c] - p00[c]) * fx;
        float b = p01[c] + (p11[c] - p01[c]) * fx;
        out[c] = a + (b - a) * fy;
    }
}

Ltc ggxIsotropic(const LtcTables& t, float alpha, const Vec3& wo) {
    const int n = LtcTables::kIsoSize;
    float cosTheta = std::clamp(wo.z, 0.f, 1.f);
    // Table coordinates (§2 "Grid"): r = √α (α = r² on the nodes), √(1 − cos θ).
    float u = lutCoord(std::sqrt(std::clamp(alpha, 0.f, 1.f)), n);
    float v = lutCoord(std::sqrt(1.f - cosTheta), n);
    float m[4], mf[2];
    sampleBilinear(t.ggxInv.data(), n, 4, u, v, m);
    sampleBilinear(t.ggxMagFres.data(), n, 2, u, v, mf);
    // inv(M) of the view-aligned frame: rows (x, 0, z), (0, 1, 0), (y, 0, w) (glm [col][row]).
    Mat3 inv(0.f);
    inv[0][0] = m[0];
    inv[0][2] = m[1];
    inv[1][1] = 1.f;
    inv[2][0] = m[2];
    inv[2][2] = m[3];
    // Fold the lobe-frame -> view-frame rotation (rows T1, T2, N; §3 step 1) into invM. wo along the normal: any T1.
    Vec3 t1(wo.x, wo.y, 0.f);
    float l = std::sqrt(t1.x * t1.x + t1.y * t1.y);
    t1 = l > 1e-7f ? t1 / l : Vec3(1.f, 0.f, 0.f);
    Vec3 t2(-t1.y, t1.x, 0.f);  // N × T1 with N = z
    Mat3 toView = glm::transpose(Mat3(t1, t2, Vec3(0.f, 0.f, 1.f)));
    Ltc out;
    out.invM = inv * toView;
    out.magnitude = mf[0];
    out.fresnel = mf[1];
    return out;
}

Ltc ggxAnisotropic(const LtcTables& t, float alphaX, float alphaY, const Vec3& wo) {
    const int n = t.anisoSize, np = t.anisoPhiSize;
    Ltc out;
    if (n < 2 || np < 1) return out;
    // Mirror wo into the first quadrant (the lobe is symmetric under x -> −x and y -> −y).
    float sx = wo.x < 0.f ? -1.f : 1.f, sy = wo.y < 0.f ? -1.f : 1.f;
    float cosTheta = std::clamp(wo.z, 0.f, 1.f);
    float phi = std::atan2(std::abs(wo.y), std::abs(wo.x));
    // Continuous node coordinates (inverse of ltc_fit.h's anisoAlpha/anisoCosTheta/anisoPhi).
    float c[4] = {std::sqrt(std::clamp(alphaX, 0.f, 1.f)) * float(n - 1),
                  std::sqrt(std::clamp(alphaY, 0.f, 1.f)) * float(n - 1), std::sqrt(1.f - cosTheta) * float(n - 1),
                  np > 1 ? phi / (0.5f * kPi) * float(np - 1) : 0.f};
    int dims[4] = {n, n, n, np};
    int i0[4];
    float f[4];
    for (int d = 0; d < 4; ++d) {
        float x = std::clamp(c[d], 0.f, float(dims[d] - 1));
        i0[d] = std::min(int(x), std::max(dims[d] - 2, 0));
        f[d] = dims[d] > 1 ? x - float(i0[d]) : 0.f;
    }
    float acc[11] = {};
    for (int corner = 0; corner < 16; ++corner) {
        float w = 1.f;
        int idx[4];
        for (int d = 0; d < 4; ++d) {
            int b = (corner >> d) & 1;
            idx[d] = std::min(i0[d] + b, dims[d] - 1);
            w *= b ? f[d] : 1.f - f[d];
        }
        if (w == 0.f) continue;
        size_t cell = ((size_t(idx[3]) * n + idx[2]) * n + idx[1]) * n + idx[0];
        for (int k = 0; k < 9; ++k) acc[k] += w * t.anisoInv[cell * 9 + k];
        acc[9] += w * t.anisoMagFres[cell * 2 + 0];
        acc[10] += w * t.anisoMagFres[cell * 2 + 1];
    }
    Mat3 inv;
    for (int col = 0; col < 3; ++col)
        for (int row = 0; row < 3; ++row) inv[col][row] = acc[col * 3 + row];
    // Mirror back: D(w) = D'(S w) with S = diag(sx, sy, 1); a cosine-space y flip when S flips orientation keeps
    // det invM > 0 (the clamped cosine is symmetric in y), so polygon windings stay valid.
    Mat3 S(1.f), F(1.f);
    S[0][0] = sx;
    S[1][1] = sy;
    F[1][1] = sx * sy;
    out.invM = F * inv * S;
    out.magnitude = acc[9];
    out.fresnel = acc[10];
    return out;
}

float sphereScale(const LtcTables& t, float z, float len) {
    const int n = LtcTables::kIsoSize;
    float out;
    sampleBilinear(t.sphere.data(), n, 1, lutCoord(std::clamp(0.5f * z + 0.5f, 0.f, 1.f), n),
                   lutCoord(std::clamp(len, 0.f, 1.f), n), &out);
    return out;
}

}  // namespace specula::ltc
