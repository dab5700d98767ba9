// closure.coat: a clear coat over any closure (car paint = base + flakes + coat). The coat is a dielectric GGX
// reflection lobe (GgxLobe, exact dielectric Fresnel); the base below keeps the energy the coat does not reflect,
// by albedo scaling (OpenPBR 1.0 §"Coat", Blender Principled v2, MaterialX layer):
//   closure = weight · coat + lerp(1, tint · (1 − E(μo)), weight) · base,
// E(μo, roughness, ior) the coat lobe's directional albedo (coat_albedo.h, tabulated) at μo = wo·n_coat. For tint = 1
// this is (1 − weight·E)·base; weight = 0 leaves the base exactly as it was (lobes, weights, emission). A white
// base of albedo 1 stays at albedo weight·E + (1 − weight·E) = 1 (the white-furnace test, tests/unit/test_coat.cpp).
// The scaling depends on wo only (as in every albedo-scaling layer), so the layered closure is not reciprocal.
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/shared/ltc_gpu.h"
#include "core/render/lobes/ggx.h"
#include "nodes/closure/coat/coat_albedo.h"

namespace specula::nodes {
namespace {

struct Params {
    ClosureRef base;
    float weight, roughness, ior;
    Color3 tint;
    Vec3 normal, tangent;
};

const NodeParams<Params> kParams = NodeParams<Params>()
    .closure("base", &Params::base, "the closure under the coat")
    .f("weight", &Params::weight, 1.f, "coat amount: 0 = no coat, 1 = full coat").range(0.f, 1.f).hard(0.f, 1.f)
    .f("roughness", &Params::roughness, 0.05f, "coat perceptual roughness, α = roughness²").range(0.f, 1.f).hard(0.f, 1.f)
    .f("ior", &Params::ior, 1.5f, "coat IOR (exact dielectric Fresnel; tabulated for 1..3)").range(1.f, 3.f).hard(1.f, 3.f)
    .c3("tint", &Params::tint, Vec3(1.f), "coat colour: absorption applied to the base seen through the coat").range(0.f, 1.f).hard(0.f, 1.f)
    .n3("normal", &Params::normal, Vec3(0, 0, 1), "coat normal (the shading normal; the base keeps its own)").bind(GeomBinding::N)
    .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent of the coat frame (the coat is isotropic)").bind(GeomBinding::T);
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "coat + albedo-scaled base");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    const int o = slotOf(c, i, kBsdf);
    Closure& dst = *c.closures[o];
    dst.clear();
    const float w = std::clamp(p.weight, 0.f, 1.f), ior = std::clamp(p.ior, coat::kMinIor, coat::kMaxIor);
    const float r = std::clamp(p.roughness, 0.f, 1.f);
    const Frame f = bsdfFrame(p.normal, p.tangent);
    // μo of the coat lobe (its wo.z); without a shading point (no view) the coat is seen head-on.
    const float mu = c.sp ? glm::dot(c.sp->wo, f.n) : 1.f;
    const float e = w > 0.f ? coat::albedo(mu, r, ior) : 0.f;
    const Color3 baseScale = Color3(1.f - w) + w * p.tint * (1.f - e);  // lerp(1, tint·(1 − E), w)
    dst.append(*c.closures[p.base.slot], baseScale);
    if (w > 0.f) dst.add(Color3(w), c.arena->make<GgxLobe>(r * r, r * r, Fresnel::dielectric(ior)), f);
    // Emission below the coat leaves through it along wo: the same transmittance as the base's reflected light.
    c.emission[o] = c.emission[p.base.slot] * baseScale;
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "closure.coat";
    s.category = "closure";
    s.doc = "Clear coat over a closure (car paint: coat over base + flakes): weight · dielectric GGX coat (exact "
            "Fresnel, α = roughness²) + lerp(1, tint·(1 − E(μo)), weight) · base, E(μo, roughness, ior) the coat's "
            "directional albedo, tabulated (32 μo × 32 roughness × 16 F0 nodes, ior 1..3) by quadrature at first use "
            "(energy-conserving albedo scaling as OpenPBR / MaterialX layer: a white base keeps albedo 1, measured "
            "within 0.4 % for μo 0.1..1; table vs Monte Carlo within 0.21 % absolute). weight 0 is the base exactly; "
            "for tint 1 the base scale is 1 − weight·E. 'normal' is the coat's own (the shading normal by default), so "
            "a flake normal map can sit under a smooth coat. Not reciprocal (the scale depends on wo, as in every "
            "albedo-scaling layer). Quad lights: the coat lobe's LTC (as bsdf.ggx) plus the scaled base's answers.";
    kParams.describe(s);
    s.outputs = kOutputs.ports();
    s.cpu = &cpu;
    s.glslFunction = "spc_closure_coat";
    s.glslFile = "closure/coat/coat.glsl";
    s.glslLibraries = {"shared/ltc.glsl", "shared/ggx_microfacet.glsl"};
    s.resources = {coat::albedoResource(), ltc::matrixResource(), ltc::amplitudeResource()};
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
