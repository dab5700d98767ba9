// math.clamp.<type>: component-wise min(max(x, lo), hi).
#include "nodes/node_common.h"

#include <algorithm>

namespace specula::nodes {
namespace {
struct Clamp {
    template <int W>
    struct Args {
        FloatN<W> x, lo, hi;
        static NodeParams<Args> declare(TypeDesc t) {
            return NodeParams<Args>()
                .typed("x", &Args::x, t, 0.f, "value").range(-2.f, 2.f)
                .typed("lo", &Args::lo, t, 0.f, "lower bound").range(-1.f, 0.f)
                .typed("hi", &Args::hi, t, 1.f, "upper bound").range(0.f, 1.f);
        }
        FloatN<W> eval() const {
            FloatN<W> o;
            for (int k = 0; k < W; ++k) o[k] = std::min(std::max(x[k], lo[k]), hi[k]);
            return o;
        }
    };
};
}  // namespace
SPECULA_REGISTER_NODE(mathNodes<Clamp>("clamp", mathTypes(), "Component-wise min(max(x, lo), hi).", "clamped value"));
}  // namespace specula::nodes
