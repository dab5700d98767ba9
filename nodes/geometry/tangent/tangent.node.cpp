// geometry.tangent: Mesh tangent T (world) and the bitangent sign.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
OutputList kOutputs;
const OutPort<Vec3> kOutT = kOutputs.add<Vec3>("T", TypeDesc::Vector3, "tangent");
const OutPort<float> kOutSign = kOutputs.add<float>("sign", TypeDesc::Float, "bitangent sign (B = sign * cross(N, T))");

void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    set(c, i, kOutT, Vec3(sp.tangent));
    set(c, i, kOutSign, sp.tangent.w);
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.tangent";
    s.category = "geometry";
    s.doc = "Mesh tangent T (world) and the bitangent sign.";
    s.outputs = kOutputs.ports();
    s.flags = kReadsUv;  // the tangent of a mesh is made from its uvs
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_tangent";
    s.glslFile = "geometry/tangent/tangent.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
