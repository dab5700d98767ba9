// math.mix.<type>: linear interpolation a·(1 − t) + b·t with a float factor t.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
template <int W>
struct Mix {
    static void run(EvalContext& c, const Instr& i) {
        const float* a = c.r + i.in[0];
        const float* b = c.r + i.in[1];
        float t = c.r[i.in[2]];
        float* o = c.r + i.out[0];
        for (int k = 0; k < W; ++k) o[k] = a[k] * (1.f - t) + b[k] * t;
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "mix", mathTypes(), "Linear interpolation a·(1 − t) + b·t.", [](NodeSpec& s, TypeDesc t) {
        s.inputs = {port("a", t, 0.f, "value at t = 0"), port("b", t, 1.f, "value at t = 1"),
                    port("t", TypeDesc::Float, 0.5f, "interpolation factor", 0.f, 1.f)};
        s.outputs = {PortSpec::out("out", t, "a·(1 − t) + b·t")};
        s.cpu = byWidth<Mix>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
