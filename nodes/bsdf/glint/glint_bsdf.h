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
    // GlintLobe::sample: the glint distribution of the shading point mixed with the Beckmann lobe (true), or the
    // limiting Beckmann lobe alone (false: the sampler before issue 11, kept for the variance comparisons).
    bool sampleGlints = true;
    // Quad lights (polygon queries): integrate each cell's distribution over the light's half-vector region
    // (glint_area.h; noise-free, ~10-30x the cost of a light sample) or let the integrator sample the light.
    bool integrateQuadLights = false;
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
// Inside [0, 1) (every glint lookup: u = |m| / (4 sigma_o) < 1) the texel pair is (i0, i0+1) with i0 in [-1, n-1], where
// mirroring is a clamp to [0, n-1]: the same texels without the two integer divisions of mirrorIndex.
inline float sampleLinear(const float* tex, int n, float u) {
    const float t = u * float(n) - 0.5f;
    const float fl = std::floor(t);
    const float f = t - fl;
    const int i0 = int(fl);
    if (i0 >= -1 && i0 < n) return (1.f - f) * tex[std::max(i0, 0)] + f * tex[std::min(i0 + 1, n - 1)];
    return (1.f - f) * tex[mirrorIndex(i0, n)] + f * tex[mirrorIndex(i0 + 1, n)];
}
// textureGrad on one dictionary row (127 floats): isotropic GL LOD mu = log2(R max(|g1|, |g2|)), clamped to
// [0, log2 R]; mu <= 0: MIP 0 linear; else blend MIPs floor(mu) and floor(mu)+1 by frac(mu).
struct MipBlend {
    int m0 = 0;     // first MIP
    float f = 0.f;  // weight of MIP m0 + 1 (0: MIP m0 alone)
};
// The MIP blend for rho = R max(|g1|, |g2|) > 1.
inline MipBlend textureGradLodOf(float rho) {
    const float mu = std::min(std::log2(rho), float(kMips - 1));
    const float m0f = std::floor(mu);
    const int m0 = int(m0f);
    return {m0, m0 >= kMips - 1 ? 0.f : mu - m0f};
}
inline MipBlend textureGradLod(float g1, float g2) {  // shared with the area-light integral (glint_area.cpp)
    const float rho = float(kRes) * std::max(std::abs(g1), std::abs(g2));
    if (!(rho > 1.f)) return {};
    return textureGradLodOf(rho);
}
// The filtered branch (rho = R max(|g1|, |g2|) > 1) on its own, for callers that already have the MIP-0 value.
inline float textureGradFiltered(const float* row, float u, float rho) {
    const MipBlend b = textureGradLodOf(rho);
    const float v0 = sampleLinear(row + mipOffset(b.m0), mipRes(b.m0), u);
    if (!(b.f > 0.f)) return v0;
    const float v1 = sampleLinear(row + mipOffset(b.m0 + 1), mipRes(b.m0 + 1), u);
    return (1.f - b.f) * v0 + b.f * v1;
}
inline float textureGrad1D(const float* row, float u, float g1, float g2) {
    const float rho = float(kRes) * std::max(std::abs(g1), std::abs(g2));
    if (!(rho > 1.f)) return sampleLinear(row, kRes, u);
    return textureGradFiltered(row, u, rho);
}

