// LEAN moment pyramids: per-texel slope moments, the pyramid's exact (fractional) box reduction in double precision,
// GL-equivalent bilinear/trilinear/anisotropic lookups (the GLSL of texture.lean performs the same steps).
#include "core/texture/lean_moments.h"

#include "core/texture/gl_mip_chain.h"
#include "core/texture/pyramid.h"

#include "core/texture/normal_map_gen.h"

#include <algorithm>
#include <cmath>

namespace specula {

Vec3 LeanStats::meanNormal() const {
    Vec3 n(-mean.x, -mean.y, 1.f);
    return n / std::sqrt(glm::dot(n, n));
}

LeanStats leanStats(const LeanMoments& m, float strength, bool flipY, bool dropCorrelation) {
    LeanStats s;
    const float sy = flipY ? -1.f : 1.f;
    s.mean = Vec2(m.x, m.y * sy) * strength;
    const float s2 = strength * strength;
    // Σ = E[x xᵀ] − E[x] E[x]ᵀ (Olano & Baker 2010), then PSD projection: float cancellation can make a
    // variance slightly negative or |cov| slightly exceed sqrt(varX varY).
    s.varX = std::max(m.xx - m.x * m.x, 0.f) * s2;
    s.varY = std::max(m.yy - m.y * m.y, 0.f) * s2;
    s.covXY = dropCorrelation ? 0.f : (m.xy - m.x * m.y) * sy * s2;
    s.sigmaX = std::sqrt(s.varX);
    s.sigmaY = std::sqrt(s.varY);
    const float lim = s.sigmaX * s.sigmaY;
    s.covXY = std::min(std::max(s.covXY, -lim), lim);
    s.rho = lim > 0.f ? s.covXY / lim : 0.f;
    return s;
}

LeanMoments leanTexelMoments(Vec3 n) {
    // Keep |slope| <= kLeanMaxSlope: nz >= max(|nx|, |ny|)/kLeanMaxSlope (per component, so x~ and y~ both stay bounded).
    float nz = std::max(n.z, std::max(std::abs(n.x), std::abs(n.y)) / kLeanMaxSlope);
    if (!(nz > 0.f)) return {};  // zero vector: flat
    float x = -n.x / nz, y = -n.y / nz;
    return {x, y, x * x, y * y, x * y};
}

int leanLevelSize(int size0, int level) { return pyramidLevelSize(size0, level); }

namespace {

TextureWrap textureWrapOf(LeanWrap wrap) { return wrap == LeanWrap::Clamp ? TextureWrap::Clamp : TextureWrap::Repeat; }

}  // namespace

void LeanPyramid::build(std::vector<LeanMoments> base, int width, int height) {
    levels_.clear();
    // Level 0 in double for the reduction chain (moments are averaged in double, stored in float): the pyramid's
    // exact area reduction over the five moments (x~, y~, x~², y~², x~y~) of each texel.
    std::vector<double> moments(base.size() * 5);
    for (size_t i = 0; i < base.size(); ++i) {
        const LeanMoments& m = base[i];
        double* d = &moments[i * 5];
        d[0] = m.x, d[1] = m.y, d[2] = m.xx, d[3] = m.yy, d[4] = m.xy;
    }
    const Pyramid pyramid = Pyramid::buildExact(width, height, 5, std::move(moments));
    // Split each level into the GLSL samplers' layout: rgba = (x~, y~, x~², y~²), r = x~y~.
    for (int l = 0; l < pyramid.levels(); ++l) {
        const PyramidLevel& P = pyramid.level(l);
        LeanLevel L;
        L.width = P.width;
        L.height = P.height;
        L.rgba.resize(size_t(P.width) * P.height * 4);
        L.r.resize(size_t(P.width) * P.height);
        for (size_t i = 0; i < size_t(P.width) * P.height; ++i) {
            for (int k = 0; k < 4; ++k) L.rgba[i * 4 + size_t(k)] = P.texels[i * 5 + size_t(k)];
            L.r[i] = P.texels[i * 5 + 4];
        }
        levels_.push_back(std::move(L));
    }
}

LeanPyramid LeanPyramid::fromEncodedPixels(const float* pixels, int width, int height, int channels, bool directx) {
    if (!pixels || width <= 0 || height <= 0) throw LeanError("LEAN: empty normal map");
    if (channels < 2) throw LeanError("LEAN: a normal map needs at least 2 channels (got " + std::to_string(channels) + ")");
    std::vector<LeanMoments> base(size_t(width) * height);
    for (int y = 0; y < height; ++y) {
        const int srcRow = height - 1 - y;  // store bottom-up
        for (int x = 0; x < width; ++x) {
            const float* p = pixels + (size_t(srcRow) * width + x) * size_t(channels);
            base[size_t(y) * width + x] = leanTexelMoments(decodeNormalPixel(p, channels, directx));
        }
    }
    LeanPyramid P;
    P.build(std::move(base), width, height);
    return P;
}

LeanPyramid LeanPyramid::fromNormalMap(const NormalMap& map) {
    const int n = map.size;
    if (n <= 0) throw LeanError("LEAN: empty normal map");
    std::vector<LeanMoments> base(size_t(n) * n);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) base[size_t(y) * n + x] = leanTexelMoments(map.at(x, n - 1 - y));
    LeanPyramid P;
    P.build(std::move(base), n, n);
    return P;
}

