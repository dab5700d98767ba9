// fresnel.schlick: Schlick's approximation F0 + (1 - F0)(1 - cos)^5 (Schlick 1994, Eq. 24).
#include "nodes/node_common.h"

#include "core/render/lobes/fresnel.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    outV3(c, i, 0, fresnelSchlick(inF(c, i, 1), inV3(c, i, 0)));
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "fresnel.schlick";
    s.category = "fresnel";
    s.doc = "Schlick's approximation F0 + (1 - F0)(1 - cos)^5 (Schlick 1994, Eq. 24).";
    s.inputs = {std::move(PortSpec::c3("f0", Vec3(0.04f), "reflectance at normal incidence")).range(0.f, 1.f),
                std::move(PortSpec::f("cos_theta", 1.f, "cosine of the incidence angle (default: N·V)")).range(0.f, 1.f).bind(GeomBinding::NdotV)};
    s.outputs = {PortSpec::out("F", TypeDesc::Color3, "reflectance")};
    s.flags = kPure;
    s.cpu = &cpu;
    s.glslFunction = "spc_fresnel_schlick_node";
    s.glslFile = "fresnel/schlick/schlick.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
