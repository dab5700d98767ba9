// geometry.uv: Texture coordinates uv0 and their screen-space derivatives.
#include "nodes/node_common.h"

#include "core/render/shading.h"

namespace specula::nodes {
namespace {
void cpu(EvalContext& c, const Instr& i) {
    const ShadingPoint& sp = *c.sp;
    outV2(c, i, 0, sp.uv); outV2(c, i, 1, sp.duvdx); outV2(c, i, 2, sp.duvdy);
}
void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "geometry.uv";
    s.category = "geometry";
    s.doc = "Texture coordinates uv0 and their screen-space derivatives.";
    s.outputs = {PortSpec::out("uv", TypeDesc::Vec2, "uv0"), PortSpec::out("duvdx", TypeDesc::Vec2, "d(uv)/dx per pixel"), PortSpec::out("duvdy", TypeDesc::Vec2, "d(uv)/dy per pixel")};
    s.flags = kGlslShading | kNeedsDerivatives;
    s.cpu = &cpu;
    s.glslFunction = "spc_geometry_uv";
    s.glslFile = "geometry/uv/uv.glsl";
    r.add(std::move(s));
}
}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
