// A host-built RGBA MIP chain filtered by the GL rules step for step (bilinear per level, trilinear at an explicit
// LOD, EXT_texture_filter_anisotropic probes): the chain a texture node uploads to its GLSL sampler and its CPU twin.
#pragma once

#include "core/math/math.h"
#include "core/texture/pyramid.h"
#include "core/texture/texture_store.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace specula {

// Footprints within this fraction of isotropic take one anisotropic probe: derivative sources that differ by rounding
// (the CPU's quad partners, a GPU's dFdx) must not flip a camera-facing surface between one probe at λ and two at λ − 1.
inline constexpr float kGlAnisoRatioSlack = 1e-3f;
inline constexpr int kGlMaxAnisotropy = 16;

// EXT_texture_filter_anisotropic's probe count N = min(ceil(Pmax/Pmin - slack), maxAniso), at least 1 (Pmin = 0:
// maxAniso). Shared by GlMipChain::anisotropic and LeanPyramid::lookup; image.glsl and lean.glsl repeat it.
inline int anisotropicProbeCount(float pmax, float pmin, int maxAniso) {
    const int n = pmin > 0.f ? int(std::min(std::ceil(pmax / pmin - kGlAnisoRatioSlack), float(maxAniso))) : maxAniso;
    return std::max(1, n);
}

class GlMipChain {
public:
    // Level 0 from 'rgba' (width x height, rows bottom-up: v = 0 is the bottom row, OpenGL convention); each further
    // level is GL's 2x2 box of the one above (PyramidReduction::GlBox: sizes max(1, n >> 1), an odd last row or
    // column averaged into its neighbour's texel).
    static GlMipChain build(int width, int height, std::vector<float> rgba);

    int levels() const { return pyramid_.levels(); }
    // Level l's texels: 4 floats (RGBA) each.
    const PyramidLevel& level(int l) const { return pyramid_.level(l); }

    // GL_LINEAR on level l at uv (texel centres at (i + 0.5) / n), the wrap applied to the texel indices.
    Vec4 bilinear(int l, Vec2 uv, TextureWrap wrap) const;
    // GL_LINEAR_MIPMAP_LINEAR at LOD λ: level 0 for λ <= 0, the last level past it, else levels floor(λ) and
    // floor(λ) + 1 blended by frac(λ).
    Vec4 trilinear(float lambda, Vec2 uv, TextureWrap wrap) const;
    // EXT_texture_filter_anisotropic's reference: N = min(ceil(Pmax/Pmin - slack), 16) trilinear probes at
    // λ = log2(Pmax / N), spaced evenly along the footprint's major axis (Pmax, Pmin: the axes' lengths in level-0
    // texels), equally weighted. Zero footprint: bilinear on level 0.
    Vec4 anisotropic(Vec2 uv, Vec2 duvdx, Vec2 duvdy, TextureWrap wrap) const;

private:
    Pyramid pyramid_;
};

}  // namespace specula
