// math.sub.<type>: component-wise a - b.
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
float op(float a, float b) { return a - b; }
}  // namespace
SPECULA_REGISTER_NODE(binaryMath<op>("sub", "Component-wise difference a - b.", "a - b",
                                     {0.f, "first operand"}, {0.f, "second operand"}));
}  // namespace specula::nodes
