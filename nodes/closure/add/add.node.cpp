// closure.add: the sum of two closures (lobes concatenated, emissions added; at most
// Closure::kMaxLobes lobes survive).
#include "nodes/node_common.h"

#include "core/render/bsdf.h"

namespace specula::nodes {
namespace {
struct Params {
    ClosureRef a, b;
};
const NodeParams<Params> kParams =
    NodeParams<Params>().closure("a", &Params::a, "first closure").closure("b", &Params::b, "second closure");
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "a + b");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    const int o = slotOf(c, i, kBsdf);
    Closure& dst = *c.closures[o];
    dst.clear();
    dst.append(*c.closures[p.a.slot]);
    dst.append(*c.closures[p.b.slot]);
    c.emission[o] = c.emission[p.a.slot] + c.emission[p.b.slot];
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("closure.add", "Sum of two closures a + b.", kParams, kOutputs, &cpu);
    s.notes = "Lobes are concatenated, at most `Closure::kMaxLobes` = 8.";
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
