// math.dot.<type>: dot product of two vec2/vector3 values.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
template <int W>
struct DotArgs {
    FloatN<W> a, b;
    static NodeParams<DotArgs> declare(TypeDesc t) {
        return NodeParams<DotArgs>()
            .typed("a", &DotArgs::a, t, 0.f, "first vector").range(-2.f, 2.f)
            .typed("b", &DotArgs::b, t, 0.f, "second vector").range(-2.f, 2.f);
    }
};
template <int W>
struct Dot {
    static void run(EvalContext& c, const Instr& i) {
        static const NodeParams<DotArgs<W>> kIn = DotArgs<W>::declare(widthType<W>());
        const DotArgs<W> p = kIn.read(c, i);
        float s = p.a[0] * p.b[0];
        for (int k = 1; k < W; ++k) s += p.a[k] * p.b[k];
        setSingleOutput(c, i, s);
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "dot", vectorTypes(), "Dot product a·b.", [](NodeSpec& s, TypeDesc t) {
        s.inputs = portsByWidth<DotArgs>(t);
        s.outputs = {PortSpec::out("out", TypeDesc::Float, "a·b")};
        s.cpu = byWidth<Dot>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
