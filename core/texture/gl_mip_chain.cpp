// GlMipChain: the GL filtering rules on a host-built MIP chain (gl_mip_chain.h). The GLSL twins (texture.image's
// spc_texture_image_filtered) run the same steps with textureLod, so both sides blend the same texels by the same LOD.
#include "core/texture/gl_mip_chain.h"

#include <algorithm>
#include <cmath>

namespace specula {
GlMipChain GlMipChain::build(int width, int height, std::vector<float> rgba) {
    GlMipChain c;
    c.pyramid_ = Pyramid::build(width, height, 4, std::move(rgba), PyramidReduction::GlBox);
    return c;
}

Vec4 GlMipChain::bilinear(int l, Vec2 uv, TextureWrap wrap) const {
    const PyramidLevel& L = pyramid_.level(l);
    const float s = texelCoordinate(uv.x * float(L.width) - 0.5f), t = texelCoordinate(uv.y * float(L.height) - 0.5f);
    const float fs = std::floor(s), ft = std::floor(t);
    const int i0 = int(fs), j0 = int(ft);
    const float a = s - fs, b = t - ft;
    const int xs[2] = {wrapTexelIndex(i0, L.width, wrap), wrapTexelIndex(i0 + 1, L.width, wrap)};
    const int ys[2] = {wrapTexelIndex(j0, L.height, wrap), wrapTexelIndex(j0 + 1, L.height, wrap)};
    const float wx[2] = {1.f - a, a}, wy[2] = {1.f - b, b};
    Vec4 r(0.f);
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            if (xs[i] < 0 || ys[j] < 0) continue;
            const float* p = &L.texels[(size_t(ys[j]) * L.width + xs[i]) * 4];
            r += Vec4(p[0], p[1], p[2], p[3]) * (wx[i] * wy[j]);
        }
    return r;
}

Vec4 GlMipChain::trilinear(float lambda, Vec2 uv, TextureWrap wrap) const {
    const int top = levels() - 1;
    if (!(lambda > 0.f)) return bilinear(0, uv, wrap);
    if (lambda >= float(top)) return bilinear(top, uv, wrap);
    const float fl = std::floor(lambda);
    const int l0 = int(fl);
    const float f = lambda - fl;
    Vec4 r = bilinear(l0, uv, wrap) * (1.f - f);
    if (f > 0.f) r += bilinear(l0 + 1, uv, wrap) * f;
    return r;
}

Vec4 GlMipChain::anisotropic(Vec2 uv, Vec2 duvdx, Vec2 duvdy, TextureWrap wrap) const {
    const Vec2 size(float(level(0).width), float(level(0).height));
    const Vec2 j1 = duvdx * size, j2 = duvdy * size;
    const float l1 = std::sqrt(glm::dot(j1, j1)), l2 = std::sqrt(glm::dot(j2, j2));
    const float pmax = std::max(l1, l2), pmin = std::min(l1, l2);
    if (!(pmax > 0.f)) return bilinear(0, uv, wrap);
    const int n = anisotropicProbeCount(pmax, pmin, kGlMaxAnisotropy);
    const Vec2 major = l1 >= l2 ? duvdx : duvdy;
    const float lambda = std::log2(pmax / float(n));
    Vec4 sum(0.f);
    for (int i = 0; i < n; ++i) {
        const float t = (float(i) + 0.5f) / float(n) - 0.5f;
        sum += trilinear(lambda, uv + major * t, wrap);
    }
    return sum / float(n);
}

}  // namespace specula
