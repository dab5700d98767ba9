// GlMipChain: the GL filtering rules on a host-built MIP chain (gl_mip_chain.h). The GLSL twins (texture.image's
// spc_texture_image_filtered) run the same steps with textureLod, so both sides blend the same texels by the same LOD.
#include "core/texture/gl_mip_chain.h"

#include <algorithm>
#include <cmath>

namespace specula {
namespace {

// Texel index i of a level n texels wide under the wrap mode; -1 for a black border.
int wrapIndex(int i, int n, TextureWrap wrap) {
    switch (wrap) {
        case TextureWrap::Clamp: return std::clamp(i, 0, n - 1);
        case TextureWrap::Mirror: {
            const int p = 2 * n;
            int m = i % p;
            if (m < 0) m += p;
            return m < n ? m : p - 1 - m;
        }
        case TextureWrap::Black: return i >= 0 && i < n ? i : -1;
        case TextureWrap::Repeat:
        default: {
            int m = i % n;
            return m < 0 ? m + n : m;
        }
    }
}

}  // namespace

GlMipChain GlMipChain::build(int width, int height, std::vector<float> rgba) {
    GlMipChain c;
    c.levels_.push_back({width, height, std::move(rgba)});
    while (c.levels_.back().width > 1 || c.levels_.back().height > 1) {
        const Level& a = c.levels_.back();
        Level b{std::max(1, a.width >> 1), std::max(1, a.height >> 1), {}};
        b.rgba.assign(size_t(b.width) * b.height * 4, 0.f);
        // Source texels [x0, x1) x [y0, y1) of one destination texel: 2x2, and the odd last row or column folded into
        // the last texel (every source texel counted once; the mean is kept exactly for power-of-two sizes).
        for (int y = 0; y < b.height; ++y) {
            const int y0 = 2 * y, y1 = y == b.height - 1 ? a.height : std::min(a.height, 2 * y + 2);
            for (int x = 0; x < b.width; ++x) {
                const int x0 = 2 * x, x1 = x == b.width - 1 ? a.width : std::min(a.width, 2 * x + 2);
                float sum[4] = {0, 0, 0, 0};
                for (int j = y0; j < y1; ++j)
                    for (int i = x0; i < x1; ++i)
                        for (int k = 0; k < 4; ++k) sum[k] += a.rgba[(size_t(j) * a.width + i) * 4 + k];
                const float w = 1.f / float((x1 - x0) * (y1 - y0));
                for (int k = 0; k < 4; ++k) b.rgba[(size_t(y) * b.width + x) * 4 + k] = sum[k] * w;
            }
        }
        c.levels_.push_back(std::move(b));
    }
    return c;
}

Vec4 GlMipChain::bilinear(int l, Vec2 uv, TextureWrap wrap) const {
    const Level& L = levels_[size_t(l)];
    const float s = texelCoordinate(uv.x * float(L.width) - 0.5f), t = texelCoordinate(uv.y * float(L.height) - 0.5f);
    const float fs = std::floor(s), ft = std::floor(t);
    const int i0 = int(fs), j0 = int(ft);
    const float a = s - fs, b = t - ft;
    const int xs[2] = {wrapIndex(i0, L.width, wrap), wrapIndex(i0 + 1, L.width, wrap)};
    const int ys[2] = {wrapIndex(j0, L.height, wrap), wrapIndex(j0 + 1, L.height, wrap)};
    const float wx[2] = {1.f - a, a}, wy[2] = {1.f - b, b};
    Vec4 r(0.f);
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            if (xs[i] < 0 || ys[j] < 0) continue;
            const float* p = &L.rgba[(size_t(ys[j]) * L.width + xs[i]) * 4];
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
    const Vec2 size(float(levels_[0].width), float(levels_[0].height));
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
