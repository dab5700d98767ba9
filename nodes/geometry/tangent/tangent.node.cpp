// geometry.tangent: Mesh tangent T (world) and the bitangent sign.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) { setOutputs(c, i, Vec3(c.sp->tangent), c.sp->tangent.w); }
}  // namespace
// kReadsUv: the tangent of a mesh is made from its uvs.
SPECULA_REGISTER_NODE(declareNode("geometry.tangent", "Mesh tangent T (world) and the bitangent sign.",
                                  {PortSpec::out("T", TypeDesc::Vector3, "tangent"),
                                   PortSpec::out("sign", TypeDesc::Float, "bitangent sign (B = sign * cross(N, T))")},
                                  &cpu, kReadsUv));
}  // namespace specula::nodes
