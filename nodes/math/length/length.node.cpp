// math.length.<type>: Euclidean length |v|.
#include "nodes/math/squared_length.h"
#include "nodes/node_common.h"

#include <cmath>

namespace specula::nodes {
namespace {
struct Length {
    template <int W>
    struct Args {
        FloatN<W> v;
        static NodeParams<Args> declare(TypeDesc t) {
            return NodeParams<Args>().typed("v", &Args::v, t, 0.f, "vector").range(-2.f, 2.f);
        }
        float eval() const {
            return std::sqrt(squaredLength(v));
        }
    };
};
}  // namespace
SPECULA_REGISTER_NODE(mathNodes<Length>("length", vectorTypes(), "Euclidean length |v|.", "|v|"));
}  // namespace specula::nodes
