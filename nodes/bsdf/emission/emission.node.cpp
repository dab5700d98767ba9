// bsdf.emission: emitted radiance color·strength (Material::emission), no scattering.
#include "nodes/node_common.h"

#include "core/render/bsdf.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    int slot = outClosure(c, i, 0);
    c.closures[slot]->clear();
    c.emission[slot] = inV3(c, i, 0) * inF(c, i, 1);
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "bsdf.emission";
    s.category = "bsdf";
    s.doc = "Emission closure: radiance color·strength (both sides), no scattering.";
    s.inputs = {std::move(PortSpec::c3("color", Vec3(1.f), "emitted colour")).range(0.f, 1.f),
                std::move(PortSpec::f("strength", 1.f, "radiance scale")).range(0.f, 10.f)};
    s.outputs = {PortSpec::out("bsdf", TypeDesc::Closure, "the emission closure")};
    s.flags = kEmissive;
    s.cpu = &cpu;
    s.glslFunction = "spc_bsdf_emission";
    s.glslFile = "bsdf/emission/emission.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
