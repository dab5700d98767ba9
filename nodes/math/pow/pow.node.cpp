// math.pow.<type>: component-wise a^b for a > 0, and 0 for a ≤ 0 (GLSL pow is undefined there).
#include "nodes/node_common.h"

#include <cmath>

namespace specula::nodes {
namespace {
float op(float a, float b) { return a <= 0.f ? 0.f : std::pow(a, b); }
}  // namespace
SPECULA_REGISTER_NODE(binaryMath<op>("pow", "Component-wise power a^b; 0 where a ≤ 0.", "a^b",
                                     {1.f, "base (≤ 0 gives 0)", 0.f, 4.f}, {1.f, "exponent", -2.f, 4.f}));
}  // namespace specula::nodes
