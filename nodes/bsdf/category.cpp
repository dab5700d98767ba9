// The bsdf category's notes: what its nodes share, shown under its heading in docs/nodes.md.
#include "nodes/node_common.h"

namespace specula::nodes {
SPECULA_DESCRIBE_CATEGORY("bsdf",
    "Closure-producing nodes. The first BSDF node of a material fixes its shading frame (from its "
    "`normal`/`tangent` inputs); later BSDFs with another frame are rotated into it "
    "([graph-format.md](graph-format.md#compilation-cpu)). The material output is the graph's `\"output\"` "
    "reference (a closure).");
}  // namespace specula::nodes
