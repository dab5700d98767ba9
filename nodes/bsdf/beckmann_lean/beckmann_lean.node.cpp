// bsdf.beckmann_lean: Beckmann reflection whose slope distribution is the LEAN Gaussian (Olano & Baker 2010):
// mean slope μ and covariance Σ from texture.lean plus the material roughness as (α²/2) I, in the unperturbed
// tangent frame; CPU lobe in beckmann_lean.h, GLSL twin in beckmann_lean.glsl.
#include "nodes/node_common.h"

#include "nodes/shared/bsdf_ports.h"

#include "core/graph/closure_util.h"
#include "nodes/shared/ltc_gpu.h"
#include "nodes/bsdf/beckmann_lean/beckmann_lean.h"

namespace specula::nodes {
namespace {

struct Params {
    Color3 weight;
    float roughness;
    Vec2 slope;
    Vec3 covariance;
    FresnelModel fresnel;
    Color3 f0;
    float ior;
    Color3 eta, k;
    Vec3 normal, tangent;
};

NodeParams<Params> declare() {
    NodeParams<Params> l;
    l.c3("weight", &Params::weight, Vec3(1.f), "tint / layer weight").range(0.f, 1.f).soft(0.f, 1.f).hard(0.f, 1e6f)
        .f("roughness", &Params::roughness, 0.3f, "material roughness, Beckmann alpha = roughness^2").range(0.1f, 1.f).hard(0.f, 1.f)
        .v2("slope", &Params::slope, Vec2(0.f), "mean slope (E[x], E[y]) in the (T, N x T) frame").range(-0.5f, 0.5f)
        .v3("covariance", &Params::covariance, Vec3(0.f), "slope covariance (var_x, var_y, cov_xy)").range(0.f, 0.05f);
    fresnelPorts(l);
    l.n3("normal", &Params::normal, Vec3(0, 0, 1), "unperturbed shading normal (LEAN slopes are relative to it)").bind(GeomBinding::N)
        .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent: the slope x axis").bind(GeomBinding::T);
    return l;
}
const NodeParams<Params> kParams = declare();
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "the specular closure");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    lean::SlopeGaussian g = lean::makeSlopeGaussian(p.slope, p.covariance, p.roughness * p.roughness);
    emitLobe(c, i, kBsdf, bsdfFrame(p.normal, p.tangent), p.weight, c.arena->make<BeckmannLeanLobe>(g, fresnelOf(p)));
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("bsdf.beckmann_lean",
                             "Beckmann microfacet reflection with a LEAN slope Gaussian (Olano & Baker 2010): mean "
                             "slope and covariance (e.g. from texture.lean) plus the material roughness as "
                             "(alpha^2/2) I; Smith G2 of the shifted Gaussian. Quad lights in closed form (polygon "
                             "queries): the LTC of an equivalent GGX (tilted frame, alpha^2 = 1.5 Sigma).",
                             kParams, kOutputs, &cpu);
    s.glslLibraries = {"shared/ltc.glsl", "shared/fresnel_f0.glsl"};
    // Polygon queries (LTC quad lights through the equivalent GGX): the GGX fits and the mag/fres/sphere table.
    s.resources = {ltc::matrixResource(), ltc::amplitudeResource(), ltc::anisotropicResource()};
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
