// GlMipChain (core/texture/gl_mip_chain.h), the GL filtering rules that texture.image's GLSL and its CPU twin share:
// the chain keeps the image mean at every level, bilinear reproduces texels at their centres under each wrap mode,
// trilinear at an integer LOD is that level, and the anisotropic probes follow EXT_texture_filter_anisotropic.
#include "core/texture/gl_mip_chain.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace specula;

namespace {

GlMipChain randomChain(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<float> rgba(size_t(w) * h * 4);
    for (float& v : rgba) v = u01(rng);
    return GlMipChain::build(w, h, std::move(rgba));
}

Vec4 texel(const GlMipChain& c, int l, int x, int y) {
    const auto& L = c.level(l);
    const float* p = &L.texels[(size_t(y) * L.width + x) * 4];
    return {p[0], p[1], p[2], p[3]};
}

Vec4 mean(const GlMipChain& c, int l) {
    const auto& L = c.level(l);
    Vec4 m(0.f);
    for (int y = 0; y < L.height; ++y)
        for (int x = 0; x < L.width; ++x) m += texel(c, l, x, y);
    return m / float(L.width * L.height);
}

}  // namespace

TEST(GlMipChain, LevelsFollowTheFloorRuleAndKeepTheMean) {
    for (auto [w, h] : {std::pair{16, 16}, std::pair{13, 7}, std::pair{1, 9}, std::pair{64, 3}}) {
        GlMipChain c = randomChain(w, h, 5);
        int lw = w, lh = h, l = 0;
        while (true) {
            EXPECT_EQ(c.level(l).width, lw);
            EXPECT_EQ(c.level(l).height, lh);
            if (lw == 1 && lh == 1) break;
            lw = std::max(1, lw >> 1), lh = std::max(1, lh >> 1), ++l;
        }
        EXPECT_EQ(c.levels(), l + 1);
        // The mean is kept exactly for power-of-two sizes and up to the fold weighting for odd ones.
        const bool pow2 = (w & (w - 1)) == 0 && (h & (h - 1)) == 0;
        for (int k = 1; k < c.levels(); ++k)
            for (int ch = 0; ch < 4; ++ch)
                EXPECT_NEAR(mean(c, k)[ch], mean(c, 0)[ch], pow2 ? 1e-5f : 0.05f) << w << "x" << h << " level " << k;
    }
}

TEST(GlMipChain, BilinearReproducesTexelsAndWraps) {
    GlMipChain c = randomChain(8, 4, 9);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) {
            Vec2 uv((x + 0.5f) / 8, (y + 0.5f) / 4);
            for (TextureWrap w : {TextureWrap::Repeat, TextureWrap::Clamp, TextureWrap::Mirror})
                EXPECT_EQ(c.bilinear(0, uv, w), texel(c, 0, x, y));
        }
    // Half-way between the last and the first texel: repeat averages them, clamp keeps the last, mirror too.
    const Vec2 edge(1.f, 0.5f / 4);
    const Vec4 last = texel(c, 0, 7, 0), first = texel(c, 0, 0, 0);
    for (int ch = 0; ch < 4; ++ch) {
        EXPECT_FLOAT_EQ(c.bilinear(0, edge, TextureWrap::Repeat)[ch], 0.5f * (last[ch] + first[ch]));
        EXPECT_FLOAT_EQ(c.bilinear(0, edge, TextureWrap::Clamp)[ch], last[ch]);
        EXPECT_FLOAT_EQ(c.bilinear(0, edge, TextureWrap::Mirror)[ch], last[ch]);
        EXPECT_FLOAT_EQ(c.bilinear(0, edge, TextureWrap::Black)[ch], 0.5f * last[ch]);
    }
    // Non-finite and huge uvs convert to texel indices without undefined behaviour (UBSan aborts on int(inf)).
    const float inf = std::numeric_limits<float>::infinity();
    for (Vec2 uv : {Vec2(inf, 0.5f), Vec2(-inf, inf), Vec2(std::nanf(""), 0.2f), Vec2(3e9f, -3e9f)})
        for (TextureWrap w : {TextureWrap::Repeat, TextureWrap::Clamp, TextureWrap::Mirror})
            EXPECT_TRUE(isFinite(Vec3(c.bilinear(0, uv, w)))) << uv.x << ", " << uv.y;
}

TEST(GlMipChain, TrilinearAndAnisotropicFollowTheGlRules) {
    GlMipChain c = randomChain(64, 64, 3);
    const Vec2 uv(0.3f, 0.55f);
    for (int l = 0; l < c.levels(); ++l) EXPECT_EQ(c.trilinear(float(l), uv, TextureWrap::Repeat), c.bilinear(l, uv, TextureWrap::Repeat));
    const Vec4 a = c.bilinear(2, uv, TextureWrap::Repeat), b = c.bilinear(3, uv, TextureWrap::Repeat);
    const Vec4 mid = c.trilinear(2.25f, uv, TextureWrap::Repeat);
    for (int ch = 0; ch < 4; ++ch) EXPECT_NEAR(mid[ch], 0.75f * a[ch] + 0.25f * b[ch], 1e-6f);
    EXPECT_EQ(c.trilinear(99.f, uv, TextureWrap::Repeat), c.bilinear(c.levels() - 1, uv, TextureWrap::Repeat));
    // Isotropic footprint of 4 texels: one probe at λ = 2; within the slack of isotropic: the same probe.
    const float d = 4.f / 64;
    EXPECT_EQ(c.anisotropic(uv, Vec2(d, 0), Vec2(0, d), TextureWrap::Repeat), c.trilinear(2.f, uv, TextureWrap::Repeat));
    EXPECT_EQ(c.anisotropic(uv, Vec2(d, 0), Vec2(0, d * (1 + 5e-4f)), TextureWrap::Repeat),
              c.trilinear(std::log2(4.f * (1 + 5e-4f)), uv, TextureWrap::Repeat));
    // 4:1 along u: 4 probes at λ = log2(16 / 4) = 2, spaced a quarter of the major axis apart, equally weighted.
    const Vec2 major(16.f / 64, 0.f);
    Vec4 want(0.f);
    for (int i = 0; i < 4; ++i) want += c.trilinear(2.f, uv + major * ((i + 0.5f) / 4 - 0.5f), TextureWrap::Repeat);
    const Vec4 got = c.anisotropic(uv, major, Vec2(0, 4.f / 64), TextureWrap::Repeat);
    for (int ch = 0; ch < 4; ++ch) EXPECT_NEAR(got[ch], want[ch] / 4.f, 1e-6f);
    // Zero footprint: level 0.
    EXPECT_EQ(c.anisotropic(uv, Vec2(0.f), Vec2(0.f), TextureWrap::Repeat), c.bilinear(0, uv, TextureWrap::Repeat));
}