// ---- per-thread memo of the cells' random numbers ---------------------------------------------------------------
// Every random number of a cell is a function of its seed S alone (S4.2), whatever the material, and consecutive
// shading points revisit the same cells (the samples of one pixel, neighbouring pixels, the coarser of the two
// LODs): a direct-mapped table per thread keeps u_A, erfinv(2 u_z - 1), cos/sin theta and the marginal indices of
// the last 4096 seeds. A memo of a pure function: results do not depend on its state, hence not on threads.
struct CellMemoEntry {
    uint32_t seed;
    float uA, erfZ;  // u_A and erfinv(2 u_z - 1) (the material scales it by zeta sqrt 2 and adds l_c, S4.5)
    float cosT, sinT;
    uint8_t i, j, filled, pad;
};
struct CellMemo {
    static constexpr int kBits = 12;
    CellMemoEntry entries[1 << kBits];  // zero-initialised thread_local storage: filled = 0
    const CellMemoEntry& get(uint32_t S) {
        CellMemoEntry& e = entries[(S * 0x9E3779B1u) >> (32 - kBits)];
        if (e.filled && e.seed == S) return e;
        e.seed = S;
        e.uA = hashUniform(13u * S);
        e.erfZ = erfinvF(2.f * hashUniform(2171u * S) - 1.f);
        const float theta = 2.f * kPi * hashUniform(S);  // as cellSdf: the same floats
        e.cosT = std::cos(theta);
        e.sinT = std::sin(theta);
        e.i = uint8_t(std::min(int(float(kMarginals) * hashUniform(16807u * S)), kMarginals - 1));
        e.j = uint8_t(std::min(int(float(kMarginals) * hashUniform(48271u * S)), kMarginals - 1));
        e.filled = 1;
        return e;
    }
};
inline CellMemo& cellMemo() {
    static thread_local CellMemo memo;
    return memo;
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

// The dictionary LOD k of a non-empty cell (S4.4-S4.5): l_d = l_c + zeta sqrt(2) erfinv(2 u_z - 1), k = clamp(round(l_d),
// 0, L); k = L means converged (analytic P_B). S is the cell seed; zeta = 0 skips the hash (0 * erfinv = 0).
// dictionaryLod takes erfinv(2 u_z - 1) already computed (CellMemoEntry::erfZ).
inline int dictionaryLod(float lc, float jitter, float erfZ) {
    const float ld = jitter != 0.f ? lc + jitter * 1.41421356f * erfZ : lc;
    return int(std::clamp(std::floor(ld + 0.5f), 0.f, float(kLevels)));
}
inline int cellDictionaryLod(uint32_t S, float lc, float jitter) {
    return dictionaryLod(lc, jitter, jitter != 0.f ? erfinvF(2.f * hashUniform(2171u * S) - 1.f) : 0.f);
}
inline int marginalIndex(float u) { return std::min(int(float(kMarginals) * u), kMarginals - 1); }

// The per-cell draws of S4.1-S4.5 that do not depend on h~ (the area-light integral, glint_area.h): occupancy,
// dictionary level k (k = L: converged), the rotation (cos, sin theta) and the marginal indices i, j; the same numbers
// as cellSdf, read through the per-thread memo.
struct CellDraw {
    bool empty = true, converged = false;
    int k = 0, i = 0, j = 0;
    float cosT = 1.f, sinT = 0.f;
};
inline CellDraw drawCell(const SdfQuery& q, int l, int s, int t) {
    CellDraw d;
    const CellMemoEntry& r = cellMemo().get(cellSeed(l, s, t));
    if (r.uA > q.relArea) return d;  // empty cell (sparse glints)
    d.empty = false;
    d.k = dictionaryLod(q.lcBase + float(l), q.jitter, r.erfZ);
    d.converged = d.k == kLevels;
    d.cosT = r.cosT, d.sinT = r.sinT;
    d.i = r.i, d.j = r.j;
    return d;
}

// S4 (C20 Alg. 3 with the C21 matrix) and S5 (C21 Eqs. 15, 19): the SDF of cell (s, t) at level l. The five uniforms
// are those of cellRandom, hashed only when needed: u_A first (an empty cell costs one hash), then u_z.
inline float cellSdf(const SdfQuery& q, int l, int s, int t) {
    const uint32_t S = cellSeed(l, s, t);
    if (hashUniform(13u * S) > q.relArea) return 0.f;  // empty cell (sparse glints)
    const int k = cellDictionaryLod(S, q.lcBase + float(l), q.jitter);
    if (k == kLevels) return q.pB;  // converged cell: analytic Beckmann (S4.6)
    const float theta = 2.f * kPi * hashUniform(S);
    const float c = std::cos(theta), sn = std::sin(theta);
    // m_o = Rot(-theta) M^-1 h~ (C21 Eq. 5 with M_c = M Rot(theta))
    const float mx = c * q.mh.x + sn * q.mh.y, my = -sn * q.mh.x + c * q.mh.y;
    const float lim = float(4.0 * kSigmaO);
    if (std::abs(mx) >= lim || std::abs(my) >= lim) return 0.f;
    const int i = marginalIndex(hashUniform(16807u * S));
    const int j = marginalIndex(hashUniform(48271u * S));
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

// ---- The cells of one shading point (wi-independent work, done once per lobe) -----------------------------------
// Which cells the footprint covers, their EWA weights W, the LOD blend, and each cell's random numbers (u_A, k, theta,
// i, j) depend on uv and the footprint only, not on wi. A shading point asks several queries (one per light, the BSDF
// sample, its MIS evaluation), so the lobe computes them once and each query is one pass over the stored cells:
// per level, sum_c W_c P_c(h~) / sum_c W_c over the visited cells (S3.6), then the LOD blend (S2). The sums run over
// the same terms in the same order as levelSdf/patchSdf (empty cells and cells zeroed by S4.8 add an exact 0), so
// the result is bit-identical to the per-query pipeline. Sampling uses the normalised weights
// w_c = (blend weight) W_c / sum_level W of the non-empty cells.
struct GlintCell {
    float weight;         // W_c (EWA weight, unnormalised)
    float cosT, sinT;     // Rot(theta_c), theta_c = 2 pi u_theta
    uint16_t rowX, rowY;  // k_c * N + i_c and k_c * N + j_c: the dictionary rows; rowX = kConverged: k = L (P_B)
    uint8_t loX, hiX, loY, hiY;  // the rows' nonzero MIP-0 texels (rowSupport)
    static constexpr uint16_t kConverged = 0xffff;
};

// First and last nonzero MIP-0 texel of every dictionary row (2 bytes per row, rows of Dictionary::instance();
// another dictionary gets the full range 0..R-1). A low-k marginal is a few narrow lobes: most of its texels are 0.
const uint8_t* rowSupport(const Dictionary& dict);

// Whether the MIP-0 linear lookup at u in [0, 1) (sampleLinear: texels max(i0, 0) and min(i0 + 1, R - 1)) reads only
// zero texels of a row whose nonzero texels are [lo, hi]: then it returns exactly 0, without touching the row.
inline bool lookupOutsideSupport(float u, int lo, int hi) {
    const int i0 = int(std::floor(u * float(kRes) - 0.5f));
    return std::min(i0 + 1, kRes - 1) < lo || std::max(i0, 0) > hi;
}

// The two SDFs one query needs: the GGAA-filtered one (what eval returns) and the unfiltered one (the density the
// glint sampler draws from); equal when GGAA is off.
struct GlintSdfPair {
    float filtered = 0.f, unfiltered = 0.f;
};

struct GlintCellSet {
    static constexpr int kMaxCells = 2 * kCellCap;  // two LODs, each capped by forEachCell
    bool footprintValid = false;  // false: |a2| = 0, P = P_B (spec S1 recommendation)
    int count = 0;                // non-empty cells (dictionary and converged) in cells[0, count)
    int levels = 0;               // 1 or 2 LODs
    int levelEnd[2] = {0, 0};     // cells of level n: [levelEnd[n-1], levelEnd[n])
    float sumW[2] = {0.f, 0.f};   // sum of W over every visited cell of the level (empty ones included)
    float blend = 0.f;            // w: P = (1 - w) P_lev(i0) + w P_lev(i0 + 1)
    float convergedWeight = 0.f;  // sum of the normalised weights of the converged cells
    float keptWeight = 0.f;       // sum of all normalised weights = the integral of the unfiltered P (spec §4.6)
    GlintCell cells[kMaxCells];   // left uninitialised until build()

    // The sampling weight of cell n: (blend weight of its level) W / sum W.
    float normalisedWeight(int n) const {
        const int lev = n < levelEnd[0] ? 0 : 1;
        return (lev == 0 ? (levels == 2 ? 1.f - blend : 1.f) : blend) * cells[n].weight / sumW[lev];
    }

    // S2 + S3 + S4.1-S4.9 without h~. Empty cells (u_A > A) are not stored (they only normalise).
    void build(const Dictionary& dict, const GlintParams& p, Vec2 uv, const Footprint& fp) {
        count = 0;
        levels = 0;
        convergedWeight = keptWeight = 0.f;
        footprintValid = fp.valid;
        if (!fp.valid) {
            convergedWeight = keptWeight = 1.f;
            return;
        }
        const float i0f = std::floor(fp.lodP);
        const int i0 = int(i0f);
        blend = fp.lodP - i0f;
        CellMemo& memo = cellMemo();  // one thread-local access per shading point
        const uint8_t* support = rowSupport(dict);
        addLevel(memo, support, p, i0, uv, fp);
        if (blend > 0.f) addLevel(memo, support, p, std::min(i0 + 1, kLevels - 1), uv, fp);
        for (int n = 0; n < count; ++n) {
            if (!(sumW[n < levelEnd[0] ? 0 : 1] > 0.f)) continue;
            const float w = normalisedWeight(n);
            keptWeight += w;
            if (cells[n].rowX == GlintCell::kConverged) convergedWeight += w;
        }
    }

    // P(h~) from mh = M^-1 h~ and the GGAA kernel gradients before the cell rotation (SdfQuery::gx, gy), pB = P_B(h~).
    // kUnfiltered: also the unfiltered P (for the sampling pdf).
    template <bool kUnfiltered>
    GlintSdfPair evaluate(const Dictionary& dict, const GlintShape& shape, Vec2 mh, float pB, bool ggaa, Vec2 gx,
                          Vec2 gy) const {
        GlintSdfPair r;
        if (!footprintValid) {
            r.filtered = r.unfiltered = pB;
            return r;
        }
        const float lim = float(4.0 * kSigmaO);
        // Whole-query early-out: max(|m.x|, |m.y|) >= |m| / sqrt(2) = |mh| / sqrt(2) in every rotation, so when
        // |mh|^2 >= 2 lim^2 every dictionary cell is zeroed by S4.8 and only the converged cells remain.
        // The 1e-5 margin covers the rounding of the rotation, so skipping is exact.
        const bool dictionaryZero = !(glm::dot(mh, mh) < 2.00002f * lim * lim);
        const float* base = dict.data().data();
        float levelF[2] = {0.f, 0.f}, levelU[2] = {0.f, 0.f};
        for (int lev = 0; lev < levels; ++lev) {
            const int begin = lev == 0 ? 0 : levelEnd[0], end = levelEnd[lev];
            // Pass 1: rotation, the S4.8 test, and the support test (a lookup that reads only zero texels is 0; with
            // GGAA only where the kernel is under one texel, rho <= 1, so MIP 0 is what is read). The surviving
            // cells' texels are prefetched: the rows (1.5 MB in all) are read at random, so the lookups are bound by
            // memory latency, not arithmetic. Order is kept: the sums below add the same terms as levelSdf.
            struct Lookup {
                int cell;
                float ux, uy, rhoX, rhoY;
                bool outX, outY;  // the axis's MIP-0 lookup reads only zeros
            };
            Lookup live[kCellCap];
            int nLive = 0;
            for (int n = begin; n < end; ++n) {
                const GlintCell& c = cells[n];
                if (c.rowX == GlintCell::kConverged) {
                    live[nLive++] = {n, 0.f, 0.f, 0.f, 0.f, false, false};
                    continue;
                }
                if (dictionaryZero) continue;
                const float mx = c.cosT * mh.x + c.sinT * mh.y, my = -c.sinT * mh.x + c.cosT * mh.y;
                if (std::abs(mx) >= lim || std::abs(my) >= lim) continue;  // S4.8
                const float ux = std::abs(mx) / lim, uy = std::abs(my) / lim;
                const bool outX = lookupOutsideSupport(ux, c.loX, c.hiX), outY = lookupOutsideSupport(uy, c.loY, c.hiY);
                float rhoX = 0.f, rhoY = 0.f;
                if (ggaa) {
                    // GGAA (S5.3-S5.4): kernel s_K Rot(-theta) M^-1 d / (4 sigma_o), x components to the x marginal.
                    const float gxx = c.cosT * gx.x + c.sinT * gx.y, gxy = -c.sinT * gx.x + c.cosT * gx.y;
                    const float gyx = c.cosT * gy.x + c.sinT * gy.y, gyy = -c.sinT * gy.x + c.cosT * gy.y;
                    rhoX = float(kRes) * std::max(std::abs(gxx), std::abs(gyx));
                    rhoY = float(kRes) * std::max(std::abs(gxy), std::abs(gyy));
                }
                // Filtered and unfiltered products are both 0 when one axis reads only zeros at MIP 0 with rho <= 1.
                if ((outX && !(rhoX > 1.f)) || (outY && !(rhoY > 1.f))) continue;
                live[nLive++] = {n, ux, uy, rhoX, rhoY, outX, outY};
                __builtin_prefetch(base + size_t(c.rowX) * kRowFloats + int(ux * float(kRes)));
                __builtin_prefetch(base + size_t(c.rowY) * kRowFloats + int(uy * float(kRes)));
            }
            float sumF = 0.f, sumU = 0.f;
            for (int n = 0; n < nLive; ++n) {
                const Lookup& lk = live[n];
                const GlintCell& c = cells[lk.cell];
                if (c.rowX == GlintCell::kConverged) {  // S4.6
                    sumF += c.weight * pB;
                    if constexpr (kUnfiltered) sumU += c.weight * pB;
                    continue;
                }
                const bool outX = lk.outX, outY = lk.outY;
                const float ux = lk.ux, uy = lk.uy;
                const float* rx = base + size_t(c.rowX) * kRowFloats;
                const float* ry = base + size_t(c.rowY) * kRowFloats;
                const float px = outX ? 0.f : sampleLinear(rx, kRes, ux);
                if (!ggaa) {
                    if (px == 0.f) continue;
                    const float v = shape.detMinv * px * sampleLinear(ry, kRes, uy);  // C21 Eq. 4
                    sumF += c.weight * v;
                    if constexpr (kUnfiltered) sumU += c.weight * v;
                    continue;
                }
                // A kernel under one texel (rho <= 1) reads MIP 0 as the unfiltered lookup does: reuse that value.
                const float pxF = lk.rhoX > 1.f ? textureGradFiltered(rx, ux, lk.rhoX) : px;
                if (pxF == 0.f && px == 0.f) continue;
                const float py = outY ? 0.f : sampleLinear(ry, kRes, uy);
                const float pyF = lk.rhoY > 1.f ? textureGradFiltered(ry, uy, lk.rhoY) : py;
                sumF += c.weight * (shape.detMinv * pxF * pyF);  // C21 Eq. 15
                if constexpr (kUnfiltered) sumU += c.weight * (shape.detMinv * px * py);
            }
            levelF[lev] = sumW[lev] > 0.f ? sumF / sumW[lev] : 0.f;
            levelU[lev] = sumW[lev] > 0.f ? sumU / sumW[lev] : 0.f;
        }
        if (levels == 2) {  // S2 LOD blend, as patchSdf
            r.filtered = (1.f - blend) * levelF[0] + blend * levelF[1];
            r.unfiltered = (1.f - blend) * levelU[0] + blend * levelU[1];
        } else {
            r.filtered = levelF[0];
            r.unfiltered = levelU[0];
        }
        if (!kUnfiltered) r.unfiltered = 0.f;
        return r;
    }

    // Draws a half slope h~ with density P_unfiltered(h~) / keptWeight (spec S4.7 inverted): a cell with probability
    // w_c / keptWeight (both LODs at once: the blend weight is part of w_c), then m in the cell's space from the two 1D
    // marginals by inverse CDF (density p_i(|m.x|) p_j(|m.y|) with a random sign per axis), h~ = M_c m = M Rot(theta) m,
    // whose density is |det M_c^-1| p_i p_j = the cell's SDF; converged cells draw from P_B. u in [0,1)^2; u.x is
    // reused (rescaled) for the cell choice and the x marginal, u.y for the y marginal.
    bool sampleSlope(const Dictionary& dict, const GlintShape& shape, Vec2 u, Vec2& slope) const;

private:
    void addLevel(CellMemo& memo, const uint8_t* support, const GlintParams& p, int l, Vec2 uv, const Footprint& fp) {
        const float lc = p.logDensity / 1.38629436f - float(kLevels - 1) + float(l);  // S4.4
        float sw = 0.f;
        forEachCell(l, uv, fp.a1, fp.a2, [&](int s, int t, float W) {
            sw += W;
            const CellMemoEntry& r = memo.get(cellSeed(l, s, t));
            if (r.uA > p.relArea) return;  // empty cell: it only normalises
            const int k = dictionaryLod(lc, p.jitter, r.erfZ);
            GlintCell& c = cells[count++];
            c.weight = W;
            if (k == kLevels) {
                c.rowX = c.rowY = GlintCell::kConverged;
                return;
            }
            c.cosT = r.cosT;
            c.sinT = r.sinT;
            c.rowX = uint16_t(k * kMarginals + r.i);
            c.rowY = uint16_t(k * kMarginals + r.j);
            c.loX = support[2 * c.rowX], c.hiX = support[2 * c.rowX + 1];
            c.loY = support[2 * c.rowY], c.hiY = support[2 * c.rowY + 1];
        });
        sumW[levels] = sw;
        levelEnd[levels++] = count;
    }
};

// Half slope from the limiting correlated Beckmann lobe N(0, Sigma) (C21 Eq. 16): h~ = L z with L the Cholesky factor
// [[sx, 0], [rho sy, sy sqrt(1-rho^2)]] and z from Box-Muller; its density is P_B(h~).
inline Vec2 sampleBeckmannSlope(const GlintShape& s, const Vec2& u) {
    const float r = std::sqrt(-2.f * std::log(std::max(1.f - u.x, 1e-12f)));
    const float phi = 2.f * kPi * u.y;
    const float z1 = r * std::cos(phi), z2 = r * std::sin(phi);
    return {s.sx * z1, s.sy * (s.rho * z1 + s.sq * z2)};
}

// Splits a uniform u in [0,1) at 1/2 into a sign and a fresh uniform in [0,1).
inline float splitSign(float& u) {
    const float v = u * 2.f;
    if (v < 1.f) {
        u = v;
        return 1.f;
    }
    u = std::min(v - 1.f, 0.99999994f);
    return -1.f;
}

inline bool GlintCellSet::sampleSlope(const Dictionary& dict, const GlintShape& shape, Vec2 u, Vec2& slope) const {
    if (!(keptWeight > 0.f)) return false;
    if (!footprintValid) {
        slope = sampleBeckmannSlope(shape, u);
        return true;
    }
    float r = u.x * keptWeight;
    int n = 0, last = -1;
    float w = 0.f;
    for (; n < count; ++n) {  // rounding: the last cell with weight takes the rest
        if (!(sumW[n < levelEnd[0] ? 0 : 1] > 0.f)) continue;
        w = normalisedWeight(n);
        last = n;
        if (r < w) break;
        r -= w;
    }
    if (last < 0) return false;
    if (n == count) n = last;
    const GlintCell& c = cells[n];
    u.x = std::clamp(r / w, 0.f, 0.99999994f);
    if (c.rowX == GlintCell::kConverged) {
        slope = sampleBeckmannSlope(shape, u);
        return true;
    }
    const float sx = splitSign(u.x), sy = splitSign(u.y);
    const int kx = c.rowX / kMarginals, ky = c.rowY / kMarginals;
    const float mx = sx * dict.sampleMarginal(kx, c.rowX - kx * kMarginals, u.x);
    const float my = sy * dict.sampleMarginal(ky, c.rowY - ky * kMarginals, u.y);
    // mh = Rot(theta) m, h~ = M mh with M = (1/sigma_o) [[sx sqrt(1-rho^2), rho sx], [0, sy]] (C21 Eq. 18).
    const float ax = c.cosT * mx - c.sinT * my, ay = c.sinT * mx + c.cosT * my;
    const float so = float(kSigmaO);
    slope = Vec2((shape.sx * shape.sq * ax + shape.rho * shape.sx * ay) / so, shape.sy * ay / so);
    return true;
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

// One query against the cells of its shading point: f cos without Fresnel (GGAA-filtered P when GGAA is on) and,
// for the sampling pdf, the unfiltered P and P_B at the same half vector.
struct GlintQueryValue {
    bool valid = false;  // h passed S0 (wo.z, wi.z, h.z, wo.h > 0)
    Vec3 h{0.f};
    float woh = 0.f;
    float fcos = 0.f;         // G D / (4 wo.z)
    float pUnfiltered = 0.f;  // unfiltered patch SDF at h~ (only with wantPdf)
    float pB = 0.f;           // P_B(h~)
};
template <bool kWantPdf>
inline GlintQueryValue glintQuery(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                                  const GlintEvalInputs& in, const GlintCellSet& cells, const Vec3& wo, const Vec3& wi,
                                  float lightDistance) {
    GlintQueryValue v;
    if (wo.z <= 0.f || wi.z <= 0.f) return v;
    const Vec3 hs = wo + wi;
    const float len = std::sqrt(glm::dot(hs, hs));
    if (!(len > 0.f)) return v;
    const Vec3 h = hs / len;
    const float woh = glm::dot(wo, h), wih = glm::dot(wi, h);
    if (h.z <= 0.f || woh <= 0.f) return v;
    v.valid = true;
    v.h = h;
    v.woh = woh;
    const Vec2 slope(-h.x / h.z, -h.y / h.z);
    v.pB = beckmannSdf(slope, shape);
    if (wih <= 0.f && !kWantPdf) return v;
    Vec2 gx(0.f), gy(0.f);
    if (p.ggaa && wih > 0.f) {
        const float k = p.kernelScale / float(4.0 * kSigmaO);  // g = s_K M^-1 d / (4 sigma_o) (S5.2)
        gx = shape.applyInv(ggaaDerivative(in.diff, 0, p.mode, wo, wi, h, len, lightDistance)) * k;
        gy = shape.applyInv(ggaaDerivative(in.diff, 1, p.mode, wo, wi, h, len, lightDistance)) * k;
    }
    const GlintSdfPair P = cells.evaluate<kWantPdf>(dict, shape, shape.applyInv(slope), v.pB, p.ggaa, gx, gy);
    v.pUnfiltered = P.unfiltered;
    if (wih > 0.f) {
        const float hz2 = h.z * h.z;
        const float D = P.filtered / (hz2 * hz2);
        const float G = std::min(1.f, 2.f * h.z * wo.z / woh) * std::min(1.f, 2.f * h.z * wi.z / wih);
        v.fcos = G * D / (4.f * wo.z);
    }
    return v;
}

// One evaluation without a lobe (tests, bench, tools): the per-query pipeline, which for a single query is cheaper
// than building a GlintCellSet (the lobe's path, bit-identical: GlintCells tests).
inline float glintFCosScalar(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                             const GlintEvalInputs& in, const Vec3& wo, const Vec3& wi, Vec3* hOut = nullptr,
                             float lightDistance = std::numeric_limits<float>::infinity());

// The per-query pipeline of spec §3 as written (patchSdf over cellSdf for every query): the reference the cell set is
// tested against, and the bench's "per query" baseline.
inline float glintFCosReference(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                                const GlintEvalInputs& in, const Vec3& wo, const Vec3& wi,
                                float lightDistance = std::numeric_limits<float>::infinity(), Vec3* hOut = nullptr) {
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
    const float P = patchSdf(q, in.uv, footprint(in.duvdx, in.duvdy, p.maxAniso));
    const float hz2 = h.z * h.z;
    const float D = P / (hz2 * hz2);
    const float G = std::min(1.f, 2.f * h.z * wo.z / woh) * std::min(1.f, 2.f * h.z * wi.z / wih);
    return G * D / (4.f * wo.z);
}

// The lobe's path for one query: builds the cells and answers one query (tests compare it with the reference).
inline float glintFCosCells(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                            const GlintEvalInputs& in, const Vec3& wo, const Vec3& wi,
                            float lightDistance = std::numeric_limits<float>::infinity()) {
    if (wo.z <= 0.f || wi.z <= 0.f) return 0.f;
    GlintCellSet cells;
    cells.build(dict, p, in.uv, footprint(in.duvdx, in.duvdy, p.maxAniso));
    return glintQuery<false>(dict, p, shape, in, cells, wo, wi, lightDistance).fcos;
}

inline float glintFCosScalar(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                             const GlintEvalInputs& in, const Vec3& wo, const Vec3& wi, Vec3* hOut,
                             float lightDistance) {
    return glintFCosReference(dict, p, shape, in, wo, wi, lightDistance, hOut);
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

// Fraction of the lobe's samples drawn from the limiting Beckmann lobe instead of the glints. It keeps the pdf > 0
// wherever the eval can be > 0: the GGAA-filtered P is nonzero where the unfiltered P (the glint sampling density)
// can be 0, and MIS needs pdf > 0 there to stay unbiased.
constexpr float kGlintBeckmannFraction = 0.15f;

// The glint lobe of the renderer: eval = F(wo.h) * f cos with the GGAA-filtered P. Sampling (issue 11 item 3): a
// mixture of the glint distribution of this shading point (GlintCellSet::sampleSlope) and, with probability
// kGlintBeckmannFraction, the limiting Beckmann lobe. Exact pdf, with dw_h = d(slope) h_z^3 (D h_z dw_h = P22 d(slope))
// and dw_i = 4 (wo.h) dw_h:
//   pdf(wi) = [beta P_B(h~) + (1 - beta) P_unfiltered(h~) / keptWeight] / h_z^3 / (4 wo.h).
// The cells are built on the first query and shared by every later query of the shading point (the lobe lives in
// one thread's scratch arena for one shading point).
class GlintLobe final : public BsdfLobe {
public:
    GlintLobe(const Dictionary& dict, const GlintParams& p, const GlintEvalInputs& in, const Fresnel& fresnel)
        : dict_(dict), p_(p), shape_(GlintShape::make(p.sigmaX, p.sigmaY, p.rho)), in_(in), fresnel_(fresnel) {}
    LobeKind kind() const override { return LobeKind::Specular; }
    using BsdfLobe::sample;
    LobeValue evalPdf(const LobeQuery& q) const override {
        LobeValue v;
        const GlintCellSet& c = cells();
        const GlintQueryValue g = glintQuery<true>(dict_, p_, shape_, in_, c, q.wo, q.wi, q.lightDistance);
        if (!g.valid) return v;
        if (g.fcos > 0.f) v.f = fresnel_.eval(g.woh) * g.fcos;
        const float beta = beckmannFraction();
        const float glint = c.keptWeight > 0.f ? g.pUnfiltered / c.keptWeight : 0.f;
        v.pdf = (beta * g.pB + (1.f - beta) * glint) / (g.h.z * g.h.z * g.h.z * 4.f * g.woh);
        return v;
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        const Vec3& wo = q.wo;
        if (wo.z <= 0.f) return false;
        const float beta = beckmannFraction();
        Vec2 uu = u, slope;
        if (uu.x < beta) {
            uu.x = std::min(uu.x / beta, 0.99999994f);
            slope = sampleBeckmannSlope(shape_, uu);
        } else {
            uu.x = std::min((uu.x - beta) / (1.f - beta), 0.99999994f);
            if (!cells().sampleSlope(dict_, shape_, uu, slope)) return false;
        }
        const Vec3 h = glm::normalize(Vec3(-slope.x, -slope.y, 1.f));
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
    // The footprint's cells (built on first use): shared with the area-light integral of the same shading point.
    const GlintCellSet& cells() const {
        if (!cellsBuilt_) {
            cells_.build(dict_, p_, in_.uv, footprint(in_.duvdx, in_.duvdy, p_.maxAniso));
            cellsBuilt_ = true;
        }
        return cells_;
    }
    // The mixture weight of the Beckmann lobe: kGlintBeckmannFraction, or 1 when every cell is empty or glint
    // sampling is off.
    float beckmannFraction() const {
        return p_.sampleGlints && cells().keptWeight > 0.f ? kGlintBeckmannFraction : 1.f;
    }

private:
    const Dictionary& dict_;
    GlintParams p_;
    GlintShape shape_;
    GlintEvalInputs in_;
    Fresnel fresnel_;
    mutable bool cellsBuilt_ = false;
    mutable GlintCellSet cells_;
};

}  // namespace specula::glint
