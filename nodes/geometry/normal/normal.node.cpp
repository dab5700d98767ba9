// geometry.normal: Shading normal N (world) and its screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) { setOutputs(c, i, c.sp->n, c.sp->dndx, c.sp->dndy); }
}  // namespace
SPECULA_REGISTER_NODE(declareNode("geometry.normal", "Shading normal N (world) and its screen-space derivatives.",
                                  {PortSpec::out("N", TypeDesc::Normal3, "shading normal"),
                                   PortSpec::out("dNdx", TypeDesc::Vector3, "dN/dx per pixel"),
                                   PortSpec::out("dNdy", TypeDesc::Vector3, "dN/dy per pixel")},
                                  &cpu, kNeedsDerivatives));
}  // namespace specula::nodes
