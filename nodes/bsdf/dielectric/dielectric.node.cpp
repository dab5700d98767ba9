// bsdf.dielectric: rough glass, the GGX microfacet interface of Walter et al. 2007 that reflects (GgxLobe with the
// exact dielectric Fresnel) and refracts (GgxTransmissionLobe, core/render/lobes/dielectric.h) with one roughness.
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/shared/ltc_gpu.h"
#include "core/render/lobes/dielectric.h"
#include "core/render/lobes/ggx.h"
#include "nodes/shared/bsdf_ports.h"

namespace specula::nodes {
namespace {

struct Params {
    Color3 weight, reflectionTint, transmissionTint;
    float roughness, anisotropy, ior, frontFacing;
    Vec3 normal, tangent;
};

NodeParams<Params> declare() {
    NodeParams<Params> l;
    l.c3("weight", &Params::weight, Vec3(1.f), "layer weight").range(0.f, 1.f).soft(0.f, 1.f).hard(0.f, 1e6f)
        .c3("reflection_tint", &Params::reflectionTint, Vec3(1.f), "tint of the reflected light").range(0.f, 1.f).hard(0.f, 1.f)
        .c3("transmission_tint", &Params::transmissionTint, Vec3(1.f),
            "tint of the refracted light, applied at each crossing of the interface").range(0.f, 1.f).hard(0.f, 1.f)
        .f("roughness", &Params::roughness, 0.1f, "perceptual roughness, α = roughness² (0: polished glass)").range(0.f, 1.f).hard(0.f, 1.f)
        .f("anisotropy", &Params::anisotropy, 0.f, "0 = isotropic; stretches α along the tangent").range(0.f, 1.f).hard(0.f, 1.f)
        .orientsByTangent()
        .f("ior", &Params::ior, 1.5f, "index of refraction of the inside (the side opposite the normal) over the outside")
        .range(1.05f, 2.5f).hard(1.0001f, 10.f)
        .f("front_facing", &Params::frontFacing, 1.f,
           "1 where the viewer is outside (on the normal's side), 0 inside: the relative IOR is then 1/ior")
        .range(0.f, 1.f).hard(0.f, 1.f).bind(GeomBinding::FrontFacing)
        .n3("normal", &Params::normal, Vec3(0, 0, 1), "shading normal (e.g. from texture.normal_map)").bind(GeomBinding::N)
        .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent: direction of αx").bind(GeomBinding::T);
    return l;
}
const NodeParams<Params> kParams = declare();
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "reflection and transmission");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    const Vec2 a = alphaFromRoughness(p.roughness, p.anisotropy);
    // η: the far side's index over the viewer's (GLSL: the same rule on s.front_facing).
    const float eta = p.frontFacing >= 0.5f ? p.ior : 1.f / p.ior;
    const Frame f = bsdfFrame(p.normal, p.tangent);
    emitLobe(c, i, kBsdf, f, p.weight * p.reflectionTint, c.arena->make<GgxLobe>(a.x, a.y, Fresnel::dielectric(eta)));
    c.closures[slotOf(c, i, kBsdf)]->add(p.weight * p.transmissionTint, c.arena->make<GgxTransmissionLobe>(a.x, a.y, eta), f);
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("bsdf.dielectric",
                             "Rough glass (Walter et al. 2007): GGX reflection with the exact dielectric Fresnel and "
                             "GGX refraction, height-correlated Smith masking-shadowing, one roughness for both. The "
                             "path tracer follows refracted paths through closed objects (the IOR inverts inside, by "
                             "`front_facing`); light samples reach it from both sides. Quad lights: the reflection in "
                             "closed form (its LTC), the refraction sampled. Raster/GPU preview: the environment seen "
                             "along the refracted view direction (one refraction, no exit), lights behind the surface "
                             "unlit.",
                             kParams, kOutputs, &cpu);
    s.notes = "η = `ior` outside (`front_facing` ≥ 0.5), 1/`ior` inside; α as `bsdf.ggx`. CPU: `GgxLobe` with "
              "`fresnelDielectric(wo·h, η)` for reflection plus `GgxTransmissionLobe` "
              "(core/render/lobes/dielectric.h) for refraction: f·cos = (1 − F) D G2 |wi·h| |wo·h| / (|wo.z| (wi·h + "
              "wo·h/η')² η'²), η' = n_wi/n_wo, h = normalize(wo + η' wi) (Walter et al. 2007, Eqs. 16 and 21, "
              "radiance form); refraction sampled through a visible normal (Heitz 2018), pdf with the Jacobian of Eq. "
              "17. The closure's lobes scatter only to their side of the geometric surface (`BsdfQuery::ng`). GLSL: "
              "the same direction eval; polygon queries as `bsdf.ggx` with `partial` set for a polygon below the "
              "surface; environment queries add (1 − F(wo.z)) times `spc_host_environment` along the refracted view "
              "direction at α·|1 − 1/η|/2.";
    s.glslLibraries = {"shared/ltc.glsl", "shared/ggx_microfacet.glsl"};
    // Polygon and environment queries of the reflection: bsdf.ggx's LTC tables.
    s.resources = {ltc::matrixResource(), ltc::amplitudeResource(), ltc::anisotropicResource()};
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
