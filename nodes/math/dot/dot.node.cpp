// math.dot.<type>: dot product of two vec2/vector3 values.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
template <int W>
struct Dot {
    static void run(EvalContext& c, const Instr& i) {
        const float* a = c.r + i.in[0];
        const float* b = c.r + i.in[1];
        float s = a[0] * b[0];
        for (int k = 1; k < W; ++k) s += a[k] * b[k];
        c.r[i.out[0]] = s;
    }
};
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "dot", vectorTypes(), "Dot product a·b.", [](NodeSpec& s, TypeDesc t) {
        s.inputs = {port("a", t, 0.f, "first vector"), port("b", t, 0.f, "second vector")};
        s.outputs = {PortSpec::out("out", TypeDesc::Float, "a·b")};
        s.cpu = byWidth<Dot>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
