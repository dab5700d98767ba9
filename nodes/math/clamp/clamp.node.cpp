// math.clamp.<type>: component-wise min(max(x, lo), hi).
#include "nodes/node_common.h"

#include <algorithm>

namespace specula::nodes {
namespace {
template <int W>
struct ClampArgs {
    FloatN<W> x, lo, hi;
    static NodeParams<ClampArgs> declare(TypeDesc t) {
        return NodeParams<ClampArgs>()
            .typed("x", &ClampArgs::x, t, 0.f, "value").range(-2.f, 2.f)
            .typed("lo", &ClampArgs::lo, t, 0.f, "lower bound").range(-1.f, 0.f)
            .typed("hi", &ClampArgs::hi, t, 1.f, "upper bound").range(0.f, 1.f);
    }
};
template <int W>
struct Clamp {
    static void run(EvalContext& c, const Instr& i) {
        static const NodeParams<ClampArgs<W>> kIn = ClampArgs<W>::declare(widthType<W>());
        const ClampArgs<W> p = kIn.read(c, i);
        FloatN<W> o;
        for (int k = 0; k < W; ++k) o[k] = std::min(std::max(p.x[k], p.lo[k]), p.hi[k]);
        setSingleOutput(c, i, o);
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "clamp", mathTypes(), "Component-wise min(max(x, lo), hi).", [](NodeSpec& s, TypeDesc t) {
        s.inputs = portsByWidth<ClampArgs>(t);
        s.outputs = {PortSpec::out("out", t, "clamped value")};
        s.cpu = byWidth<Clamp>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
