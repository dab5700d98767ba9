// texture.uv_transform: uv' = R(rotation) · (uv · scale) + offset, with the footprint carried along
// (duv'/dx = R · (duv/dx · scale)), so tiling a texture never silently breaks its filter footprint.
#include "nodes/node_common.h"

#include <cmath>

namespace specula::nodes {
namespace {

struct Params {
    Vec2 uv, duvdx, duvdy, scale;
    float rotation;
    Vec2 offset;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .v2("uv", &Params::uv, Vec2(0.f), "texture coordinates").range(-1.f, 2.f).bind(GeomBinding::UV)
    .v2("duvdx", &Params::duvdx, Vec2(0.f), "footprint: d(uv)/dx").range(-0.01f, 0.01f).bind(GeomBinding::DUVDX)
    .v2("duvdy", &Params::duvdy, Vec2(0.f), "footprint: d(uv)/dy").range(-0.01f, 0.01f).bind(GeomBinding::DUVDY)
    .v2("scale", &Params::scale, Vec2(1.f), "tiling factor per axis").range(0.25f, 8.f)
    .f("rotation", &Params::rotation, 0.f, "counter-clockwise rotation in degrees, after scaling").range(-180.f, 180.f)
    .v2("offset", &Params::offset, Vec2(0.f), "added last").range(-1.f, 1.f);
OutputList kOutputs;
const OutPort<Vec2> kUv = kOutputs.add<Vec2>("uv", TypeDesc::Vec2, "transformed texture coordinates");
const OutPort<Vec2> kDuvdx = kOutputs.add<Vec2>("duvdx", TypeDesc::Vec2, "transformed d(uv)/dx");
const OutPort<Vec2> kDuvdy = kOutputs.add<Vec2>("duvdy", TypeDesc::Vec2, "transformed d(uv)/dy");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    const float a = p.rotation * (kPi / 180.f), cs = std::cos(a), sn = std::sin(a);
    auto rot = [&](Vec2 v) { return Vec2(cs * v.x - sn * v.y, sn * v.x + cs * v.y); };
    set(c, i, kUv, rot(p.uv * p.scale) + p.offset);
    set(c, i, kDuvdx, rot(p.duvdx * p.scale));
    set(c, i, kDuvdy, rot(p.duvdy * p.scale));
}
}  // namespace
SPECULA_REGISTER_NODE(declareNode("texture.uv_transform",
                                  "Scale, rotate and offset texture coordinates, carrying the uv footprint (duvdx, "
                                  "duvdy) along.",
                                  kParams, kOutputs, &cpu, kPure | kNeedsDerivatives));
}  // namespace specula::nodes
