// The cells of one shading point (spec S1-S4; C20 Eq. 3 / Alg. 3, C21 Eqs. 4, 10, 15): the pixel footprint and its
// LOD, the EWA weights of the cells it covers, and the cell set that answers every query of the shading point.
#pragma once

#include "nodes/bsdf/glint/glint_correlation.h"
#include "nodes/bsdf/glint/glint_counting.h"
#include "nodes/bsdf/glint/glint_lookup.h"
#include "nodes/bsdf/glint/glint_params.h"

#include <algorithm>
#include <atomic>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace specula::glint {

constexpr int kCellCap = 100;  // the GLSL's cap on evaluated cells per LOD (spec §3 S3); hits are counted
std::atomic<uint64_t>& cellCapHits();

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

// ---- The cells of one shading point (wi-independent work, done once per lobe) -----------------------------------
// Which cells the footprint covers, their EWA weights W, the LOD blend, and each cell's random numbers (u_A, k, theta,
// i, j) depend on uv and the footprint only, not on wi. A shading point asks several queries (one per light, the BSDF
// sample, its MIS evaluation), so the lobe computes them once and each query is one pass over the stored cells:
// per level, sum_c W_c P_c(h~) / sum_c W_c over the visited cells (S3.6), then the LOD blend (S2). The sums run over
// the same terms in the same order as levelSdf/patchSdf (empty cells and cells zeroed by S4.8 add an exact 0), so
// the result is bit-identical to the per-query pipeline. Sampling uses the normalised weights
// w_c = (blend weight) W_c / sum_level W of the non-empty cells.
//
// Layout (issue 37 item 3): structure of arrays, each level's cells starting at a multiple of kLanes, so a query
// (rotation, S4.8, the support test, the GGAA kernel size, the lookups, the terms) runs kLanes cells at a time
// (levelSums). It does the same float operations per cell as the scalar code (mul, add, abs, div, compare; no FMA, no
// reciprocal), so every CPU gets the same bits, with or without SSE2. Padding lanes are dead (cos = sin = 0 rotates
// to m = 0, an empty support [lo, hi] = [kRes, -1] rejects every lookup, rho = 0).

// The two SDFs one query needs: the GGAA-filtered one (what eval returns) and the unfiltered one (the density the
// glint sampler draws from); equal when GGAA is off.
struct GlintSdfPair {
    float filtered = 0.f, unfiltered = 0.f;
};

