// math.mix.<type>: linear interpolation a·(1 − t) + b·t with a float factor t.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
struct Mix {
    template <int W>
    struct Args {
        FloatN<W> a, b;
        float t;
        static NodeParams<Args> declare(TypeDesc ty) {
            return NodeParams<Args>()
                .typed("a", &Args::a, ty, 0.f, "value at t = 0").range(-2.f, 2.f)
                .typed("b", &Args::b, ty, 1.f, "value at t = 1").range(-2.f, 2.f)
                .f("t", &Args::t, 0.5f, "interpolation factor").range(0.f, 1.f);
        }
        FloatN<W> eval() const {
            FloatN<W> o;
            for (int k = 0; k < W; ++k) o[k] = a[k] * (1.f - t) + b[k] * t;
            return o;
        }
    };
};
}  // namespace
SPECULA_REGISTER_NODE(mathNodes<Mix>("mix", mathTypes(), "Linear interpolation a·(1 − t) + b·t.", "a·(1 − t) + b·t"));
}  // namespace specula::nodes
