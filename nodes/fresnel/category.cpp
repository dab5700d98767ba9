// The fresnel category's notes: what its nodes share, shown under its heading in docs/nodes.md.
#include "nodes/node_common.h"

namespace specula::nodes {
SPECULA_DESCRIBE_CATEGORY("fresnel",
    "Pattern nodes; `cos_theta` defaults to the binding `NdotV` = dot(N, wo). CPU code is "
    "`core/render/lobes/fresnel.h`; GLSL twins are in the prelude (same operation order).");
}  // namespace specula::nodes
