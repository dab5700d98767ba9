// geometry.position: World-space position P and its screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) { setOutputs(c, i, c.sp->p, c.sp->dpdx, c.sp->dpdy); }
}  // namespace
SPECULA_REGISTER_NODE(declareNode("geometry.position", "World-space position P and its screen-space derivatives.",
                                  {PortSpec::out("P", TypeDesc::Vector3, "position"),
                                   PortSpec::out("dPdx", TypeDesc::Vector3, "dP/dx per pixel"),
                                   PortSpec::out("dPdy", TypeDesc::Vector3, "dP/dy per pixel")},
                                  &cpu, kNeedsDerivatives));
}  // namespace specula::nodes
