// geometry.geometric_normal: Geometric normal Ng (world).
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    outV3(c, i, 0, sp.ng);
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.geometric_normal";
    s.category = "geometry";
    s.doc = "Geometric normal Ng (world).";
    s.outputs = {PortSpec::out("Ng", TypeDesc::Normal3, "geometric normal")};
    s.flags = kGlslShading;
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_geometric_normal";
    s.glslFile = "geometry/geometric_normal/geometric_normal.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
