// closure.mix: a·(1 − t) + b·t (lobe weights and emissions scaled).
#include "nodes/node_common.h"

#include "core/render/bsdf.h"

namespace specula::nodes {
namespace {
struct Params {
    ClosureRef a, b;
    float t;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .closure("a", &Params::a, "closure at t = 0")
    .closure("b", &Params::b, "closure at t = 1")
    .f("t", &Params::t, 0.5f, "blend factor").range(0.f, 1.f).hard(0.f, 1.f);
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "a·(1 − t) + b·t");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    const int o = slotOf(c, i, kBsdf);
    Closure& dst = *c.closures[o];
    dst.clear();
    dst.append(*c.closures[p.a.slot], Color3(1.f - p.t));
    dst.append(*c.closures[p.b.slot], Color3(p.t));
    c.emission[o] = c.emission[p.a.slot] * (1.f - p.t) + c.emission[p.b.slot] * p.t;
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("closure.mix", "Blend of two closures a·(1 − t) + b·t.", kParams, kOutputs, &cpu);
    s.notes = "Lobe weights and emission are scaled.";
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
