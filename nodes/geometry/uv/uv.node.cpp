// geometry.uv: Texture coordinates uv0 and their screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
// Texture filtering wants the sample's footprint (shrunk with spp, as in pbrt); the glint LOD wants the whole pixel.
void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    setOutputs(c, i, sp.uv, sp.duvdx, sp.duvdy, sp.duvdx / sp.differentialScale.x, sp.duvdy / sp.differentialScale.y);
}
}  // namespace
SPECULA_REGISTER_NODE(declareNode(
    "geometry.uv",
    "Texture coordinates uv0 and their screen-space derivatives: duvdx/duvdy are the sample's footprint (a pixel step "
    "scaled by max(1/8, 1/sqrt(spp)) on the CPU, for texture filtering), pixel_duvdx/pixel_duvdy one whole pixel step "
    "at any spp (on a GPU both are dFdx/dFdy).",
    {PortSpec::out("uv", TypeDesc::Vec2, "uv0"), PortSpec::out("duvdx", TypeDesc::Vec2, "d(uv)/dx per pixel"),
     PortSpec::out("duvdy", TypeDesc::Vec2, "d(uv)/dy per pixel"),
     PortSpec::out("pixel_duvdx", TypeDesc::Vec2,
                   "d(uv)/dx over one whole pixel at any spp (the glint LOD footprint: bsdf.glint duvdx)"),
     PortSpec::out("pixel_duvdy", TypeDesc::Vec2, "d(uv)/dy over one whole pixel at any spp")},
    &cpu, kNeedsDerivatives | kReadsUv));
}  // namespace specula::nodes
