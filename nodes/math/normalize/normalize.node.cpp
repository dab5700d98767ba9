// math.normalize.<type>: v / |v|, and 0 for the zero vector.
#include "nodes/node_common.h"

#include <cmath>

namespace specula::nodes {
namespace {
template <int W>
struct NormalizeArgs {
    FloatN<W> v;
    static NodeParams<NormalizeArgs> declare(TypeDesc t) { return NodeParams<NormalizeArgs>().typed("v", &NormalizeArgs::v, t, 0.f, "vector").range(-2.f, 2.f); }
};
template <int W>
struct NormalizeKernel {
    static void run(EvalContext& c, const Instr& i) {
        static const NodeParams<NormalizeArgs<W>> kIn = NormalizeArgs<W>::declare(widthType<W>());
        const NormalizeArgs<W> p = kIn.read(c, i);
        float l2 = p.v[0] * p.v[0];
        for (int k = 1; k < W; ++k) l2 += p.v[k] * p.v[k];
        float l = std::sqrt(l2);
        FloatN<W> o;
        for (int k = 0; k < W; ++k) o[k] = l2 > 0.f ? p.v[k] / l : 0.f;
        setSingleOutput(c, i, o);
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "normalize", vectorTypes(), "Unit vector v/|v| (0 for v = 0).", [](NodeSpec& s, TypeDesc t) {
        s.inputs = portsByWidth<NormalizeArgs>(t);
        s.outputs = {PortSpec::out("out", t, "v/|v|")};
        s.cpu = byWidth<NormalizeKernel>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
