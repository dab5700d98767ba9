// math.normalize.<type>: v / |v|, and 0 for the zero vector.
#include "nodes/math/squared_length.h"
#include "nodes/node_common.h"

#include <cmath>

namespace specula::nodes {
namespace {
struct Normalize {
    template <int W>
    struct Args {
        FloatN<W> v;
        static NodeParams<Args> declare(TypeDesc t) {
            return NodeParams<Args>().typed("v", &Args::v, t, 0.f, "vector").range(-2.f, 2.f);
        }
        FloatN<W> eval() const {
            const float l2 = squaredLength(v), l = std::sqrt(l2);
            FloatN<W> o;
            for (int k = 0; k < W; ++k) o[k] = l2 > 0.f ? v[k] / l : 0.f;
            return o;
        }
    };
};
}  // namespace
SPECULA_REGISTER_NODE(mathNodes<Normalize>("normalize", vectorTypes(), "Unit vector v/|v| (0 for v = 0).", "v/|v|"));
}  // namespace specula::nodes
