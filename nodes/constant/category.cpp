// The constant category's notes: what its nodes share, shown under its heading in docs/nodes.md.
#include "nodes/node_common.h"

namespace specula::nodes {
SPECULA_DESCRIBE_CATEGORY("constant",
    "A typed literal as a node. Pure: always folded on the CPU; in GLSL the literal is a uniform-block "
    "member.");
}  // namespace specula::nodes
