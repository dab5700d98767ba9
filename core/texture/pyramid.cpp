// The pyramid's two box reductions (core/texture/pyramid.h). Both keep the operation order of the builders they
// replace (GlMipChain, LeanPyramid, the glint dictionary's MIPs), so every level is bit-identical to theirs.
#include "core/texture/pyramid.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace specula {

int pyramidLevelSize(int size0, int level) { return std::max(1, size0 >> level); }

int wrapTexelIndex(int i, int n, TextureWrap wrap) {
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

namespace {

// GL's reduction of one level (PyramidReduction::GlBox).
PyramidLevel reduceGlBox(const PyramidLevel& a, int channels) {
    PyramidLevel b{std::max(1, a.width >> 1), std::max(1, a.height >> 1), {}};
    const size_t nc = size_t(channels);
    b.texels.assign(size_t(b.width) * b.height * nc, 0.f);
    std::vector<float> sum(nc);
    // Source texels [x0, x1) x [y0, y1) of one destination texel: 2x2, and the odd last row or column folded into
    // the last texel (every source texel counted once; the mean is kept exactly for power-of-two sizes).
    for (int y = 0; y < b.height; ++y) {
        const int y0 = 2 * y, y1 = y == b.height - 1 ? a.height : std::min(a.height, 2 * y + 2);
        for (int x = 0; x < b.width; ++x) {
            const int x0 = 2 * x, x1 = x == b.width - 1 ? a.width : std::min(a.width, 2 * x + 2);
            std::fill(sum.begin(), sum.end(), 0.f);
            for (int j = y0; j < y1; ++j)
                for (int i = x0; i < x1; ++i)
                    for (size_t k = 0; k < nc; ++k) sum[k] += a.texels[(size_t(j) * a.width + i) * nc + k];
            const float w = 1.f / float((x1 - x0) * (y1 - y0));
            for (size_t k = 0; k < nc; ++k) b.texels[(size_t(y) * b.width + x) * nc + k] = sum[k] * w;
        }
    }
    return b;
}

// Exact 1D box reduction weights: output i covers [i * r, (i + 1) * r) input texels, r = nIn / nOut.
// Returns (input index, weight) lists per output; weights sum to 1 per output and to nOut/nIn per input.
std::vector<std::vector<std::pair<int, double>>> boxWeights(int nIn, int nOut) {
    std::vector<std::vector<std::pair<int, double>>> w(static_cast<size_t>(nOut));
    const double r = double(nIn) / double(nOut);
    for (int i = 0; i < nOut; ++i) {
        double a = i * r, b = (i + 1) * r;
        for (int j = int(std::floor(a)); j < int(std::ceil(b)) && j < nIn; ++j) {
            double ov = std::min(b, double(j + 1)) - std::max(a, double(j));
            if (ov > 0) w[size_t(i)].push_back({j, ov / r});
        }
    }
    return w;
}

PyramidLevel toFloat(const std::vector<double>& v, int w, int h) {
    PyramidLevel L{w, h, std::vector<float>(v.size())};
    for (size_t i = 0; i < v.size(); ++i) L.texels[i] = float(v[i]);
    return L;
}

}  // namespace

Pyramid Pyramid::build(int width, int height, int channels, std::vector<float> base, PyramidReduction reduction) {
    if (reduction == PyramidReduction::ExactArea)
        return buildExact(width, height, channels, std::vector<double>(base.begin(), base.end()));
    Pyramid p;
    p.channels_ = channels;
    p.levels_.push_back({width, height, std::move(base)});
    while (p.levels_.back().width > 1 || p.levels_.back().height > 1)
        p.levels_.push_back(reduceGlBox(p.levels_.back(), channels));
    return p;
}

Pyramid Pyramid::buildExact(int width, int height, int channels, std::vector<double> cur) {
    Pyramid p;
    p.channels_ = channels;
    const size_t nc = size_t(channels);
    int w = width, h = height;
    p.levels_.push_back(toFloat(cur, w, h));
    while (w > 1 || h > 1) {
        const int nw = std::max(1, w / 2), nh = std::max(1, h / 2);
        auto wx = boxWeights(w, nw), wy = boxWeights(h, nh);
        // Rows first (x), then columns (y): separable box = exact area average of the 2D box.
        std::vector<double> tmp(size_t(nw) * h * nc, 0.0);
        for (int y = 0; y < h; ++y)
            for (int i = 0; i < nw; ++i)
                for (auto [j, wt] : wx[size_t(i)])
                    for (size_t k = 0; k < nc; ++k) tmp[(size_t(y) * nw + i) * nc + k] += wt * cur[(size_t(y) * w + j) * nc + k];
        std::vector<double> next(size_t(nw) * nh * nc, 0.0);
        for (int i = 0; i < nh; ++i)
            for (auto [j, wt] : wy[size_t(i)])
                for (int x = 0; x < nw; ++x)
                    for (size_t k = 0; k < nc; ++k) next[(size_t(i) * nw + x) * nc + k] += wt * tmp[(size_t(j) * nw + x) * nc + k];
        cur.swap(next);
        w = nw, h = nh;
        p.levels_.push_back(toFloat(cur, w, h));
    }
    return p;
}

}  // namespace specula
