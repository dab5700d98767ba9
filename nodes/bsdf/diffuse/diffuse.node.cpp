// bsdf.diffuse: Lambertian reflection f = color/π in the frame of its normal input (LambertLobe).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "core/render/lobes/lambert.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    Frame f = bsdfFrame(inV3(c, i, 1), inV3(c, i, 2));
    emitLobe(c, i, 0, f, Color3(1.f), c.arena->make<LambertLobe>(inV3(c, i, 0)));
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "bsdf.diffuse";
    s.category = "bsdf";
    s.doc = "Lambertian diffuse reflection, f = color/π.";
    s.inputs = {std::move(PortSpec::c3("color", Vec3(0.8f), "albedo")).range(0.f, 1.f),
                std::move(PortSpec::n3("normal", Vec3(0, 0, 1), "shading normal")).bind(GeomBinding::N),
                std::move(PortSpec::v3("tangent", Vec3(1, 0, 0), "tangent (orients the frame)")).bind(GeomBinding::T)};
    s.outputs = {PortSpec::out("bsdf", TypeDesc::Closure, "the diffuse closure")};
    s.flags = kGlslDirections;
    s.cpu = &cpu;
    s.glslFunction = "spc_bsdf_diffuse";
    s.glslFile = "bsdf/diffuse/diffuse.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
