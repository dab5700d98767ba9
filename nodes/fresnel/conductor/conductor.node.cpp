// fresnel.conductor: Exact conductor Fresnel reflectance for a complex IOR eta + i k per RGB channel (unpolarised average of r_s and r_p).
#include "nodes/node_common.h"

#include "core/render/lobes/fresnel.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    Vec3 e = inV3(c, i, 0), k = inV3(c, i, 1); float ct = inF(c, i, 2); outV3(c, i, 0, Vec3(fresnelConductor(ct, e.x, k.x), fresnelConductor(ct, e.y, k.y), fresnelConductor(ct, e.z, k.z)));
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "fresnel.conductor";
    s.category = "fresnel";
    s.doc = "Exact conductor Fresnel reflectance for a complex IOR eta + i k per RGB channel (unpolarised average of r_s and r_p).";
    s.inputs = {std::move(PortSpec::c3("eta", Vec3(0.143f, 0.374f, 1.442f), "real part of the IOR (default: gold)")).range(0.1f, 3.f), std::move(PortSpec::c3("k", Vec3(3.983f, 2.385f, 1.603f), "imaginary part (extinction)")).range(0.f, 5.f),
                std::move(PortSpec::f("cos_theta", 1.f, "cosine of the incidence angle (default: N·V)")).range(0.f, 1.f).bind(GeomBinding::NdotV)};
    s.outputs = {PortSpec::out("F", TypeDesc::Color3, "reflectance")};
    s.flags = kPure;
    s.cpu = &cpu;
    s.glslFunction = "spc_fresnel_conductor_node";
    s.glslFile = "fresnel/conductor/conductor.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
