// math.remap.<type>: maps x linearly from [in_min, in_max] to [out_min, out_max] (no clamping);
// out_min where in_max == in_min.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
template <int W>
struct RemapArgs {
    FloatN<W> x, inMin, inMax, outMin, outMax;
    static NodeParams<RemapArgs> declare(TypeDesc t) {
        return NodeParams<RemapArgs>()
            .typed("x", &RemapArgs::x, t, 0.f, "value").range(-2.f, 2.f)
            .typed("in_min", &RemapArgs::inMin, t, 0.f, "input low").range(-1.f, 0.f)
            .typed("in_max", &RemapArgs::inMax, t, 1.f, "input high").range(0.5f, 2.f)
            .typed("out_min", &RemapArgs::outMin, t, 0.f, "output low").range(-2.f, 2.f)
            .typed("out_max", &RemapArgs::outMax, t, 1.f, "output high").range(-2.f, 2.f);
    }
};
template <int W>
struct Remap {
    static void run(EvalContext& c, const Instr& i) {
        static const NodeParams<RemapArgs<W>> kIn = RemapArgs<W>::declare(widthType<W>());
        const RemapArgs<W> p = kIn.read(c, i);
        FloatN<W> o;
        for (int k = 0; k < W; ++k) {
            float d = p.inMax[k] - p.inMin[k];
            o[k] = d == 0.f ? p.outMin[k] : p.outMin[k] + (p.x[k] - p.inMin[k]) / d * (p.outMax[k] - p.outMin[k]);
        }
        setSingleOutput(c, i, o);
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "remap", mathTypes(), "Linear remap of x from [in_min, in_max] to [out_min, out_max].",
                  [](NodeSpec& s, TypeDesc t) {
                      s.inputs = portsByWidth<RemapArgs>(t);
                      s.outputs = {PortSpec::out("out", t, "remapped value")};
                      s.cpu = byWidth<Remap>(t);
                  });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
