// One image pyramid for every MIP chain Specula builds on the host (texture.image's GL chain, the LEAN moment pyramid,
// the glint dictionary's 1D marginals): the levels of a float image and the box reduction between them, defined once.
#pragma once

#include "core/texture/texture_store.h"

#include <vector>

namespace specula {

// Level sizes follow GL's floor rule for both reductions: level l is max(1, n >> l) texels along an axis of n.
int pyramidLevelSize(int size0, int level);

// Texel index of i along an axis of n texels under a wrap mode (GL's REPEAT, CLAMP_TO_EDGE, MIRRORED_REPEAT and a
// black border); -1 for a texel of the black border.
int wrapTexelIndex(int i, int n, TextureWrap wrap);

enum class PyramidReduction {
    // GL's 2x2 box in float (what glGenerateMipmap computes for power-of-two sizes): a texel averages the 2x2 texels
    // above it, an odd last row or column folded into the last texel, so every source texel counts once.
    GlBox,
    // The exact area average (Olano & Baker 2010 need every level to keep the image mean): a texel of level l+1 covers
    // nIn / nOut texels of level l with fractional overlaps for odd sizes; rows first, then columns, in double, and
    // the double levels carried down the chain (each stored rounded to float).
    ExactArea,
};

struct PyramidLevel {
    int width = 0, height = 0;
    std::vector<float> texels;  // 'channels' floats per texel, row-major in the order level 0 was given
};

class Pyramid {
public:
    // Level 0 = 'base' (width x height texels of 'channels' floats), reduced down to 1x1.
    static Pyramid build(int width, int height, int channels, std::vector<float> base, PyramidReduction reduction);
    // ExactArea from a double-precision level 0 (LEAN's moments): no float rounding before the first reduction.
    static Pyramid buildExact(int width, int height, int channels, std::vector<double> base);

    int levels() const { return int(levels_.size()); }
    int channels() const { return channels_; }
    const PyramidLevel& level(int l) const { return levels_[size_t(l)]; }
    // The 'channels' floats of texel (x, y) of level l.
    const float* texel(int l, int x, int y) const {
        const PyramidLevel& L = levels_[size_t(l)];
        return &L.texels[(size_t(y) * size_t(L.width) + size_t(x)) * size_t(channels_)];
    }

private:
    std::vector<PyramidLevel> levels_;
    int channels_ = 0;
};

}  // namespace specula
