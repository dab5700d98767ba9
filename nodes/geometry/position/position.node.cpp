// geometry.position: World-space position P and its screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
OutputList kOutputs;
const OutPort<Vec3> kOutP = kOutputs.add<Vec3>("P", TypeDesc::Vector3, "position");
const OutPort<Vec3> kOutDPdx = kOutputs.add<Vec3>("dPdx", TypeDesc::Vector3, "dP/dx per pixel");
const OutPort<Vec3> kOutDPdy = kOutputs.add<Vec3>("dPdy", TypeDesc::Vector3, "dP/dy per pixel");

void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    set(c, i, kOutP, sp.p);
    set(c, i, kOutDPdx, sp.dpdx);
    set(c, i, kOutDPdy, sp.dpdy);
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.position";
    s.category = "geometry";
    s.doc = "World-space position P and its screen-space derivatives.";
    s.outputs = kOutputs.ports();
    s.flags = kNeedsDerivatives;
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_position";
    s.glslFile = "geometry/position/position.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
