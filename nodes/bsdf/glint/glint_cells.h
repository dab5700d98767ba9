// The cells of one shading point (spec S1-S4; C20 Eq. 3 / Alg. 3, C21 Eqs. 4, 10, 15): the pixel footprint and its
// LOD, the EWA weights of the cells it covers, and the cell set that answers every query of the shading point.
#pragma once

#include "nodes/bsdf/glint/glint_correlation.h"
#include "nodes/bsdf/glint/glint_counting.h"
#include "nodes/bsdf/glint/glint_lookup.h"
#include "nodes/bsdf/glint/glint_params.h"

#include <atomic>
#include <cstdint>

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
struct GlintCell {
    float weight;         // W_c (EWA weight, unnormalised)
    float cosT, sinT;     // Rot(theta_c), theta_c = 2 pi u_theta
    uint16_t rowX, rowY;  // k_c * N + i_c and k_c * N + j_c: the dictionary rows; rowX = kConverged: k = L (P_B)
    uint8_t loX, hiX, loY, hiY;  // the rows' nonzero MIP-0 texels (rowSupport)
    static constexpr uint16_t kConverged = 0xffff;
};

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

}  // namespace specula::glint
