// math.length.<type>: Euclidean length |v|.
#include "nodes/node_common.h"

#include <cmath>

namespace specula::nodes {
namespace {
template <int W>
struct LengthArgs {
    FloatN<W> v;
    static NodeParams<LengthArgs> declare(TypeDesc t) { return NodeParams<LengthArgs>().typed("v", &LengthArgs::v, t, 0.f, "vector").range(-2.f, 2.f); }
};
template <int W>
struct LengthKernel {
    static void run(EvalContext& c, const Instr& i) {
        static const NodeParams<LengthArgs<W>> kIn = LengthArgs<W>::declare(widthType<W>());
        const LengthArgs<W> p = kIn.read(c, i);
        float l2 = p.v[0] * p.v[0];
        for (int k = 1; k < W; ++k) l2 += p.v[k] * p.v[k];
        setSingleOutput(c, i, std::sqrt(l2));
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "length", vectorTypes(), "Euclidean length |v|.", [](NodeSpec& s, TypeDesc t) {
        s.inputs = portsByWidth<LengthArgs>(t);
        s.outputs = {PortSpec::out("out", TypeDesc::Float, "|v|")};
        s.cpu = byWidth<LengthKernel>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
