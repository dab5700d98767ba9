// The math category's notes: what its nodes share, shown under its heading in docs/nodes.md.
#include "nodes/node_common.h"

namespace specula::nodes {
SPECULA_DESCRIBE_CATEGORY("math",
    "Component-wise; typed variants `math.<op>.<type>` with `<type>` in `float`, `vec2`, `color3`, "
    "`vector3` (`dot`, `normalize`, `length`: `vec2`, `vector3`). Writing `math.add` alone is an error "
    "suggesting a typed variant.");
}  // namespace specula::nodes
