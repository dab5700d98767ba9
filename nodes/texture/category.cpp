// The texture category's notes: what its nodes share, shown under its heading in docs/nodes.md.
#include "nodes/node_common.h"

namespace specula::nodes {
SPECULA_DESCRIBE_CATEGORY("texture",
    "Plain string inputs (`file`, `colorspace`) are literals resolved on the host (a `file` is relative "
    "to the scene file); enum choices reach GLSL as their index. For a node with a `sampler2D` in its "
    "prototype the emitter declares `layout(binding = i) uniform sampler2D spc_tex_<node>`.");
}  // namespace specula::nodes
