// geometry.uv: Texture coordinates uv0 and their screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
OutputList kOutputs;
const OutPort<Vec2> kOutUv = kOutputs.add<Vec2>("uv", TypeDesc::Vec2, "uv0");
const OutPort<Vec2> kOutDuvdx = kOutputs.add<Vec2>("duvdx", TypeDesc::Vec2, "d(uv)/dx per pixel");
const OutPort<Vec2> kOutDuvdy = kOutputs.add<Vec2>("duvdy", TypeDesc::Vec2, "d(uv)/dy per pixel");

void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    set(c, i, kOutUv, sp.uv);
    set(c, i, kOutDuvdx, sp.duvdx);
    set(c, i, kOutDuvdy, sp.duvdy);
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.uv";
    s.category = "geometry";
    s.doc = "Texture coordinates uv0 and their screen-space derivatives.";
    s.outputs = kOutputs.ports();
    s.flags = kNeedsDerivatives;
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_uv";
    s.glslFile = "geometry/uv/uv.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
