// The table of the dictionary rows' nonzero MIP-0 texels (glint_lookup.h rowSupport), built once from
// Dictionary::instance(), so a lookup that can only read zeros skips the row (spec S5.4).
#include "nodes/bsdf/glint/glint_lookup.h"

#include <vector>

namespace specula::glint {

const uint8_t* rowSupport(const Dictionary& dict) {
    static const std::vector<uint8_t> full = [] {
        std::vector<uint8_t> v(size_t(2) * kLevels * kMarginals);
        for (size_t r = 0; r < v.size() / 2; ++r) v[2 * r] = 0, v[2 * r + 1] = uint8_t(kRes - 1);
        return v;
    }();
    static const Dictionary& instance = Dictionary::instance();
    static const std::vector<uint8_t> table = [] {
        std::vector<uint8_t> v(size_t(2) * kLevels * kMarginals);
        for (int k = 0; k < kLevels; ++k)
            for (int d = 0; d < kMarginals; ++d) {
                const float* row = instance.row(k, d);
                int lo = 0, hi = kRes - 1;
                while (lo < kRes - 1 && row[lo] == 0.f) ++lo;
                while (hi > lo && row[hi] == 0.f) --hi;
                const size_t r = size_t(k) * kMarginals + size_t(d);
                v[2 * r] = uint8_t(lo), v[2 * r + 1] = uint8_t(hi);
            }
        return v;
    }();
    return &dict == &instance ? table.data() : full.data();
}

}  // namespace specula::glint
