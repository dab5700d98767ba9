// bsdf.sheen: the Charlie sheen of Estevez & Kulla 2017 (SheenLobe, sheen_lobe.h in this folder), the soft back- and
// grazing-angle scattering of cloth fibres and dust, with the paper's fitted Λ visibility; GLSL twin: sheen.glsl.
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/bsdf/sheen/sheen_lobe.h"

namespace specula::nodes {
namespace {

struct Params {
    Color3 color;
    float roughness;
    Vec3 normal;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .c3("color", &Params::color, Vec3(1.f), "sheen colour (tint / layer weight)").range(0.f, 1.f).soft(0.f, 1.f).hard(0.f, 1e6f)
    .f("roughness", &Params::roughness, 0.3f, "fibre spread α (used as is, not squared); clamped to at least 0.08")
        .range(0.f, 1.f).hard(0.f, 1.f)
    .n3("normal", &Params::normal, Vec3(0, 0, 1), "shading normal").bind(GeomBinding::N);
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "the sheen closure");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    // Isotropic: any tangent completes the frame.
    emitLobe(c, i, kBsdf, bsdfFrame(p.normal, Vec3(1, 0, 0)), Color3(1.f), c.arena->make<SheenLobe>(p.roughness, p.color));
}

void reg(NodeRegistry& r) {
    // id "bsdf.sheen": category bsdf, GLSL spc_bsdf_sheen in bsdf/sheen/sheen.glsl (declareNode, nodes/node_common.h).
    NodeSpec s = declareNode("bsdf.sheen",
                             "Charlie sheen for cloth and dust (Estevez & Kulla 2017): D = (2 + 1/α) sin(θh)^(1/α) / "
                             "(2π) with their fitted Λ, G2 = 1/(1 + Λo + Λi). Quad lights are sampled (no closed form).",
                             kParams, kOutputs, &cpu);
    s.notes = "f·cos θi = color · D(h) G2(wo, wi) / (4 cos θo), α = roughness clamped to [0.08, 1] (below, the fitted "
              "Λ lets the albedo exceed 1 at grazing views); Λ(θ) = exp(L(cos θ)) below 60°, exp(2 L(0.5) − L(1 − cos θ)) "
              "above, L(x) = a/(1 + b x^c) + d x + e with the paper's Table 1 coefficients interpolated in (1 − α)². "
              "Sampled uniformly over the hemisphere. CPU: SheenLobe (nodes/bsdf/sheen/sheen_lobe.h); GLSL: spc_bsdf_sheen "
              "(nodes/bsdf/sheen/sheen.glsl), which answers polygon queries as partial (the host samples the lobe).";
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
