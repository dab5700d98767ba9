// geometry.geometric_normal: Geometric normal Ng (world).
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
OutputList kOutputs;
const OutPort<Vec3> kOutNg = kOutputs.add<Vec3>("Ng", TypeDesc::Normal3, "geometric normal");

void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    set(c, i, kOutNg, sp.ng);
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.geometric_normal";
    s.category = "geometry";
    s.doc = "Geometric normal Ng (world).";
    s.outputs = kOutputs.ports();
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_geometric_normal";
    s.glslFile = "geometry/geometric_normal/geometric_normal.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
