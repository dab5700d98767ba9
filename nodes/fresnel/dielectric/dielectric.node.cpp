// fresnel.dielectric: Exact unpolarised dielectric Fresnel reflectance for relative IOR (Walter et al. 2007, Eq. 22); 1 under total internal reflection.
#include "nodes/node_common.h"

#include "core/render/lobes/fresnel.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    outF(c, i, 0, fresnelDielectric(inF(c, i, 1), inF(c, i, 0)));
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "fresnel.dielectric";
    s.category = "fresnel";
    s.doc = "Exact unpolarised dielectric Fresnel reflectance for relative IOR (Walter et al. 2007, Eq. 22); 1 under total internal reflection.";
    s.inputs = {std::move(PortSpec::f("ior", 1.5f, "relative index of refraction n_t/n_i")).range(1.0f, 3.f),
                std::move(PortSpec::f("cos_theta", 1.f, "cosine of the incidence angle (default: N·V)")).range(0.f, 1.f).bind(GeomBinding::NdotV)};
    s.outputs = {PortSpec::out("F", TypeDesc::Float, "reflectance")};
    s.flags = kPure;
    s.cpu = &cpu;
    s.glslFunction = "spc_fresnel_dielectric_node";
    s.glslFile = "fresnel/dielectric/dielectric.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
