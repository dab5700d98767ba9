// The per-query pipeline of spec §3 as written (C20 Alg. 3 with the C21 matrix and GGAA): each query re-draws its
// cells' SDFs (C21 Eqs. 4, 15) and blends the LODs (C20 Eq. 3); the reference the lobe's cell set is tested against.
#pragma once

#include "nodes/bsdf/glint/glint_assembly.h"
#include "nodes/bsdf/glint/glint_cells.h"
#include "nodes/bsdf/glint/glint_ggaa.h"

#include <limits>

namespace specula::glint {

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
    HalfVector hv;
    if (!halfVector(wo, wi, hv) || hv.wih <= 0.f) return 0.f;
    const Vec3 h = hv.h;
    const float len = hv.len;
    if (hOut) *hOut = h;
    Vec2 dx(0.f), dy(0.f);
    if (p.ggaa) {
        dx = ggaaDerivative(in.diff, 0, p.mode, wo, wi, h, len, lightDistance);
        dy = ggaaDerivative(in.diff, 1, p.mode, wo, wi, h, len, lightDistance);
    }
    const SdfQuery q = makeQuery(dict, p, shape, h, dx, dy);
    return fCosFromSdf(patchSdf(q, in.uv, footprint(in.duvdx, in.duvdy, p.maxAniso)), hv, wo, wi);
}

inline float glintFCosScalar(const Dictionary& dict, const GlintParams& p, const GlintShape& shape,
                             const GlintEvalInputs& in, const Vec3& wo, const Vec3& wi, Vec3* hOut,
                             float lightDistance) {
    return glintFCosReference(dict, p, shape, in, wo, wi, lightDistance, hOut);
}

}  // namespace specula::glint
