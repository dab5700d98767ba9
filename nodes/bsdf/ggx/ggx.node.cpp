// bsdf.ggx: anisotropic GGX microfacet reflection with height-correlated Smith G2, unfiltered
// (core/render/lobes/ggx.h GgxLobe). α = roughness² (Burley 2012), anisotropy via the aspect
// a = sqrt(1 − 0.9·anisotropy): αx = α/a, αy = α·a (Burley 2012, addendum B.2); the Fresnel term is
// evaluated per microfacet at wo·h (Schlick F0, exact dielectric IOR, or exact conductor eta + ik).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "core/render/lobes/ggx.h"

namespace specula::nodes {
namespace {

void cpu(EvalContext& c, const Instr& i) {
    float rough = inF(c, i, 1);
    float aniso = inF(c, i, 2);
    float alpha = rough * rough;
    float aspect = std::sqrt(std::max(1.f - 0.9f * aniso, 0.f));
    float ax = alpha / aspect, ay = alpha * aspect;
    Fresnel fr;
    switch (inEnum(i, 3)) {
        case 0: fr = Fresnel::schlick(inV3(c, i, 4)); break;
        case 1: fr = Fresnel::dielectric(inF(c, i, 5)); break;
        case 2: fr = Fresnel::conductor(inV3(c, i, 6), inV3(c, i, 7)); break;
        default: fr = Fresnel::one(); break;
    }
    Frame f = bsdfFrame(inV3(c, i, 8), inV3(c, i, 9));
    emitLobe(c, i, 0, f, inV3(c, i, 0), c.arena->make<GgxLobe>(ax, ay, fr));
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "bsdf.ggx";
    s.category = "bsdf";
    s.doc = "Anisotropic GGX reflection, height-correlated Smith masking-shadowing (Heitz 2014, Eq. 99), unfiltered.";
    s.inputs = {std::move(PortSpec::c3("weight", Vec3(1.f), "tint / layer weight")).range(0.f, 1.f),
                std::move(PortSpec::f("roughness", 0.5f, "perceptual roughness, α = roughness²")).range(0.f, 1.f),
                std::move(PortSpec::f("anisotropy", 0.f, "0 = isotropic; stretches α along the tangent")).range(0.f, 1.f),
                PortSpec::choice("fresnel", {"schlick", "dielectric", "conductor", "none"}, "Fresnel model at wo·h"),
                std::move(PortSpec::c3("f0", Vec3(0.04f), "Schlick F0")).range(0.f, 1.f),
                std::move(PortSpec::f("ior", 1.5f, "dielectric IOR")).range(1.f, 3.f),
                std::move(PortSpec::c3("eta", Vec3(0.143f, 0.374f, 1.442f), "conductor IOR real part (gold)")).range(0.1f, 3.f),
                std::move(PortSpec::c3("k", Vec3(3.983f, 2.385f, 1.603f), "conductor IOR imaginary part (gold)")).range(0.f, 5.f),
                std::move(PortSpec::n3("normal", Vec3(0, 0, 1), "shading normal (e.g. from texture.normal_map)")).bind(GeomBinding::N),
                std::move(PortSpec::v3("tangent", Vec3(1, 0, 0), "tangent: direction of αx")).bind(GeomBinding::T)};
    s.outputs = {PortSpec::out("bsdf", TypeDesc::Closure, "the specular closure")};
    s.flags = kGlslDirections;
    s.cpu = &cpu;
    s.glslFunction = "spc_bsdf_ggx";
    s.glslFile = "bsdf/ggx/ggx.glsl";
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
