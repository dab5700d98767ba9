// fresnel.schlick: Schlick's approximation F0 + (1 - F0)(1 - cos)^5 (Schlick 1994, Eq. 24).
#include "nodes/node_common.h"

#include "core/render/lobes/fresnel.h"

namespace specula::nodes {
namespace {
struct Params {
    Vec3 f0;
    float cosTheta;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .c3("f0", &Params::f0, Vec3(0.04f), "reflectance at normal incidence").range(0.f, 1.f).hard(0.f, 1.f)
    .f("cos_theta", &Params::cosTheta, 1.f, "cosine of the incidence angle (default: N·V)").range(0.f, 1.f).bind(GeomBinding::NdotV);
OutputList kOutputs;
const OutPort<Vec3> kF = kOutputs.add<Vec3>("F", TypeDesc::Color3, "reflectance");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    set(c, i, kF, fresnelSchlick(p.cosTheta, p.f0));
}
}  // namespace
SPECULA_REGISTER_NODE(fresnelNode("fresnel.schlick",
                                  "Schlick's approximation F0 + (1 - F0)(1 - cos)^5 (Schlick 1994, Eq. 24).",
                                  kParams, kOutputs, &cpu));
}  // namespace specula::nodes
