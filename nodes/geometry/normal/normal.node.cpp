// geometry.normal: Shading normal N (world) and its screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    outV3(c, i, 0, sp.n); outV3(c, i, 1, sp.dndx); outV3(c, i, 2, sp.dndy);
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.normal";
    s.category = "geometry";
    s.doc = "Shading normal N (world) and its screen-space derivatives.";
    s.outputs = {PortSpec::out("N", TypeDesc::Normal3, "shading normal"), PortSpec::out("dNdx", TypeDesc::Vector3, "dN/dx per pixel"), PortSpec::out("dNdy", TypeDesc::Vector3, "dN/dy per pixel")};
    s.flags = kGlslShading | kNeedsDerivatives;
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_normal";
    s.glslFile = "geometry/normal/normal.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