struct GlintCellSet {
    static constexpr int kLanes = 4;                                 // cells per step of a query
    static constexpr int kLevelCapacity = (kCellCap + kLanes - 1) / kLanes * kLanes;  // forEachCell's cap, padded
    static constexpr int kMaxCells = 2 * kLevelCapacity;             // two LODs
    static constexpr int16_t kConverged = -1;  // rowX of a cell with k = L (analytic P_B, S4.6)
    bool footprintValid = false;  // false: |a2| = 0, P = P_B (spec S1 recommendation)
    int count = 0;                // non-empty cells (dictionary and converged) of both levels
    int levels = 0;               // 1 or 2 LODs
    int levelBegin[2] = {0, 0};   // cells of level n: [levelBegin[n], levelEnd[n]); levelBegin[n] % kLanes == 0
    int levelEnd[2] = {0, 0};
    float sumW[2] = {0.f, 0.f};   // sum of W over every visited cell of the level (empty ones included)
    float blend = 0.f;            // w: P = (1 - w) P_lev(i0) + w P_lev(i0 + 1)
    float convergedWeight = 0.f;  // sum of the normalised weights of the converged cells
    float keptWeight = 0.f;       // sum of all normalised weights = the integral of the unfiltered P (spec §4.6)
    // Per cell, left uninitialised until build(): W_c (EWA weight, unnormalised), its normalised sampling weight
    // (0 when sum W of its level is 0), Rot(theta_c) with theta_c = 2 pi u_theta, the dictionary rows k_c N + i_c and
    // k_c N + j_c (kConverged: k = L), and the rows' nonzero MIP-0 texels [lo, hi] (rowSupport).
    alignas(16) float weight[kMaxCells];
    alignas(16) float sampleWeight[kMaxCells];
    alignas(16) float cosT[kMaxCells];
    alignas(16) float sinT[kMaxCells];
    alignas(16) int16_t rowX[kMaxCells];
    alignas(16) int16_t rowY[kMaxCells];
    alignas(16) int16_t loX[kMaxCells];
    alignas(16) int16_t hiX[kMaxCells];
    alignas(16) int16_t loY[kMaxCells];
    alignas(16) int16_t hiY[kMaxCells];

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
        for (int lev = 0; lev < levels; ++lev) {
            // (blend weight of the level) W / sum W, in cell order as the sampler walks them.
            const float levelWeight = lev == 0 ? (levels == 2 ? 1.f - blend : 1.f) : blend;
            const bool normalises = sumW[lev] > 0.f;
            for (int n = levelBegin[lev]; n < levelEnd[lev]; ++n) {
                sampleWeight[n] = 0.f;
                if (!normalises) continue;
                const float w = levelWeight * weight[n] / sumW[lev];
                sampleWeight[n] = w;
                keptWeight += w;
                if (rowX[n] == kConverged) convergedWeight += w;
            }
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
            float sumF = 0.f, sumU = 0.f;
            levelSums<kUnfiltered>(base, lev, shape.detMinv, mh, pB, ggaa, gx, gy, dictionaryZero, sumF, sumU);
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
    // sum_c W_c P_c of the cells of level lev, filtered and (kUnfiltered) unfiltered, in cell order (S3.6).
    template <bool kUnfiltered>
    void levelSums(const float* base, int lev, float detMinv, Vec2 mh, float pB, bool ggaa, Vec2 gx, Vec2 gy,
                   bool dictionaryZero, float& sumF, float& sumU) const;

    void addLevel(CellMemo& memo, const uint8_t* support, const GlintParams& p, int l, Vec2 uv, const Footprint& fp) {
        const float lc = p.logDensity / 1.38629436f - float(kLevels - 1) + float(l);  // S4.4
        float sw = 0.f;
        const int begin = levels == 0 ? 0 : (levelEnd[0] + kLanes - 1) / kLanes * kLanes;
        int end = begin;
        forEachCell(l, uv, fp.a1, fp.a2, [&](int s, int t, float W) {
            sw += W;
            const CellMemoEntry& r = memo.get(cellSeed(l, s, t));
            if (r.uA > p.relArea) return;  // empty cell: it only normalises
            const int k = dictionaryLod(lc, p.jitter, r.erfZ);
            const int n = end++;
            weight[n] = W;
            if (k == kLevels) {
                rowX[n] = rowY[n] = kConverged;
                cosT[n] = sinT[n] = 0.f;
                loX[n] = loY[n] = 0, hiX[n] = hiY[n] = int16_t(kRes - 1);
                return;
            }
            cosT[n] = r.cosT;
            sinT[n] = r.sinT;
            const int rx = k * kMarginals + r.i, ry = k * kMarginals + r.j;
            rowX[n] = int16_t(rx);
            rowY[n] = int16_t(ry);
            loX[n] = support[2 * rx], hiX[n] = support[2 * rx + 1];
            loY[n] = support[2 * ry], hiY[n] = support[2 * ry + 1];
        });
        for (int n = end; n % kLanes != 0; ++n) {  // dead padding lanes (see the layout note above)
            weight[n] = 0.f;
            cosT[n] = sinT[n] = 0.f;
            rowX[n] = rowY[n] = 0;
            loX[n] = loY[n] = int16_t(kRes), hiX[n] = hiY[n] = -1;
        }
        count += end - begin;
        sumW[levels] = sw;
        levelBegin[levels] = begin;
        levelEnd[levels++] = end;
    }
};

// One query's sums over the cells of level lev, kLanes cells at a time, in one pass without compaction (about three
// quarters of the cells survive S4.8 and the support test in the renders, so gathering the survivors first cost
// more than it saved). Per cell, exactly the scalar operations of the per-query pipeline (cellSdf): m = Rot(-theta)
// mh, S4.8, u = |m| / (4 sigma_o), the MIP-0 texel pair of u against the row's support (a lookup that reads only
// zero texels is 0), the GGAA kernel Rot(-theta) g scaled to texels rho (S5.2-S5.4), the MIP-0 lookups
// (sampleLinear) and where rho > 1 the filtered ones (textureGradFiltered: the MIP from the library's log2, whose
// bits decide the blend), then the term W (detMinv px py) (C21 Eq. 4 and Eq. 15; a converged cell's is W P_B, S4.6).
// A cell the per-query pipeline skips (zeroed by S4.8, an axis reading only zeros under a kernel of at most one
// texel, a dead padding lane) adds an exact +0, which leaves the sums, added lane by lane in cell order, unchanged.
// Every float operation is the scalar one (mul, add, sub, div, compare; no FMA, no reciprocal), so every CPU gets the
// same bits with or without SSE2. Texels are gathered by scalar loads; a lane that must not read reads texel 0.
template <bool kUnfiltered>
inline void GlintCellSet::levelSums(const float* base, int lev, float detMinv, Vec2 mh, float pB, bool ggaa, Vec2 gx,
                                    Vec2 gy, bool dictionaryZero, float& sumF, float& sumU) const {
    const int begin = levelBegin[lev], end = levelEnd[lev];
    const float lim = float(4.0 * kSigmaO);
    float sf = 0.f, su = 0.f;
#if defined(__SSE2__)
    const int endPadded = (end + kLanes - 1) / kLanes * kLanes;
    const __m128 vmhx = _mm_set1_ps(mh.x), vmhy = _mm_set1_ps(mh.y);
    const __m128 vgxx = _mm_set1_ps(gx.x), vgxy = _mm_set1_ps(gx.y), vgyx = _mm_set1_ps(gy.x), vgyy = _mm_set1_ps(gy.y);
    const __m128 vlim = _mm_set1_ps(lim), vres = _mm_set1_ps(float(kRes)), vhalf = _mm_set1_ps(0.5f);
    const __m128 vone = _mm_set1_ps(1.f), vzero = _mm_setzero_ps(), vpB = _mm_set1_ps(pB);
    const __m128 vdet = _mm_set1_ps(detMinv), vlastMip = _mm_set1_ps(float(kMips - 1));
    const __m128 absMask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 signMask = _mm_castsi128_ps(_mm_set1_epi32(int(0x80000000u)));
    const __m128 allOnes = _mm_castsi128_ps(_mm_set1_epi32(-1));
    const __m128i vlast = _mm_set1_epi32(kRes - 1), vconv = _mm_set1_epi32(kConverged), izero = _mm_setzero_si128();
    const __m128i ione = _mm_set1_epi32(1), vstride = _mm_set1_epi32(kRowFloats), i128 = _mm_set1_epi32(2 * kRes);
    const auto load4 = [](const int16_t* p) {  // 4 int16 -> 4 int32, sign-extended
        const __m128i v = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(p));
        return _mm_srai_epi32(_mm_unpacklo_epi16(v, v), 16);
    };
    const auto mul = [](__m128i a, __m128i b) {  // 32-bit products of small non-negative values (SSE2)
        const __m128i even = _mm_mul_epu32(a, b), odd = _mm_mul_epu32(_mm_srli_epi64(a, 32), _mm_srli_epi64(b, 32));
        return _mm_unpacklo_epi32(_mm_shuffle_epi32(even, _MM_SHUFFLE(0, 0, 2, 0)),
                                  _mm_shuffle_epi32(odd, _MM_SHUFFLE(0, 0, 2, 0)));
    };
    // floor(t) as truncation corrected by one where the truncation rounded up (t < 0), exact for |t| < 2^31
    const auto floorInt = [](__m128 t) {
        const __m128i i = _mm_cvttps_epi32(t);
        return _mm_add_epi32(i, _mm_castps_si128(_mm_cmplt_ps(t, _mm_cvtepi32_ps(i))));
    };
    const auto minInt = [](__m128i a, __m128i b) {
        const __m128i big = _mm_cmpgt_epi32(a, b);
        return _mm_or_si128(_mm_andnot_si128(big, a), _mm_and_si128(big, b));
    };
    // sampleLinear on n texels at offset (row + MIP offset) for u in [0, 1): (1 - f) tex[max(i0, 0)] + f tex[min(i0 + 1,
    // n - 1)] with i0 = floor(u n - 1/2); lanes of skip read texel 0 of the table and return +0.
    const auto linear = [&](__m128 u, __m128 n, __m128i offset, __m128i skip) {
        const __m128 t = _mm_sub_ps(_mm_mul_ps(u, n), vhalf);
        const __m128i i0 = floorInt(t);
        const __m128 f = _mm_sub_ps(t, _mm_cvtepi32_ps(i0));
        const __m128i a = _mm_and_si128(i0, _mm_cmpgt_epi32(i0, izero));
        const __m128i b = minInt(_mm_add_epi32(i0, ione), _mm_sub_epi32(_mm_cvttps_epi32(n), ione));
        alignas(16) int32_t ia[kLanes], ib[kLanes];
        _mm_store_si128(reinterpret_cast<__m128i*>(ia), _mm_andnot_si128(skip, _mm_add_epi32(offset, a)));
        _mm_store_si128(reinterpret_cast<__m128i*>(ib), _mm_andnot_si128(skip, _mm_add_epi32(offset, b)));
        const __m128 ta = _mm_setr_ps(base[ia[0]], base[ia[1]], base[ia[2]], base[ia[3]]);
        const __m128 tb = _mm_setr_ps(base[ib[0]], base[ib[1]], base[ib[2]], base[ib[3]]);
        const __m128 v = _mm_add_ps(_mm_mul_ps(_mm_sub_ps(vone, f), ta), _mm_mul_ps(f, tb));
        return _mm_andnot_ps(_mm_castsi128_ps(skip), v);
    };
    // textureGradFiltered for the lanes of use (rho > 1): mu = min(log2 rho, 6), m0 = floor(mu) (mu > 0), blend weight
    // of MIP m0 + 1 mu - m0 below MIP 6 (else MIP m0 alone, as textureGradFiltered returns v0 without reading MIP 7).
    // MIP m has 2^(6 - m) texels at offset 128 - 2^(7 - m).
    const auto filtered = [&](__m128 u, __m128 rho, __m128i row, __m128 use) {
        alignas(16) float r[kLanes], lg[kLanes];
        _mm_store_ps(r, rho);
        const int bits = _mm_movemask_ps(use);
        for (int k = 0; k < kLanes; ++k) lg[k] = (bits >> k) & 1 ? std::log2(r[k]) : 1.f;
        const __m128 mu = _mm_min_ps(_mm_load_ps(lg), vlastMip);  // std::min(log2, 6) for non-NaN log2
        const __m128i m0 = _mm_cvttps_epi32(mu);
        const __m128 m0f = _mm_cvtepi32_ps(m0);
        const __m128 below = _mm_cmplt_ps(m0f, vlastMip);
        const __m128 bf = _mm_and_ps(below, _mm_sub_ps(mu, m0f));
        const __m128 n0 = _mm_castsi128_ps(_mm_slli_epi32(_mm_sub_epi32(_mm_set1_epi32(127 + kMips - 1), m0), 23));
        const __m128 n1 = _mm_or_ps(_mm_andnot_ps(below, n0), _mm_and_ps(below, _mm_mul_ps(n0, vhalf)));
        const __m128i skip = _mm_castps_si128(_mm_andnot_ps(use, allOnes));
        const auto offset = [&](__m128 n) { return _mm_add_epi32(row, _mm_sub_epi32(i128, _mm_cvttps_epi32(_mm_add_ps(n, n)))); };
        const __m128 v0 = linear(u, n0, offset(n0), skip), v1 = linear(u, n1, offset(n1), skip);
        const __m128 mixed = _mm_add_ps(_mm_mul_ps(_mm_sub_ps(vone, bf), v0), _mm_mul_ps(bf, v1));
        const __m128 useMix = _mm_cmpgt_ps(bf, vzero);
        return _mm_or_ps(_mm_and_ps(useMix, mixed), _mm_andnot_ps(useMix, v0));
    };
    const auto outside = [&](__m128 u, __m128i lo, __m128i hi) {  // lookupOutsideSupport
        const __m128i i0 = floorInt(_mm_sub_ps(_mm_mul_ps(u, vres), vhalf));
        const __m128i a = minInt(_mm_add_epi32(i0, ione), vlast);
        const __m128i b = _mm_and_si128(i0, _mm_cmpgt_epi32(i0, izero));
        return _mm_or_si128(_mm_cmplt_epi32(a, lo), _mm_cmpgt_epi32(b, hi));
    };
    alignas(16) float tf[kLanes], tu[kLanes];
    for (int n = begin; n < endPadded; n += kLanes) {
        const __m128i rx = load4(rowX + n);
        const __m128i convI = _mm_cmpeq_epi32(rx, vconv);
        const __m128 W = _mm_load_ps(weight + n);
        const __m128 convTerm = _mm_and_ps(_mm_castsi128_ps(convI), _mm_mul_ps(W, vpB));  // S4.6
        __m128 termF = convTerm, termU = convTerm;
        if (!dictionaryZero) {
            const __m128 c = _mm_load_ps(cosT + n), s = _mm_load_ps(sinT + n), ns = _mm_xor_ps(s, signMask);
            const __m128 mx = _mm_add_ps(_mm_mul_ps(c, vmhx), _mm_mul_ps(s, vmhy));
            const __m128 my = _mm_add_ps(_mm_mul_ps(ns, vmhx), _mm_mul_ps(c, vmhy));
            const __m128 ax = _mm_and_ps(mx, absMask), ay = _mm_and_ps(my, absMask);
            const __m128 cut = _mm_or_ps(_mm_cmpge_ps(ax, vlim), _mm_cmpge_ps(ay, vlim));  // S4.8
            const __m128 ux = _mm_div_ps(ax, vlim), uy = _mm_div_ps(ay, vlim);
            const __m128 oX = _mm_castsi128_ps(outside(ux, load4(loX + n), load4(hiX + n)));
            const __m128 oY = _mm_castsi128_ps(outside(uy, load4(loY + n), load4(hiY + n)));
            __m128 rX = vzero, rY = vzero;
            if (ggaa) {  // S5.2-S5.4: kernel s_K Rot(-theta) M^-1 d / (4 sigma_o), x components to the x marginal
                const __m128 gxx = _mm_add_ps(_mm_mul_ps(c, vgxx), _mm_mul_ps(s, vgxy));
                const __m128 gxy = _mm_add_ps(_mm_mul_ps(ns, vgxx), _mm_mul_ps(c, vgxy));
                const __m128 gyx = _mm_add_ps(_mm_mul_ps(c, vgyx), _mm_mul_ps(s, vgyy));
                const __m128 gyy = _mm_add_ps(_mm_mul_ps(ns, vgyx), _mm_mul_ps(c, vgyy));
                // std::max(a, b) = a < b ? b : a = _mm_max_ps(b, a), NaN included
                rX = _mm_mul_ps(vres, _mm_max_ps(_mm_and_ps(gyx, absMask), _mm_and_ps(gxx, absMask)));
                rY = _mm_mul_ps(vres, _mm_max_ps(_mm_and_ps(gyy, absMask), _mm_and_ps(gxy, absMask)));
            }
            const __m128 filtX = _mm_cmpgt_ps(rX, vone), filtY = _mm_cmpgt_ps(rY, vone);
            const __m128 dead = _mm_or_ps(_mm_or_ps(cut, _mm_castsi128_ps(convI)),
                                          _mm_or_ps(_mm_andnot_ps(filtX, oX), _mm_andnot_ps(filtY, oY)));
            const __m128 live = _mm_andnot_ps(dead, allOnes);  // dictionary cells with a term
            if (_mm_movemask_ps(live) != 0) {
                const __m128i offX = mul(_mm_andnot_si128(convI, rx), vstride);  // k N + i < 2^15, >= 0 but kConverged
                const __m128i offY = mul(_mm_andnot_si128(convI, load4(rowY + n)), vstride);
                const __m128i deadI = _mm_castps_si128(dead);
                const __m128 px = linear(ux, vres, offX, _mm_or_si128(deadI, _mm_castps_si128(oX)));
                const __m128 py = linear(uy, vres, offY, _mm_or_si128(deadI, _mm_castps_si128(oY)));
                __m128 pxF = px, pyF = py;
                const __m128 useX = _mm_and_ps(live, filtX), useY = _mm_and_ps(live, filtY);
                if (_mm_movemask_ps(useX) != 0)
                    pxF = _mm_or_ps(_mm_and_ps(useX, filtered(ux, rX, offX, useX)), _mm_andnot_ps(useX, px));
                if (_mm_movemask_ps(useY) != 0)
                    pyF = _mm_or_ps(_mm_and_ps(useY, filtered(uy, rY, offY, useY)), _mm_andnot_ps(useY, py));
                // C21 Eq. 4 (GGAA off: pxF = px, pyF = py) and Eq. 15, as W * (detMinv * px * py)
                const __m128 f = _mm_mul_ps(W, _mm_mul_ps(_mm_mul_ps(vdet, pxF), pyF));
                termF = _mm_or_ps(convTerm, _mm_and_ps(live, f));
                if constexpr (kUnfiltered) {
                    const __m128 u = _mm_mul_ps(W, _mm_mul_ps(_mm_mul_ps(vdet, px), py));
                    termU = _mm_or_ps(convTerm, _mm_and_ps(live, u));
                }
            }
        }
        _mm_store_ps(tf, termF);
        sf += tf[0], sf += tf[1], sf += tf[2], sf += tf[3];
        if constexpr (kUnfiltered) {
            _mm_store_ps(tu, termU);
            su += tu[0], su += tu[1], su += tu[2], su += tu[3];
        }
    }
#else
    for (int n = begin; n < end; ++n) {
        const float W = weight[n];
        if (rowX[n] == kConverged) {  // S4.6
            sf += W * pB;
            su += W * pB;
            continue;
        }
        if (dictionaryZero) continue;
        const float c = cosT[n], s = sinT[n];
        const float mx = c * mh.x + s * mh.y, my = -s * mh.x + c * mh.y;
        if (std::abs(mx) >= lim || std::abs(my) >= lim) continue;  // S4.8
        const float ux = std::abs(mx) / lim, uy = std::abs(my) / lim;
        const bool outX = lookupOutsideSupport(ux, loX[n], hiX[n]), outY = lookupOutsideSupport(uy, loY[n], hiY[n]);
        float rX = 0.f, rY = 0.f;
        if (ggaa) {
            const float gxx = c * gx.x + s * gx.y, gxy = -s * gx.x + c * gx.y;
            const float gyx = c * gy.x + s * gy.y, gyy = -s * gy.x + c * gy.y;
            rX = float(kRes) * std::max(std::abs(gxx), std::abs(gyx));
            rY = float(kRes) * std::max(std::abs(gxy), std::abs(gyy));
        }
        if ((outX && !(rX > 1.f)) || (outY && !(rY > 1.f))) continue;
        const float* rowx = base + size_t(uint16_t(rowX[n])) * kRowFloats;
        const float* rowy = base + size_t(uint16_t(rowY[n])) * kRowFloats;
        const float px = outX ? 0.f : sampleLinear(rowx, kRes, ux), py = outY ? 0.f : sampleLinear(rowy, kRes, uy);
        const float pxF = rX > 1.f ? textureGradFiltered(rowx, ux, rX) : px;
        const float pyF = rY > 1.f ? textureGradFiltered(rowy, uy, rY) : py;
        sf += W * (detMinv * pxF * pyF);
        su += W * (detMinv * px * py);
    }
#endif
    sumF = sf;
    sumU = su;
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
    int n = -1, last = -1;
    float w = 0.f;
    for (int lev = 0; lev < levels && n < 0; ++lev) {  // rounding: the last cell with weight takes the rest
        if (!(sumW[lev] > 0.f)) continue;
        for (int c = levelBegin[lev]; c < levelEnd[lev]; ++c) {
            w = sampleWeight[c];
            last = c;
            if (r < w) {
                n = c;
                break;
            }
            r -= w;
        }
    }
    if (last < 0) return false;
    if (n < 0) n = last;
    u.x = std::clamp(r / w, 0.f, 0.99999994f);
    if (rowX[n] == kConverged) {
        slope = sampleBeckmannSlope(shape, u);
        return true;
    }
    const float sx = splitSign(u.x), sy = splitSign(u.y);
    const int rx = uint16_t(rowX[n]), ry = uint16_t(rowY[n]);
    const int kx = rx / kMarginals, ky = ry / kMarginals;
    const float mx = sx * dict.sampleMarginal(kx, rx - kx * kMarginals, u.x);
    const float my = sy * dict.sampleMarginal(ky, ry - ky * kMarginals, u.y);
    // mh = Rot(theta) m, h~ = M mh with M = (1/sigma_o) [[sx sqrt(1-rho^2), rho sx], [0, sy]] (C21 Eq. 18).
    const float ax = cosT[n] * mx - sinT[n] * my, ay = sinT[n] * mx + cosT[n] * my;
    const float so = float(kSigmaO);
    slope = Vec2((shape.sx * shape.sq * ax + shape.rho * shape.sx * ay) / so, shape.sy * ay / so);
    return true;
}

}  // namespace specula::glint
