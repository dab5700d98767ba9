// Procedural glint BRDF (Chermain et al. 2020 "C20") with geometric glint anti-aliasing and slope correlation
// (Chermain et al. 2021 "C21"): spec glint-brdf.md §3 steps S0-S7, in float with the same operations as glint.glsl.
#pragma once

#include "core/render/bsdf.h"
#include "core/render/lobes/fresnel.h"
#include "nodes/bsdf/glint/glint_dictionary.h"

#include <atomic>
#include <cstdint>
#include <limits>

namespace specula::glint {

enum class DerivMode : uint8_t { ProjectedHalf = 0, HalfSlope = 1 };

// Material inputs (spec §1). Values are clamped by GlintShape::make / the node as the authors' code does.
struct GlintParams {
    float sigmaX = 0.16f, sigmaY = 0.16f;  // RMS slopes of the converged lobe, clamped to [0.01, 1]
    float rho = 0.f;                       // slope correlation (C21 §5.2), clamped to +-0.99
    float logDensity = 15.f;               // lambda = ln(microfacets per unit UV area)
    float relArea = 1.f;                   // A: probability that a cell holds microfacets
    float jitter = 2.f;                    // zeta: std of the per-cell dictionary-LOD jitter
    float maxAniso = 8.f;                  // a_max
    bool ggaa = true;                      // C21 §4.2
    float kernelScale = 0.5f;              // s_K (C21 Eq. 19)
    DerivMode mode = DerivMode::ProjectedHalf;  // C21 Eq. 21 (default) or Eq. 20
};

constexpr int kCellCap = 100;  // the GLSL's cap on evaluated cells per LOD (spec §3 S3); hits are counted
std::atomic<uint64_t>& cellCapHits();

// The linear transformation of C21 Eq. 18, M = (1/sigma_o) [[sx sqrt(1-rho^2), rho sx], [0, sy]], through its inverse
// M^-1 = sigma_o [[1/(sx sq), -rho/(sy sq)], [0, 1/sy]] and det(M^-1) = sigma_o^2 / (sx sy sq)   (spec S4.7, S4.10).
struct GlintShape {
    float sx, sy, rho, sq;
    float mi00, mi01, mi11;
    float detMinv;
    static GlintShape make(float sigmaX, float sigmaY, float rho) {
        GlintShape s;
        s.sx = std::clamp(sigmaX, 0.01f, 1.f);
        s.sy = std::clamp(sigmaY, 0.01f, 1.f);
        s.rho = std::clamp(rho, -0.99f, 0.99f);
        s.sq = std::sqrt(1.f - s.rho * s.rho);
        const float so = float(kSigmaO);
        s.mi00 = so / (s.sx * s.sq);
        s.mi01 = -so * s.rho / (s.sy * s.sq);
        s.mi11 = so / s.sy;
        s.detMinv = so * so / (s.sx * s.sy * s.sq);
        return s;
    }
    Vec2 applyInv(Vec2 v) const { return {mi00 * v.x + mi01 * v.y, mi11 * v.y}; }
};

// Non-axis-aligned Beckmann SDF (spec S7; C21 Eq. 16 covariance):
// P_B(x, y) = exp(-q/2) / (2 pi sx sy sqrt(1-rho^2)), q = [x^2/sx^2 - 2 rho x y/(sx sy) + y^2/sy^2] / (1-rho^2).
inline float beckmannSdf(Vec2 h, const GlintShape& s) {
    const float a = h.x / s.sx, b = h.y / s.sy;
    const float q = (a * a - 2.f * s.rho * a * b + b * b) / (s.sq * s.sq);
    return std::exp(-0.5f * q) / (2.f * kPi * s.sx * s.sy * s.sq);
}

// ---- per-cell random numbers (spec S4.1-S4.2) ---------------------------------------------------------------
// Coherent seed S = s*2^l + 1549*t*2^l in wrapping uint32 arithmetic (level-l cell = its level-0 corner child).
inline uint32_t cellSeed(int l, int s, int t) {
    const uint32_t p = 1u << l;
    return uint32_t(s) * p + 1549u * uint32_t(t) * p;
}
// Hugo-Elias integer hash as used by Quilez; H(n) in [0, 1], clamped to [2^-24, 1 - 2^-24] (spec recommendation).
inline float hashUniform(uint32_t n) {
    n = (n << 13u) ^ n;
    n = n * (n * n * 15731u + 789221u) + 1376312589u;
    const float u = float(n & 0x7fffffffu) / float(0x7fffffff);
    return std::clamp(u, 5.9604645e-8f, 0.99999994f);
}
struct CellRandom {
    float uA, uZ, uTheta, uI, uJ;
};
inline CellRandom cellRandom(uint32_t S) {
    return {hashUniform(13u * S), hashUniform(2171u * S), hashUniform(S), hashUniform(16807u * S), hashUniform(48271u * S)};
}

// Single-precision erfinv (Giles 2010, "Approximating the erfinv function", GPU Gems 4); same in GLSL.
inline float erfinvF(float x) {
    float w = -std::log((1.f - x) * (1.f + x)), p;
    if (w < 5.f) {
        w = w - 2.5f;
        p = 2.81022636e-08f;
        p = 3.43273939e-07f + p * w;
        p = -3.5233877e-06f + p * w;
        p = -4.39150654e-06f + p * w;
        p = 0.00021858087f + p * w;
        p = -0.00125372503f + p * w;
        p = -0.00417768164f + p * w;
        p = 0.246640727f + p * w;
        p = 1.50140941f + p * w;
    } else {
        w = std::sqrt(w) - 3.f;
        p = -0.000200214257f;
        p = 0.000100950558f + p * w;
        p = 0.00134934322f + p * w;
        p = -0.00367342844f + p * w;
        p = 0.00573950773f + p * w;
        p = -0.0076224613f + p * w;
        p = 0.00943887047f + p * w;
        p = 1.00167406f + p * w;
        p = 2.83297682f + p * w;
    }
    return p * x;
}

// ---- 1D texture emulation (spec S5.4): centre convention, mirrored repeat, GL trilinear rule --------------
inline int mirrorIndex(int i, int n) {
    const int p = 2 * n;
    i %= p;
    if (i < 0) i += p;
    return i < n ? i : p - 1 - i;
}
// Linear filtering between texel centres with GL_MIRRORED_REPEAT; u in texture units (1 = 4 sigma_o).
inline float sampleLinear(const float* tex, int n, float u) {
    const float t = u * float(n) - 0.5f;
    const float fl = std::floor(t);
    const float f = t - fl;
    const int i0 = int(fl);
    return (1.f - f) * tex[mirrorIndex(i0, n)] + f * tex[mirrorIndex(i0 + 1, n)];
}
// textureGrad on one dictionary row (127 floats): isotropic GL LOD mu = log2(R max(|g1|, |g2|)), clamped to
// [0, log2 R]; mu <= 0: MIP 0 linear; else blend MIPs floor(mu) and floor(mu)+1 by frac(mu).
struct MipBlend {
    int m0 = 0;     // first MIP
    float f = 0.f;  // weight of MIP m0 + 1 (0: MIP m0 alone)
};
inline MipBlend textureGradLod(float g1, float g2) {  // shared with the area-light integral (glint_area.cpp)
    const float rho = float(kRes) * std::max(std::abs(g1), std::abs(g2));
    if (!(rho > 1.f)) return {};
    const float mu = std::min(std::log2(rho), float(kMips - 1));
    const float m0f = std::floor(mu);
    const int m0 = int(m0f);
    return {m0, m0 >= kMips - 1 ? 0.f : mu - m0f};
}
inline float textureGrad1D(const float* row, float u, float g1, float g2) {
    const MipBlend b = textureGradLod(g1, g2);
    const float v0 = sampleLinear(row + mipOffset(b.m0), mipRes(b.m0), u);
    if (!(b.f > 0.f)) return v0;
    const float v1 = sampleLinear(row + mipOffset(b.m0 + 1), mipRes(b.m0 + 1), u);
    return (1.f - b.f) * v0 + b.f * v1;
}

// ---- S1/S2: footprint and LOD ---------------------------------------------------------------------------
struct Footprint {
    Vec2 a1{0.f}, a2{0.f};  // major and (anisotropy-clamped) minor axis in UV
    float lodP = 0.f;       // l_P in [0, L-1]
    bool valid = false;     // false: |a2| = 0, the analytic D is used (spec S1 recommendation)
};
inline Footprint footprint(Vec2 J1, Vec2 J2, float maxAniso) {
    Footprint fp;
    const float l1 = glm::dot(J1, J1), l2 = glm::dot(J2, J2);
    fp.a1 = l1 >= l2 ? J1 : J2;
    fp.a2 = l1 >= l2 ? J2 : J1;
    float la1 = std::sqrt(std::max(l1, l2)), la2 = std::sqrt(std::min(l1, l2));
    if (!(la2 > 0.f) || !std::isfinite(la1)) return fp;
    if (la1 > maxAniso * la2) {  // lengthen the minor axis (C20 code, pbrt EWA)
        fp.a2 = fp.a2 * (la1 / (maxAniso * la2));
        la2 = la1 / maxAniso;
    }
    // l_P = max(0, (L-1) + log2|a2|), clamped to <= L-1 (spec S2 recommendation).
    fp.lodP = std::clamp(float(kLevels - 1) + std::log2(la2), 0.f, float(kLevels - 1));
    fp.valid = true;
    return fp;
}

// Everything constant over one SDF evaluation.
struct SdfQuery {
    const Dictionary* dict = nullptr;
    GlintShape shape;
    float relArea = 1.f, jitter = 2.f;
    float lcBase = 0.f;  // lambda/ln 4 - (L-1): l_c = lcBase + l (spec S4.4)
    Vec2 hs{0.f};        // half slope h~
    Vec2 mh{0.f};        // M^-1 h~ (m_o = Rot(-theta) mh)
    bool ggaa = false;
    Vec2 gx{0.f}, gy{0.f};  // s_K M^-1 d_{x,y} / (4 sigma_o): kernel gradients before the cell rotation (S5.2)
    float pB = 0.f;         // P_B(h~)
};

// S4 (C20 Alg. 3 with the C21 matrix) and S5 (C21 Eqs. 15, 19): the SDF of cell (s, t) at level l.
// The per-cell draws of S4.1-S4.5 that do not depend on h~ (shared with the area-light integral, glint_area.h):
// occupancy, dictionary level k (k = L: converged), rotation theta and the marginal indices i, j.
struct CellDraw {
    bool empty = true, converged = false;
    int k = 0, i = 0, j = 0;
    float theta = 0.f;
};
inline CellDraw drawCell(const SdfQuery& q, int l, int s, int t) {
    CellDraw d;
    const CellRandom r = cellRandom(cellSeed(l, s, t));
    if (r.uA > q.relArea) return d;  // empty cell (sparse glints)
    d.empty = false;
    const float lc = q.lcBase + float(l);
    const float ld = lc + q.jitter * 1.41421356f * erfinvF(2.f * r.uZ - 1.f);
    d.k = int(std::clamp(std::floor(ld + 0.5f), 0.f, float(kLevels)));
    d.converged = d.k == kLevels;
    d.theta = 2.f * kPi * r.uTheta;
    d.i = std::min(int(float(kMarginals) * r.uI), kMarginals - 1);
    d.j = std::min(int(float(kMarginals) * r.uJ), kMarginals - 1);
    return d;
}

inline float cellSdf(const SdfQuery& q, int l, int s, int t) {
    const CellDraw d = drawCell(q, l, s, t);
    if (d.empty) return 0.f;
    if (d.converged) return q.pB;  // converged cell: analytic Beckmann (S4.6)
    const int k = d.k, i = d.i, j = d.j;
    const float c = std::cos(d.theta), sn = std::sin(d.theta);
    // m_o = Rot(-theta) M^-1 h~ (C21 Eq. 5 with M_c = M Rot(theta))
    const float mx = c * q.mh.x + sn * q.mh.y, my = -sn * q.mh.x + c * q.mh.y;
    const float lim = float(4.0 * kSigmaO);
    if (std::abs(mx) >= lim || std::abs(my) >= lim) return 0.f;
    const float ux = std::abs(mx) / lim, uy = std::abs(my) / lim;
    float px, py;
    if (q.ggaa) {
        // Kernel in texture units: s_K Rot(-theta) M^-1 d / (4 sigma_o); x-marginal gets the x components (S5.3).
        const float gxx = c * q.gx.x + sn * q.gx.y, gxy = -sn * q.gx.x + c * q.gx.y;
        const float gyx = c * q.gy.x + sn * q.gy.y, gyy = -sn * q.gy.x + c * q.gy.y;
        px = textureGrad1D(q.dict->row(k, i), ux, gxx, gyx);
        py = textureGrad1D(q.dict->row(k, j), uy, gxy, gyy);
    } else {
        px = sampleLinear(q.dict->row(k, i), kRes, ux);
        py = sampleLinear(q.dict->row(k, j), kRes, uy);
    }
    return q.shape.detMinv * px * py;  // C21 Eq. 4 / Eq. 15
}

// S3: EWA footprint-to-cell weights W_P over integer cells at level l (pbrt-v3 / Heckbert). Calls
// visit(s, t, W) for every cell inside the ellipse (at most kCellCap; further cells are counted in cellCapHits) and
// returns how many were visited. Shared by the point evaluation (levelSdf) and the area-light integral.
template <class Visit>
inline int forEachCell(int l, Vec2 uv, Vec2 a1, Vec2 a2, Visit&& visit) {
    const float n = float(1 << (kLevels - 1 - l));  // cells per UV unit
    const float cs = uv.x * n - 0.5f, ct = uv.y * n - 0.5f;
    const Vec2 b1 = a1 * n, b2 = a2 * n;
    float A = b1.y * b1.y + b2.y * b2.y + 1.f;
    float B = -2.f * (b1.x * b1.y + b2.x * b2.y);
    float C = b1.x * b1.x + b2.x * b2.x + 1.f;
    const float F = A * C - B * B * 0.25f;
    A /= F, B /= F, C /= F;
    const float det = 4.f * A * C - B * B;
    const float invDet = 1.f / det;
    const float su = 2.f * invDet * std::sqrt(det * C), sv = 2.f * invDet * std::sqrt(det * A);
    const int s0 = int(std::ceil(cs - su)), s1 = int(std::floor(cs + su));
    const int t0 = int(std::ceil(ct - sv)), t1 = int(std::floor(ct + sv));
    const float e2 = 0.13533528f;  // e^-2
    int count = 0;
    for (int t = t0; t <= t1; ++t) {
        const float dt = float(t) - ct;
        for (int s = s0; s <= s1; ++s) {
            const float ds = float(s) - cs;
            const float r2 = A * ds * ds + B * ds * dt + C * dt * dt;
            if (!(r2 < 1.f)) continue;
            if (count >= kCellCap) {
                cellCapHits().fetch_add(1, std::memory_order_relaxed);
                return count;
            }
            ++count;
            visit(s, t, std::exp(-2.f * r2) - e2);
        }
    }
    return count;
}

// The normalised EWA average of the cells' SDFs at level l (spec S3 step 6).
inline float levelSdf(const SdfQuery& q, int l, Vec2 uv, Vec2 a1, Vec2 a2, int* visited = nullptr) {
    float sumW = 0.f, sumWP = 0.f;
    const int count = forEachCell(l, uv, a1, a2, [&](int s, int t, float W) {
        sumW += W;
        sumWP += W * cellSdf(q, l, s, t);
    });
    if (visited) *visited = count;
    return sumW > 0.f ? sumWP / sumW : 0.f;
}

// Patch SDF P(h~) of C20 Eq. 3 / C21 Eq. 10: LOD blend of two levels (S2).
inline float patchSdf(const SdfQuery& q, Vec2 uv, const Footprint& fp) {
    if (!fp.valid) return q.pB;
    const float i0f = std::floor(fp.lodP);
    const int i0 = int(i0f);
    const float w = fp.lodP - i0f;
    const float p0 = levelSdf(q, i0, uv, fp.a1, fp.a2);
    if (!(w > 0.f)) return p0;
    const float p1 = levelSdf(q, std::min(i0 + 1, kLevels - 1), uv, fp.a1, fp.a2);
    return (1.f - w) * p0 + w * p1;
}

// Derivative of the GGAA quantity from dh: the projected half vector (h_x, h_y) (C21 Eq. 21) or the half slope
// h~ = (-h_x/h_z, -h_y/h_z) (C21 Eq. 20, first order).
inline Vec2 quantityDerivative(const Vec3& h, const Vec3& dh, DerivMode mode) {
    if (mode == DerivMode::ProjectedHalf) return {dh.x, dh.y};
    const float iz2 = 1.f / (h.z * h.z);
    return {-(dh.x * h.z - h.x * dh.z) * iz2, -(dh.y * h.z - h.y * dh.z) * iz2};
}

// Builds the query for half vector h (local frame, h.z > 0). dx/dy: per-pixel derivatives of the GGAA quantity
// (quantityDerivative), turned into kernel gradients in texture units g = s_K M^-1 d / (4 sigma_o) (S5.2).
inline SdfQuery makeQuery(const Dictionary& dict, const GlintParams& p, const GlintShape& shape, const Vec3& h,
                          Vec2 dx, Vec2 dy) {
    SdfQuery q;
    q.dict = &dict;
    q.shape = shape;
    q.relArea = p.relArea;
    q.jitter = p.jitter;
    q.lcBase = p.logDensity / 1.38629436f - float(kLevels - 1);
    q.hs = Vec2(-h.x / h.z, -h.y / h.z);
    q.mh = shape.applyInv(q.hs);
    q.pB = beckmannSdf(q.hs, shape);
    q.ggaa = p.ggaa;
    if (p.ggaa) {
        const float k = p.kernelScale / float(4.0 * kSigmaO);
        q.gx = shape.applyInv(dx) * k;
        q.gy = shape.applyInv(dy) * k;
    }
    return q;
}

// A 2x2-quad partner pixel (render setting "derivatives": "quad", ShadingPoint::quad), in this lobe's local frame:
// the GGAA difference is sign * (q(partner) - q(this)) with each h expressed in its own (normal-mapped) frame, as
// dFdx of the tangent-space h does on a GPU (C21 §6.1).
struct GlintNeighbour {
    bool valid = false;
    float sign = 1.f;
    Vec3 dp{0.f}, wo{0.f};  // partner position minus this position, partner wo
    Vec3 t{1, 0, 0}, b{0, 1, 0}, n{0, 0, 1};  // partner frame
};

// Per-pixel change of the local frame and of wo, from which dh is formed at eval time (C21 §6.1 computes
// dFdx(h) once per pixel). dn: (t.dN, b.dN), the infinitesimal rotation of the frame; dwo/dp: local change of wo
// and of the position (CPU only: the GLSL inputs carry neither). wi changes only for delta lights at a finite
// distance (the query's light distance); otherwise it is held fixed (directional light).
struct GlintDifferentials {
    Vec2 dnx{0.f}, dny{0.f};
    Vec3 dwox{0.f}, dwoy{0.f};
    Vec3 dpx{0.f}, dpy{0.f};
    GlintNeighbour nb[2];
};

// d(w_local) for a fixed world vector under the frame rotation a = (t.dN, b.dN): (-a.x w.z, -a.y w.z, a.w_xy).
inline Vec3 frameRotation(Vec2 a, const Vec3& w) { return {-a.x * w.z, -a.y * w.z, a.x * w.x + a.y * w.y}; }

// dh = (I - h h^T)(dwo + dwi) / |wo + wi|.
inline Vec3 halfDerivative(const Vec3& h, float len, const Vec3& dsum) {
    return (dsum - h * glm::dot(h, dsum)) / len;
}

// GGAA derivative of the quantity along screen axis k (0 = x, 1 = y).
inline Vec2 ggaaDerivative(const GlintDifferentials& d, int k, DerivMode mode, const Vec3& wo, const Vec3& wi,
                           const Vec3& h, float len, float dist) {
    const bool finite = std::isfinite(dist) && dist > 0.f;
    const GlintNeighbour& nb = d.nb[k];
    if (nb.valid) {
        const Vec3 wiN = finite ? glm::normalize(wi * dist - nb.dp) : wi;
        const Vec3 hN = glm::normalize(nb.wo + wiN);
        const Vec3 hl(glm::dot(hN, nb.t), glm::dot(hN, nb.b), glm::dot(hN, nb.n));
        if (hl.z > 0.f) {
            if (mode == DerivMode::ProjectedHalf) return Vec2(hl.x - h.x, hl.y - h.y) * nb.sign;
            return (Vec2(-hl.x / hl.z, -hl.y / hl.z) - Vec2(-h.x / h.z, -h.y / h.z)) * nb.sign;
        }
    }
    const Vec2 a = k == 0 ? d.dnx : d.dny;
    Vec3 dsum = frameRotation(a, wo) + (k == 0 ? d.dwox : d.dwoy) + frameRotation(a, wi);
    if (finite) {  // wi = (L - p)/|L - p|: dwi = -(I - wi wi^T) dp / dist
        const Vec3 dp = k == 0 ? d.dpx : d.dpy;
        dsum -= (dp - wi * glm::dot(wi, dp)) / dist;
    }
    return quantityDerivative(h, halfDerivative(h, len, dsum), mode);
}

// The full BRDF times cos(theta_i) (C20 Eq. 14 + S7): F G D / (4 wo.z), D = P / h_z^4,
// G = G1(wo) G1(wi), G1(w) = min(1, 2 h_z w_z / (w.h)) (V-cavity). Returns 0 per the S0 rejections.
struct GlintEvalInputs {
    Vec2 uv{0.f}, duvdx{0.f}, duvdy{0.f};  // already multiplied by the uv scale
    GlintDifferentials diff;
};
inline float glintFCosScalar(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                             const GlintEvalInputs& in, const Vec3& wo, const Vec3& wi, Vec3* hOut = nullptr,
                             float lightDistance = std::numeric_limits<float>::infinity()) {
    if (wo.z <= 0.f || wi.z <= 0.f) return 0.f;
    const Vec3 hs = wo + wi;
    const float len = std::sqrt(glm::dot(hs, hs));
    if (!(len > 0.f)) return 0.f;
    const Vec3 h = hs / len;
    const float woh = glm::dot(wo, h), wih = glm::dot(wi, h);
    if (h.z <= 0.f || woh <= 0.f || wih <= 0.f) return 0.f;
    if (hOut) *hOut = h;
    Vec2 dx(0.f), dy(0.f);
    if (p.ggaa) {
        dx = ggaaDerivative(in.diff, 0, p.mode, wo, wi, h, len, lightDistance);
        dy = ggaaDerivative(in.diff, 1, p.mode, wo, wi, h, len, lightDistance);
    }
    const SdfQuery q = makeQuery(dict, p, shape, h, dx, dy);
    const Footprint fp = footprint(in.duvdx, in.duvdy, p.maxAniso);
    const float P = patchSdf(q, in.uv, fp);
    const float hz2 = h.z * h.z;
    const float D = P / (hz2 * hz2);
    const float G = std::min(1.f, 2.f * h.z * wo.z / woh) * std::min(1.f, 2.f * h.z * wi.z / wih);
    return G * D / (4.f * wo.z);
}

// Reference limit (spec S7, "Limit as density -> infinity"): Cook-Torrance with P_B and the same V-cavity G.
inline float beckmannFCosScalar(const GlintShape& shape, const Vec3& wo, const Vec3& wi) {
    if (wo.z <= 0.f || wi.z <= 0.f) return 0.f;
    const Vec3 hs = wo + wi;
    const float len = std::sqrt(glm::dot(hs, hs));
    if (!(len > 0.f)) return 0.f;
    const Vec3 h = hs / len;
    const float woh = glm::dot(wo, h), wih = glm::dot(wi, h);
    if (h.z <= 0.f || woh <= 0.f || wih <= 0.f) return 0.f;
    const float hz2 = h.z * h.z;
    const float D = beckmannSdf(Vec2(-h.x / h.z, -h.y / h.z), shape) / (hz2 * hz2);
    const float G = std::min(1.f, 2.f * h.z * wo.z / woh) * std::min(1.f, 2.f * h.z * wi.z / wih);
    return G * D / (4.f * wo.z);
}

// Importance sampling: half slopes from the limiting correlated Beckmann lobe N(0, Sigma) (C21 Eq. 16),
// h~ = L z with L the Cholesky factor [[sx, 0], [rho sy, sy sqrt(1-rho^2)]], z from Box-Muller; wi = reflect.
// Its exact solid-angle pdf is P_B(h~) / h_z^3 / (4 wo.h), so MIS stays unbiased whatever the glints are.
inline Vec3 sampleBeckmannHalf(const GlintShape& s, const Vec2& u) {
    const float r = std::sqrt(-2.f * std::log(std::max(1.f - u.x, 1e-12f)));
    const float phi = 2.f * kPi * u.y;
    const float z1 = r * std::cos(phi), z2 = r * std::sin(phi);
    const float hx = s.sx * z1, hy = s.sy * (s.rho * z1 + s.sq * z2);  // half slope h~
    return glm::normalize(Vec3(-hx, -hy, 1.f));
}
inline float beckmannHalfPdf(const GlintShape& s, const Vec3& wo, const Vec3& wi) {
    if (wo.z <= 0.f || wi.z <= 0.f) return 0.f;
    const Vec3 hs = wo + wi;
    const float len = std::sqrt(glm::dot(hs, hs));
    if (!(len > 0.f)) return 0.f;
    const Vec3 h = hs / len;
    const float woh = glm::dot(wo, h);
    if (h.z <= 0.f || woh <= 0.f) return 0.f;
    return beckmannSdf(Vec2(-h.x / h.z, -h.y / h.z), s) / (h.z * h.z * h.z) / (4.f * woh);
}

// S6 (C21 §5): LEAN mapping with glints. cov = (var_x, var_y, cov_xy) of the normal-map slopes over the footprint
// (var = E[x^2] - E[x]^2, from the LEAN moments). Variances are clamped to [1e-4, 1]; if either hit the lower clamp the
// normal-map term is dropped. Otherwise sigma^2 = sigma_m^2 + sigma_n^2 per axis and
// rho = (rho_m sigma_mx sigma_my + rho_n sigma_nx sigma_ny) / (sigma_x sigma_y), then sigma in [0.01, 1], rho in +-0.99.
// Returns whether the normal-map term was applied.
inline bool leanCombine(float& sigmaX, float& sigmaY, float& rho, const Vec3& cov) {
    const float vx = std::min(cov.x, 1.f), vy = std::min(cov.y, 1.f);
    if (!(vx > 1e-4f) || !(vy > 1e-4f)) return false;
    const float snx = std::sqrt(vx), sny = std::sqrt(vy);
    const float rn = std::clamp(cov.z / (snx * sny), -0.99f, 0.99f);
    const float sx = std::sqrt(sigmaX * sigmaX + vx), sy = std::sqrt(sigmaY * sigmaY + vy);
    rho = std::clamp((rho * sigmaX * sigmaY + rn * snx * sny) / (sx * sy), -0.99f, 0.99f);
    sigmaX = std::clamp(sx, 0.01f, 1.f);
    sigmaY = std::clamp(sy, 0.01f, 1.f);
    return true;
}
// S6.4: the shading normal of the mean slope (E[x], E[y]) in the frame (t, b, n): n' ∝ (-E[x], -E[y], 1); if it faces
// away from wo it is pulled towards wo by 1.01 times its component along wo. (The tangent follows by Gram-Schmidt.)
inline Vec3 leanNormal(const Vec3& t, const Vec3& b, const Vec3& n, Vec2 mean, const Vec3& wo) {
    Vec3 m = glm::normalize(n - mean.x * t - mean.y * b);
    const float c = glm::dot(m, wo);
    if (c < 0.f) m = glm::normalize(m - 1.01f * c * wo);
    return m;
}

// The glint lobe of the renderer: eval = F(wo.h) * glintFCosScalar; sample/pdf: the limiting Beckmann lobe.
class GlintLobe final : public BsdfLobe {
public:
    GlintLobe(const Dictionary& dict, const GlintParams& p, const GlintEvalInputs& in, const Fresnel& fresnel)
        : dict_(dict), p_(p), shape_(GlintShape::make(p.sigmaX, p.sigmaY, p.rho)), in_(in), fresnel_(fresnel) {}
    LobeKind kind() const override { return LobeKind::Specular; }
    using BsdfLobe::sample;
    LobeValue evalPdf(const LobeQuery& q) const override {
        LobeValue v;
        Vec3 h;
        const float f = glintFCosScalar(dict_, p_, shape_, in_, q.wo, q.wi, &h, q.lightDistance);
        if (f > 0.f) v.f = fresnel_.eval(glm::dot(q.wo, h)) * f;
        v.pdf = beckmannHalfPdf(shape_, q.wo, q.wi);
        return v;
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        const Vec3& wo = q.wo;
        if (wo.z <= 0.f) return false;
        const Vec3 h = sampleBeckmannHalf(shape_, u);
        const float woh = glm::dot(wo, h);
        if (woh <= 0.f) return false;
        wi = 2.f * woh * h - wo;
        return wi.z > 0.f;
    }
    // Expected albedo estimate (selection weights, albedo AOV): A F(wo.z), the limit's mean energy.
    Color3 albedo(const Vec3& wo) const override {
        return fresnel_.eval(std::max(wo.z, 0.f)) * std::clamp(p_.relArea, 0.f, 1.f);
    }
    const char* modelName() const override { return "glint"; }
    void parameters(const LobeQuery&, LobeParameters& out) const override {
        out.push_back({"sigma", {p_.sigmaX, p_.sigmaY}});
        out.push_back({"rho", {p_.rho}});
        out.push_back({"log_density", {p_.logDensity}});
        out.push_back({"ggaa", {p_.ggaa ? 1.0 : 0.0}});
        out.push_back({"footprint_duv", {in_.duvdx.x, in_.duvdx.y, in_.duvdy.x, in_.duvdy.y}});
    }
    // Quad lights (issue 11 item 2): the per-cell polygon integral and the shadow-ray direction (glint_area.cpp).
    bool integratePolygon(const LobeQuery& q, const Vec3* vertices, int count, Color3& result) const override;
    bool samplePolygon(const LobeQuery& q, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                       Vec3& wi) const override;
    const GlintParams& params() const { return p_; }
    const GlintEvalInputs& inputs() const { return in_; }

private:
    const Dictionary& dict_;
    GlintParams p_;
    GlintShape shape_;
    GlintEvalInputs in_;
    Fresnel fresnel_;
};

}  // namespace specula::glint
