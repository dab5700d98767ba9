// The convert category's notes: what its nodes share, shown under its heading in docs/nodes.md.
#include "nodes/node_common.h"

namespace specula::nodes {
SPECULA_DESCRIBE_CATEGORY("convert",
    "Connections never convert implicitly ([graph-format.md](graph-format.md#types-and-conversions)): "
    "these nodes are the explicit conversions. Input `in`, output `out`; broadcasts copy the float into "
    "every component, reinterpretations keep the values (no renormalisation).");
}  // namespace specula::nodes
