// bsdf.diffuse: Lambertian reflection f = color/π in the frame of its normal input (LambertLobe).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/shared/ltc_gpu.h"
#include "core/render/lobes/lambert.h"

namespace specula::nodes {
namespace {

struct Params {
    Color3 color;
    Vec3 normal, tangent;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .c3("color", &Params::color, Vec3(0.8f), "albedo").range(0.f, 1.f).soft(0.f, 1.f).hard(0.f, 1e6f)
    .n3("normal", &Params::normal, Vec3(0, 0, 1), "shading normal").bind(GeomBinding::N)
    .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent (orients the frame)").bind(GeomBinding::T);
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "the diffuse closure");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    emitLobe(c, i, kBsdf, bsdfFrame(p.normal, p.tangent), Color3(1.f), c.arena->make<LambertLobe>(p.color));
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("bsdf.diffuse",
                             "Lambertian diffuse reflection, f = color/π. Quad lights in closed form (polygon "
                             "queries): Lambert's form factor (the LTC with M = I).",
                             kParams, kOutputs, &cpu);
    s.notes = "CPU: `LambertLobe`.";
    s.glslLibraries = {"shared/ltc.glsl"};
    // Polygon queries: the clip-free horizon reads the sphere channel of the shared LTC amplitude table.
    s.resources = {ltc::amplitudeResource()};
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
