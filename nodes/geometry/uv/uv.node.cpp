// geometry.uv: Texture coordinates uv0 and their screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
OutputList kOutputs;
const OutPort<Vec2> kOutUv = kOutputs.add<Vec2>("uv", TypeDesc::Vec2, "uv0");
const OutPort<Vec2> kOutDuvdx = kOutputs.add<Vec2>("duvdx", TypeDesc::Vec2, "d(uv)/dx per pixel");
const OutPort<Vec2> kOutDuvdy = kOutputs.add<Vec2>("duvdy", TypeDesc::Vec2, "d(uv)/dy per pixel");
// Texture filtering wants the sample's footprint (shrunk with spp, as in pbrt); the glint LOD wants the whole pixel.
const OutPort<Vec2> kOutPixelDuvdx = kOutputs.add<Vec2>("pixel_duvdx", TypeDesc::Vec2,
    "d(uv)/dx over one whole pixel at any spp (the glint LOD footprint: bsdf.glint duvdx)");
const OutPort<Vec2> kOutPixelDuvdy = kOutputs.add<Vec2>("pixel_duvdy", TypeDesc::Vec2,
    "d(uv)/dy over one whole pixel at any spp");

void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    set(c, i, kOutUv, sp.uv);
    set(c, i, kOutDuvdx, sp.duvdx);
    set(c, i, kOutDuvdy, sp.duvdy);
    set(c, i, kOutPixelDuvdx, sp.duvdx / sp.differentialScale.x);
    set(c, i, kOutPixelDuvdy, sp.duvdy / sp.differentialScale.y);
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.uv";
    s.category = "geometry";
    s.doc = "Texture coordinates uv0 and their screen-space derivatives: duvdx/duvdy are the sample's footprint "
            "(a pixel step scaled by max(1/8, 1/sqrt(spp)) on the CPU, for texture filtering), pixel_duvdx/pixel_duvdy "
            "one whole pixel step at any spp (on a GPU both are dFdx/dFdy).";
    s.outputs = kOutputs.ports();
    s.flags = kNeedsDerivatives | kReadsUv;
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_uv";
    s.glslFile = "geometry/uv/uv.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
