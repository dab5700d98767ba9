// bsdf.ggx: anisotropic GGX microfacet reflection with height-correlated Smith G2, unfiltered
// (core/render/lobes/ggx.h GgxLobe). α from roughness and anisotropy (nodes/shared/bsdf_ports.h); the Fresnel term is
// evaluated per microfacet at wo·h (Schlick F0, exact dielectric IOR, or exact conductor eta + ik).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/shared/ltc_gpu.h"
#include "core/render/lobes/ggx.h"
#include "nodes/shared/bsdf_ports.h"

namespace specula::nodes {
namespace {

struct Params {
    Color3 weight;
    float roughness, anisotropy;
    FresnelModel fresnel;
    Color3 f0;
    float ior;
    Color3 eta, k;
    Vec3 normal, tangent;
};

NodeParams<Params> declare() {
    NodeParams<Params> l;
    l.c3("weight", &Params::weight, Vec3(1.f), "tint / layer weight").range(0.f, 1.f).soft(0.f, 1.f).hard(0.f, 1e6f)
        .f("roughness", &Params::roughness, 0.5f, "perceptual roughness, α = roughness²").range(0.f, 1.f).hard(0.f, 1.f)
        .f("anisotropy", &Params::anisotropy, 0.f, "0 = isotropic; stretches α along the tangent").range(0.f, 1.f).hard(0.f, 1.f)
        .orientsByTangent();
    fresnelPorts(l);
    l.n3("normal", &Params::normal, Vec3(0, 0, 1), "shading normal (e.g. from texture.normal_map)").bind(GeomBinding::N)
        .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent: direction of αx").bind(GeomBinding::T);
    return l;
}
const NodeParams<Params> kParams = declare();
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "the specular closure");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    const Vec2 a = alphaFromRoughness(p.roughness, p.anisotropy);
    emitLobe(c, i, kBsdf, bsdfFrame(p.normal, p.tangent), p.weight, c.arena->make<GgxLobe>(a.x, a.y, fresnelOf(p)));
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("bsdf.ggx",
                             "Anisotropic GGX reflection, height-correlated Smith masking-shadowing (Heitz 2014, Eq. "
                             "99), unfiltered. Quad lights in closed form (polygon queries): its fitted LTC (HDHN16), "
                             "Fresnel as F0·mag + (1 − F0)·fres.",
                             kParams, kOutputs, &cpu);
    s.notes = "α = roughness² (Burley 2012); aspect a = √(1 − 0.9·anisotropy), αx = α/a, αy = α·a (Burley 2012, "
              "addendum B.2), αx and αy clamped at 1e-4 like `GgxLobe`; `fresnel` is evaluated per microfacet at "
              "wo·h. CPU: `GgxLobe` (anisotropic GGX D, Walter et al. 2007 Eq. 33; height-correlated Smith G2, Heitz "
              "2014 Eq. 99; VNDF sampling, Heitz 2018), unfiltered. GLSL: the same eval, f·cos = weight·F·D·G2/(4 "
              "wo.z).";
    s.glslLibraries = {"shared/ltc.glsl", "shared/fresnel_f0.glsl", "shared/ggx_microfacet.glsl"};
    // Polygon queries (LTC quad lights): the isotropic and anisotropic GGX fits and the mag/fres/sphere table.
    s.resources = {ltc::matrixResource(), ltc::amplitudeResource(), ltc::anisotropicResource()};
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
