// constant.float / constant.vec2 / constant.color3 / constant.vector3: a typed literal as a node
// (always constant-folded on the CPU).
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {

template <int W>
struct ConstantArgs {
    FloatN<W> value;
    static NodeParams<ConstantArgs> declare(TypeDesc t) {
        return NodeParams<ConstantArgs>().typed("value", &ConstantArgs::value, t, 0.f, "the value").range(-10.f, 10.f);
    }
};
template <int W>
struct Copy {
    static void run(EvalContext& c, const Instr& i) {
        static const NodeParams<ConstantArgs<W>> kIn = ConstantArgs<W>::declare(widthType<W>());
        setSingleOutput(c, i, kIn.read(c, i).value);
    }
};
void registerConstants(NodeRegistry& reg) {
    for (TypeDesc t : mathTypes()) {
        NodeSpec s;
        s.id = std::string("constant.") + typeName(t);
        s.category = "constant";
        s.doc = std::string("A constant ") + typeName(t) + " value.";
        s.inputs = portsByWidth<ConstantArgs>(t);
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
