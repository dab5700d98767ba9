// Reading the dictionary's rows as the GLSL's 1D textures do (spec S5.4): linear filtering between texel centres,
// mirrored repeat, textureGrad's MIP choice for the GGAA kernel (C21 Eq. 19), and each row's nonzero texel span.
#pragma once

#include "core/math/math.h"
#include "nodes/bsdf/glint/glint_dictionary.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace specula::glint {

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

// First and last nonzero MIP-0 texel of every dictionary row (2 bytes per row, rows of Dictionary::instance();
// another dictionary gets the full range 0..R-1). A low-k marginal is a few narrow lobes: most of its texels are 0.
const uint8_t* rowSupport(const Dictionary& dict);

// Whether the MIP-0 linear lookup at u in [0, 1) (sampleLinear: texels max(i0, 0) and min(i0 + 1, R - 1)) reads only
// zero texels of a row whose nonzero texels are [lo, hi]: then it returns exactly 0, without touching the row.
inline bool lookupOutsideSupport(float u, int lo, int hi) {
    const int i0 = int(std::floor(u * float(kRes) - 0.5f));
    return std::min(i0 + 1, kRes - 1) < lo || std::max(i0, 0) > hi;
}

}  // namespace specula::glint