LeanMoments LeanPyramid::texel(int l, int x, int y) const {
    const LeanLevel& L = levels_[size_t(l)];
    size_t i = size_t(y) * L.width + x;
    const float* a = &L.rgba[i * 4];
    return {a[0], a[1], a[2], a[3], L.r[i]};
}

LeanMoments LeanPyramid::bilinear(int l, Vec2 uv, LeanWrap wrap) const {
    const LeanLevel& L = levels_[size_t(l)];
    float s = texelCoordinate(uv.x * float(L.width) - 0.5f), t = texelCoordinate(uv.y * float(L.height) - 0.5f);
    float fs = std::floor(s), ft = std::floor(t);
    int i0 = int(fs), j0 = int(ft);
    float a = s - fs, b = t - ft;
    const TextureWrap tw = textureWrapOf(wrap);
    int x0 = wrapTexelIndex(i0, L.width, tw), x1 = wrapTexelIndex(i0 + 1, L.width, tw);
    int y0 = wrapTexelIndex(j0, L.height, tw), y1 = wrapTexelIndex(j0 + 1, L.height, tw);
    LeanMoments m = texel(l, x0, y0) * ((1 - a) * (1 - b));
    m += texel(l, x1, y0) * (a * (1 - b));
    m += texel(l, x0, y1) * ((1 - a) * b);
    m += texel(l, x1, y1) * (a * b);
    return m;
}

LeanMoments LeanPyramid::trilinear(float lambda, Vec2 uv, LeanWrap wrap) const {
    const int top = levels() - 1;
    if (!(lambda > 0.f)) return bilinear(0, uv, wrap);
    if (lambda >= float(top)) return bilinear(top, uv, wrap);
    float fl = std::floor(lambda);
    int l0 = int(fl);
    float f = lambda - fl;
    LeanMoments m = bilinear(l0, uv, wrap) * (1.f - f);
    if (f > 0.f) m += bilinear(l0 + 1, uv, wrap) * f;
    return m;
}

LeanMoments LeanPyramid::lookup(Vec2 uv, Vec2 duvdx, Vec2 duvdy, LeanFilter filter, LeanWrap wrap, int maxAniso) const {
    if (levels_.empty()) return {};
    if (filter == LeanFilter::None) return bilinear(0, uv, wrap);
    const Vec2 size{float(width()), float(height())};
    const Vec2 j1 = duvdx * size, j2 = duvdy * size;  // footprint axes in level-0 texels
    const float l1 = std::sqrt(glm::dot(j1, j1)), l2 = std::sqrt(glm::dot(j2, j2));
    if (filter == LeanFilter::Trilinear) {
        float rho = std::max(l1, l2);
        return rho > 0.f ? trilinear(std::log2(rho), uv, wrap) : bilinear(0, uv, wrap);
    }
    // Anisotropic (EXT_texture_filter_anisotropic reference): probes along the longer axis.
    const float pmax = std::max(l1, l2), pmin = std::min(l1, l2);
    if (!(pmax > 0.f)) return bilinear(0, uv, wrap);
    const int n = anisotropicProbeCount(pmax, pmin, maxAniso);  // near-isotropic footprints: one probe
    const Vec2 major = l1 >= l2 ? duvdx : duvdy;
    const float lambda = std::log2(pmax / float(n));
    LeanMoments m;
    const float wgt = 1.f / float(n);
    for (int i = 0; i < n; ++i) {
        float t = (float(i) + 0.5f) / float(n) - 0.5f;
        m += trilinear(lambda, uv + major * t, wrap) * wgt;
    }
    return m;
}

size_t LeanPyramid::memoryBytes() const {
    size_t b = 0;
    for (const LeanLevel& L : levels_) b += (L.rgba.size() + L.r.size()) * sizeof(float);
    return b;
}

void LeanPyramid::glslLevelSize(int l, int& w, int& h) const {
    const int p0 = 2 * std::max(width(), height());
    w = std::max(1, width() >> l);
    h = std::max(1, p0 >> l);
}

std::vector<float> LeanPyramid::glslPackedLevel(int l) const {
    int w, h;
    glslLevelSize(l, w, h);
    std::vector<float> out(size_t(w) * h * 4, 0.f);
    if (l >= levels()) return out;  // padding level
    const LeanLevel& L = levels_[size_t(l)];
    for (int j = 0; j < L.height; ++j)
        for (int x = 0; x < L.width; ++x) {
            const size_t src = size_t(j) * L.width + x;
            float* a = &out[(size_t(2 * j) * w + x) * 4];
            float* b = &out[(size_t(2 * j + 1) * w + x) * 4];
            for (int k = 0; k < 4; ++k) a[k] = L.rgba[src * 4 + size_t(k)];
            b[0] = L.r[src];
            b[1] = float(L.height);
            b[2] = float(levels());
        }
    return out;
}

size_t LeanPyramid::baseBytes() const {
    return levels_.empty() ? 0 : (levels_[0].rgba.size() + levels_[0].r.size()) * sizeof(float);
}

}  // namespace specula
