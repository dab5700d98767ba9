// geometry.tangent: Mesh tangent T (world) and the bitangent sign.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    outV3(c, i, 0, Vec3(sp.tangent)); outF(c, i, 1, sp.tangent.w);
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.tangent";
    s.category = "geometry";
    s.doc = "Mesh tangent T (world) and the bitangent sign.";
    s.outputs = {PortSpec::out("T", TypeDesc::Vector3, "tangent"), PortSpec::out("sign", TypeDesc::Float, "bitangent sign (B = sign * cross(N, T))")};
    s.flags = kGlslShading;
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_tangent";
    s.glslFile = "geometry/tangent/tangent.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
