// fresnel.dielectric: Exact unpolarised dielectric Fresnel reflectance for relative IOR (Walter et al. 2007, Eq. 22); 1 under total internal reflection.
#include "nodes/node_common.h"

#include "core/render/lobes/fresnel.h"

namespace specula::nodes {
namespace {
struct Params {
    float ior, cosTheta;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .f("ior", &Params::ior, 1.5f, "relative index of refraction n_t/n_i").range(1.0f, 3.f).hard(1e-3f, 1e3f)
    .f("cos_theta", &Params::cosTheta, 1.f, "cosine of the incidence angle (default: N·V)").range(0.f, 1.f).bind(GeomBinding::NdotV);
OutputList kOutputs;
const OutPort<float> kF = kOutputs.add<float>("F", TypeDesc::Float, "reflectance");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    set(c, i, kF, fresnelDielectric(p.cosTheta, p.ior));
}
}  // namespace
SPECULA_REGISTER_NODE(fresnelNode("fresnel.dielectric",
                                  "Exact unpolarised dielectric Fresnel reflectance for relative IOR (Walter et al. 2007, "
                                  "Eq. 22); 1 under total internal reflection.",
                                  kParams, kOutputs, &cpu));
}  // namespace specula::nodes
