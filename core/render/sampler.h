// Stateless hashed sampler: every random number is a hash of (pixel, sample index, dimension, seed),
// so an image is bit-identical for any thread count or tile order (cf. pbrt-v4's hashed samplers).
#pragma once

#include "core/math/math.h"

#include <cstdint>

namespace specula {

// 64-bit finaliser (splitmix64 / Stafford variant 13): a bijective avalanche mix.
inline uint64_t mix64(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

class PixelSampler {
public:
    PixelSampler(uint32_t px, uint32_t py, uint32_t sampleIndex, uint64_t seed)
        : base_(mix64(mix64(mix64(seed + 0x9E3779B97F4A7C15ULL) ^ ((uint64_t(py) << 32) | px)) ^ sampleIndex)) {}

    // Dimensions are consumed in a fixed order by the integrator, so the same dimension index always
    // means the same decision for a given (pixel, sample).
    float get1D() { return toFloat(mix64(base_ ^ (0xD1B54A32D192ED03ULL * ++dim_))); }
    Vec2 get2D() {
        float a = get1D();
        return {a, get1D()};
    }
    uint32_t dimension() const { return dim_; }
    // Random bits for a decision outside the fixed dimension order (keyed, consumes no dimension): the extra
    // samples of LTC shadow rays, rejection-sampling retries.
    uint64_t bits(uint64_t key) const { return mix64(base_ ^ mix64(key + 0x632BE59BD9B4E019ULL)); }
    static float unitFloat(uint64_t h) { return toFloat(h); }
    // Jump to a fixed dimension block (e.g. the start of bounce k), keeping bounce sequences aligned.
    void setDimension(uint32_t d) { dim_ = d; }

private:
    static float toFloat(uint64_t h) {
        // 24 high bits -> [0,1)
        return float(h >> 40) * (1.f / 16777216.f);
    }
    uint64_t base_;
    uint32_t dim_ = 0;
};

}  // namespace specula
