// fresnel.conductor: Exact conductor Fresnel reflectance for a complex IOR eta + i k per RGB channel (unpolarised average of r_s and r_p).
#include "nodes/node_common.h"

#include "core/render/lobes/fresnel.h"

namespace specula::nodes {
namespace {
struct Params {
    Vec3 eta, k;
    float cosTheta;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .c3("eta", &Params::eta, Vec3(0.143f, 0.374f, 1.442f), "real part of the IOR (default: gold)").range(0.1f, 3.f).hard(0.f, 1e3f)
    .c3("k", &Params::k, Vec3(3.983f, 2.385f, 1.603f), "imaginary part (extinction)").range(0.f, 10.f).hard(0.f, 1e3f)
    .f("cos_theta", &Params::cosTheta, 1.f, "cosine of the incidence angle (default: N·V)").range(0.f, 1.f).bind(GeomBinding::NdotV);
OutputList kOutputs;
const OutPort<Vec3> kF = kOutputs.add<Vec3>("F", TypeDesc::Color3, "reflectance");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    set(c, i, kF, Vec3(fresnelConductor(p.cosTheta, p.eta.x, p.k.x), fresnelConductor(p.cosTheta, p.eta.y, p.k.y),
                       fresnelConductor(p.cosTheta, p.eta.z, p.k.z)));
}
}  // namespace
SPECULA_REGISTER_NODE(fresnelNode("fresnel.conductor",
                                  "Exact conductor Fresnel reflectance for a complex IOR eta + i k per RGB channel "
                                  "(unpolarised average of r_s and r_p).",
                                  kParams, kOutputs, &cpu));
}  // namespace specula::nodes
