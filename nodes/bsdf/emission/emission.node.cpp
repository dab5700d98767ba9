// bsdf.emission: emitted radiance color·strength (returned with the closure by Material::shade), no scattering.
#include "nodes/node_common.h"

#include "core/render/bsdf.h"

namespace specula::nodes {
namespace {

struct Params {
    Color3 color;
    float strength;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .c3("color", &Params::color, Vec3(1.f), "emitted colour").range(0.f, 1.f).hard(0.f, 1e30f)
    .f("strength", &Params::strength, 1.f, "radiance scale").range(0.f, 10.f).hard(0.f, 1e30f);
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "the emission closure");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    int slot = slotOf(c, i, kBsdf);
    c.closures[slot]->clear();
    c.emission[slot] = p.color * p.strength;
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("bsdf.emission",
                             "Emission closure: radiance color·strength (both sides), no scattering.",
                             kParams, kOutputs, &cpu, kEmissive);
    s.notes = "No lobes: emission only.";
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
