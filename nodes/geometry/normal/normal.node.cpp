// geometry.normal: Shading normal N (world) and its screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
OutputList kOutputs;
const OutPort<Vec3> kOutN = kOutputs.add<Vec3>("N", TypeDesc::Normal3, "shading normal");
const OutPort<Vec3> kOutDNdx = kOutputs.add<Vec3>("dNdx", TypeDesc::Vector3, "dN/dx per pixel");
const OutPort<Vec3> kOutDNdy = kOutputs.add<Vec3>("dNdy", TypeDesc::Vector3, "dN/dy per pixel");

void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    set(c, i, kOutN, sp.n);
    set(c, i, kOutDNdx, sp.dndx);
    set(c, i, kOutDNdy, sp.dndy);
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.normal";
    s.category = "geometry";
    s.doc = "Shading normal N (world) and its screen-space derivatives.";
    s.outputs = kOutputs.ports();
    s.flags = kNeedsDerivatives;
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_normal";
    s.glslFile = "geometry/normal/normal.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
