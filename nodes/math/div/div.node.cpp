// math.div.<type>: component-wise a / b, defined as 0 where b == 0 (no inf/NaN in shading).
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {
float op(float a, float b) { return b == 0.f ? 0.f : a / b; }
}  // namespace
SPECULA_REGISTER_NODE(binaryMath<op>("div", "Component-wise quotient a / b; 0 where b == 0.", "a / b",
                                     {0.f, "numerator"}, {1.f, "denominator (0 gives 0)"}));
}  // namespace specula::nodes
