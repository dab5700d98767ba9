// The closure category's notes: what its nodes share, shown under its heading in docs/nodes.md.
#include "nodes/node_common.h"

namespace specula::nodes {
SPECULA_DESCRIBE_CATEGORY("closure",
    "Closure combinators; their closure inputs are required (a closure has no default).");
}  // namespace specula::nodes
