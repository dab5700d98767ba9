// closure.add: the sum of two closures (lobes concatenated, emissions added; at most
// Closure::kMaxLobes lobes survive).
#include "nodes/node_common.h"

#include "core/render/bsdf.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    int a = inClosure(c, i, 0), b = inClosure(c, i, 1), o = outClosure(c, i, 0);
    Closure& dst = *c.closures[o];
    dst.clear();
    dst.append(*c.closures[a]);
    dst.append(*c.closures[b]);
    c.emission[o] = c.emission[a] + c.emission[b];
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "closure.add";
    s.category = "closure";
    s.doc = "Sum of two closures a + b.";
    s.inputs = {PortSpec::closure("a", "first closure"), PortSpec::closure("b", "second closure")};
    s.outputs = {PortSpec::out("bsdf", TypeDesc::Closure, "a + b")};
    s.cpu = &cpu;
    s.glslFunction = "spc_closure_add";
    s.glslFile = "closure/add/add.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
