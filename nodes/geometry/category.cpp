// The geometry category's notes: what its nodes share, shown under its heading in docs/nodes.md.
#include "nodes/node_common.h"

namespace specula::nodes {
SPECULA_DESCRIBE_CATEGORY("geometry",
    "GLSL: read `SpeculaShadingInputs s`. CPU sources (`ShadingPoint sp`):\n\n"
    "| id | CPU source |\n"
    "|---|---|\n"
    "| `geometry.uv` | `sp.uv`, `sp.duvdx`, `sp.duvdy` |\n"
    "| `geometry.position` | `sp.p`, `sp.dpdx`, `sp.dpdy` |\n"
    "| `geometry.normal` | `sp.n`, `sp.dndx`, `sp.dndy` |\n"
    "| `geometry.tangent` | `sp.tangent.xyz`, `.w` |\n"
    "| `geometry.geometric_normal` | `sp.ng` |\n\n"
    "Derivatives: CPU from ray differentials (zero when `sp.hasDifferentials` is false); GLSL from the struct, "
    "which `specula_shading_inputs()` fills with `dFdx/dFdy` (tested: exact for linear attributes).");
}  // namespace specula::nodes
