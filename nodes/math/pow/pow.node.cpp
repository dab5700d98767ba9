// math.pow.<type>: component-wise a^b for a > 0, and 0 for a ≤ 0 (GLSL pow is undefined there).
#include "nodes/node_common.h"

#include <cmath>

namespace specula::nodes {
namespace {
float op(float a, float b) { return a <= 0.f ? 0.f : std::pow(a, b); }
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "pow", mathTypes(), "Component-wise power a^b; 0 where a ≤ 0.", [](NodeSpec& s, TypeDesc t) {
        s.inputs = portsByWidth<BinaryArgs>(t, OperandDoc{1.f, "base (≤ 0 gives 0)", 0.f, 4.f}, OperandDoc{1.f, "exponent", -2.f, 4.f});
        s.outputs = {PortSpec::out("out", t, "a^b")};
        s.cpu = byWidth<Binary<op>::K>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
