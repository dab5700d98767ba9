// bsdf.beckmann_lean: Beckmann reflection whose slope distribution is the LEAN Gaussian (Olano & Baker 2010):
// mean slope μ and covariance Σ from texture.lean plus the material roughness as (α²/2) I, in the unperturbed
// tangent frame; CPU lobe in beckmann_lean.h, GLSL twin in beckmann_lean.glsl.
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/bsdf/beckmann_lean/beckmann_lean.h"

namespace specula::nodes {
namespace {

void cpu(EvalContext& c, const Instr& i) {
    float rough = inF(c, i, 1);
    lean::SlopeGaussian g = lean::makeSlopeGaussian(inV2(c, i, 2), inV3(c, i, 3), rough * rough);
    Fresnel fr;
    switch (inEnum(i, 4)) {
        case 0: fr = Fresnel::schlick(inV3(c, i, 5)); break;
        case 1: fr = Fresnel::dielectric(inF(c, i, 6)); break;
        case 2: fr = Fresnel::conductor(inV3(c, i, 7), inV3(c, i, 8)); break;
        default: fr = Fresnel::one(); break;
    }
    Frame f = bsdfFrame(inV3(c, i, 9), inV3(c, i, 10));
    emitLobe(c, i, 0, f, inV3(c, i, 0), c.arena->make<BeckmannLeanLobe>(g, fr));
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "bsdf.beckmann_lean";
    s.category = "bsdf";
    s.doc = "Beckmann microfacet reflection with a LEAN slope Gaussian (Olano & Baker 2010): mean slope and covariance "
            "(e.g. from texture.lean) plus the material roughness as (alpha^2/2) I; Smith G2 of the shifted Gaussian.";
    s.inputs = {std::move(PortSpec::c3("weight", Vec3(1.f), "tint / layer weight")).range(0.f, 1.f),
                std::move(PortSpec::f("roughness", 0.3f, "material roughness, Beckmann alpha = roughness^2")).range(0.1f, 1.f),
                std::move(PortSpec::v2("slope", Vec2(0.f), "mean slope (E[x], E[y]) in the (T, N x T) frame")).range(-0.5f, 0.5f),
                std::move(PortSpec::v3("covariance", Vec3(0.f), "slope covariance (var_x, var_y, cov_xy)")).range(0.f, 0.05f),
                PortSpec::choice("fresnel", {"schlick", "dielectric", "conductor", "none"}, "Fresnel model at wo.h"),
                std::move(PortSpec::c3("f0", Vec3(0.04f), "Schlick F0")).range(0.f, 1.f),
                std::move(PortSpec::f("ior", 1.5f, "dielectric IOR")).range(1.f, 3.f),
                std::move(PortSpec::c3("eta", Vec3(0.143f, 0.374f, 1.442f), "conductor IOR real part (gold)")).range(0.1f, 3.f),
                std::move(PortSpec::c3("k", Vec3(3.983f, 2.385f, 1.603f), "conductor IOR imaginary part (gold)")).range(0.f, 5.f),
                std::move(PortSpec::n3("normal", Vec3(0, 0, 1), "unperturbed shading normal (LEAN slopes are relative to it)")).bind(GeomBinding::N),
                std::move(PortSpec::v3("tangent", Vec3(1, 0, 0), "tangent: the slope x axis")).bind(GeomBinding::T)};
    s.outputs = {PortSpec::out("bsdf", TypeDesc::Closure, "the specular closure")};
    s.flags = kGlslDirections;
    s.cpu = &cpu;
    s.glslFunction = "spc_bsdf_beckmann_lean";
    s.glslFile = "bsdf/beckmann_lean/beckmann_lean.glsl";
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
