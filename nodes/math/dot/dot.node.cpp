// math.dot.<type>: dot product of two vec2/vector3 values.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
struct Dot {
    template <int W>
    struct Args {
        FloatN<W> a, b;
        static NodeParams<Args> declare(TypeDesc t) {
            return NodeParams<Args>()
                .typed("a", &Args::a, t, 0.f, "first vector").range(-2.f, 2.f)
                .typed("b", &Args::b, t, 0.f, "second vector").range(-2.f, 2.f);
        }
        float eval() const {
            float s = a[0] * b[0];
            for (int k = 1; k < W; ++k) s += a[k] * b[k];
            return s;
        }
    };
};
}  // namespace
SPECULA_REGISTER_NODE(mathNodes<Dot>("dot", vectorTypes(), "Dot product a·b.", "a·b"));
}  // namespace specula::nodes
