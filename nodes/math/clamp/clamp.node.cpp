// math.clamp.<type>: component-wise min(max(x, lo), hi).
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
float op(float x, float lo, float hi) { return std::min(std::max(x, lo), hi); }
void reg(NodeRegistry& r) {
    registerTyped(r, "math", "clamp", mathTypes(), "Component-wise min(max(x, lo), hi).", [](NodeSpec& s, TypeDesc t) {
        s.inputs = {port("x", t, 0.f, "value"), port("lo", t, 0.f, "lower bound", -1.f, 0.f),
                    port("hi", t, 1.f, "upper bound", 0.f, 1.f)};
        s.outputs = {PortSpec::out("out", t, "clamped value")};
        s.cpu = byWidth<Ternary<op>::K>(t);
    });
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
