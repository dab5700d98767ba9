// math.mul.<type>: component-wise a * b.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
float op(float a, float b) { return a * b; }
}  // namespace
SPECULA_REGISTER_NODE(binaryMath<op>("mul", "Component-wise product a * b.", "a * b",
                                     {1.f, "first operand"}, {1.f, "second operand"}));
}  // namespace specula::nodes
