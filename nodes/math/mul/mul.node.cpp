// math.mul.<type>: component-wise a * b.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
float op(float a, float b) { return a * b; }
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "mul", mathTypes(), "Component-wise product a * b.", [](NodeSpec& s, TypeDesc t) {
        s.inputs = portsByWidth<BinaryArgs>(t, OperandDoc{1.f, "first operand"}, OperandDoc{1.f, "second operand"});
        s.outputs = {PortSpec::out("out", t, "a * b")};
        s.cpu = byWidth<Binary<op>::K>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
