// math.div.<type>: component-wise a / b, defined as 0 where b == 0 (no inf/NaN in shading).
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
float op(float a, float b) { return b == 0.f ? 0.f : a / b; }
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "div", mathTypes(), "Component-wise quotient a / b; 0 where b == 0.", [](NodeSpec& s, TypeDesc t) {
        s.inputs = portsByWidth<BinaryArgs>(t, OperandDoc{0.f, "numerator"}, OperandDoc{1.f, "denominator (0 gives 0)"});
        s.outputs = {PortSpec::out("out", t, "a / b")};
        s.cpu = byWidth<Binary<op>::K>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
