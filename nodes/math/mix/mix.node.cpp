// math.mix.<type>: linear interpolation a·(1 − t) + b·t with a float factor t.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
template <int W>
struct MixArgs {
    FloatN<W> a, b;
    float t;
    static NodeParams<MixArgs> declare(TypeDesc ty) {
        return NodeParams<MixArgs>()
            .typed("a", &MixArgs::a, ty, 0.f, "value at t = 0").range(-2.f, 2.f)
            .typed("b", &MixArgs::b, ty, 1.f, "value at t = 1").range(-2.f, 2.f)
            .f("t", &MixArgs::t, 0.5f, "interpolation factor").range(0.f, 1.f);
    }
};
template <int W>
struct Mix {
    static void run(EvalContext& c, const Instr& i) {
        static const NodeParams<MixArgs<W>> kIn = MixArgs<W>::declare(widthType<W>());
        const MixArgs<W> p = kIn.read(c, i);
        FloatN<W> o;
        for (int k = 0; k < W; ++k) o[k] = p.a[k] * (1.f - p.t) + p.b[k] * p.t;
        setSingleOutput(c, i, o);
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "mix", mathTypes(), "Linear interpolation a·(1 − t) + b·t.", [](NodeSpec& s, TypeDesc t) {
        s.inputs = portsByWidth<MixArgs>(t);
        s.outputs = {PortSpec::out("out", t, "a·(1 − t) + b·t")};
        s.cpu = byWidth<Mix>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
