// |v|² of a width-generic math port, summed in component order (math.length and math.normalize share it, so
// their results stay bit-identical to each other: normalize divides by exactly the length math.length returns).
#pragma once

#include <array>
#include <cstddef>

namespace specula::nodes {

// std::array's extent is a size_t: FloatN<W> deduces through it.
template <size_t W>
inline float squaredLength(const std::array<float, W>& v) {
    float l2 = v[0] * v[0];
    for (size_t k = 1; k < W; ++k) l2 += v[k] * v[k];
    return l2;
}

}  // namespace specula::nodes
