// constant.float / constant.vec2 / constant.color3 / constant.vector3: a typed literal as a node
// (always constant-folded on the CPU).
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {

template <int W>
struct Copy {
    static void run(EvalContext& c, const Instr& i) {
        for (int k = 0; k < W; ++k) c.r[i.out[0] + k] = c.r[i.in[0] + k];
    }
};

void registerConstants(NodeRegistry& reg) {
    for (TypeDesc t : mathTypes()) {
        NodeSpec s;
        s.id = std::string("constant.") + typeName(t);
        s.category = "constant";
        s.doc = std::string("A constant ") + typeName(t) + " value.";
        s.inputs = {port("value", t, 0.f, "the value", -10.f, 10.f)};
        s.outputs = {PortSpec::out("out", t, "the value")};
        s.flags = kPure;
        s.cpu = byWidth<Copy>(t);
        s.glslFunction = "spc_constant";
        s.glslFile = "constant/constant/constant.glsl";
        reg.add(std::move(s));
    }
}

}  // namespace
SPECULA_REGISTER_NODES(registerConstants);
}  // namespace specula::nodes
