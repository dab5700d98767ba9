// The value of a geometric binding (GeomBinding) at a shading point, as a node's parameter read and the program's
// prologue load it: inline, because a node reads its bound ports (normal, tangent, uv) at every shading point.
#pragma once

#include "core/graph/node_spec.h"
#include "core/render/shading.h"

namespace specula::graph {

// Writes the binding's value (typeWidth(bindingType(b)) floats) for a shading point.
inline void loadBinding(GeomBinding b, const ShadingPoint& sp, float* d) {
    auto v3 = [d](const Vec3& v) { d[0] = v.x, d[1] = v.y, d[2] = v.z; };
    auto v2 = [d](const Vec2& v) { d[0] = v.x, d[1] = v.y; };
    switch (b) {
        case GeomBinding::None: break;
        case GeomBinding::UV: v2(sp.uv); break;
        case GeomBinding::DUVDX: v2(sp.duvdx); break;
        case GeomBinding::DUVDY: v2(sp.duvdy); break;
        case GeomBinding::P: v3(sp.p); break;
        case GeomBinding::N: v3(sp.n); break;
        case GeomBinding::Ng: v3(sp.ng); break;
        case GeomBinding::T: v3(Vec3(sp.tangent)); break;
        case GeomBinding::TSign: d[0] = sp.tangent.w; break;
        case GeomBinding::NdotV: d[0] = glm::dot(sp.n, sp.wo); break;
        case GeomBinding::DNDX: v3(sp.dndx); break;
        case GeomBinding::DNDY: v3(sp.dndy); break;
        case GeomBinding::PixelDUVDX: v2(sp.duvdx / sp.differentialScale.x); break;
        case GeomBinding::PixelDUVDY: v2(sp.duvdy / sp.differentialScale.y); break;
        case GeomBinding::PixelDNDX: v3(sp.dndx / sp.differentialScale.x); break;
        case GeomBinding::PixelDNDY: v3(sp.dndy / sp.differentialScale.y); break;
        case GeomBinding::FrontFacing: d[0] = sp.frontFacing ? 1.f : 0.f; break;
    }
}

}  // namespace specula::graph
