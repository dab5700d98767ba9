// geometry.position: World-space position P and its screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    outV3(c, i, 0, sp.p); outV3(c, i, 1, sp.dpdx); outV3(c, i, 2, sp.dpdy);
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.position";
    s.category = "geometry";
    s.doc = "World-space position P and its screen-space derivatives.";
    s.outputs = {PortSpec::out("P", TypeDesc::Vector3, "position"), PortSpec::out("dPdx", TypeDesc::Vector3, "dP/dx per pixel"), PortSpec::out("dPdy", TypeDesc::Vector3, "dP/dy per pixel")};
    s.flags = kGlslShading | kNeedsDerivatives;
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_position";
    s.glslFile = "geometry/position/position.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
