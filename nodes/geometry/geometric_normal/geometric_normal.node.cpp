// geometry.geometric_normal: Geometric normal Ng (world).
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) { setOutputs(c, i, c.sp->ng); }
}  // namespace
SPECULA_REGISTER_NODE(declareNode("geometry.geometric_normal", "Geometric normal Ng (world).",
                                  {PortSpec::out("Ng", TypeDesc::Normal3, "geometric normal")}, &cpu));
}  // namespace specula::nodes
