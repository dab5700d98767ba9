// The shading point handed to materials: hit geometry, shading frame and the screen-space
// differentials (dp, duv, dn, dwo per pixel step) propagated from camera ray differentials.
#pragma once

#include "core/math/math.h"

#include <cstdint>

namespace specula {

struct ShadingPoint {
    // Geometry (world space).
    Vec3 p{0.f};           // shading position (on the exact surface for analytic shapes)
    Vec3 pGeom{0.f};       // hit on the tessellation: origin for spawned rays (offset along ng)
    Vec3 ng{0, 0, 1};      // geometric normal, facing the incoming ray's side
    Vec3 n{0, 0, 1};       // interpolated (or exact) shading normal, same side as ng
    Vec2 uv{0.f};          // surface parameters / texture coordinates
    Vec3 dpdu{1, 0, 0}, dpdv{0, 1, 0};  // position partials (world)
    Vec3 dndu{0.f}, dndv{0.f};          // shading-normal partials (world)
    Vec4 tangent{1, 0, 0, 1};           // mesh tangent (xyz world, w = bitangent sign); from dpdu if absent
    Frame frame;                        // geometric shading frame: n, tangent along dpdu (each lobe has its own)

    Vec3 wo{0, 0, 1};      // direction towards the viewer / previous vertex (world, unit)

    // Screen-space differentials: change per pixel step in x and y (scaled for spp as pbrt does).
    bool hasDifferentials = false;
    Vec3 dpdx{0.f}, dpdy{0.f};
    Vec2 duvdx{0.f}, duvdy{0.f};
    Vec3 dndx{0.f}, dndy{0.f};
    Vec3 dwodx{0.f}, dwody{0.f};  // derivative of wo (world)
    // The factor the x and y differentials above were shrunk by (pbrt's max(1/8, 1/sqrt(spp)) for ray
    // differentials; 1 for quad differences): a per-pixel quantity, e.g. the glint LOD footprint, which must not change
    // with spp, is the differential divided by it (pixel bindings, GeomBinding::PixelDUVDX ...).
    Vec2 differentialScale{1.f, 1.f};
    // Camera hits: the sample's offset from its pixel centre in pixels (RayDifferential::pixelOffset), so uv at the
    // pixel centre is uv - duvdx/differentialScale.x · offset.x - duvdy/differentialScale.y · offset.y; 0 elsewhere
    // (secondary vertices, tools). On a GPU a fragment is at its pixel centre: 0.
    Vec2 pixelOffset{0.f};

    // Render setting "derivatives": "quad" (filtered-ggx.md §5.2): this pixel's partners in its aligned 2×2 quad along
    // screen x ([0]) and y ([1]), shaded at their own pixel centres; the differentials above then hold the fine
    // one-sided differences sign·(neighbour − this).
    struct QuadNeighbour {
        bool valid = false;
        float sign = 1.f;  // +1 if this pixel is the quad's x0 (y0): Δ = q(neighbour) − q(this); −1 otherwise
        Vec3 p{0.f}, wo{0.f};
        Frame frame;       // the dominant lobe's frame of its closure (normal maps included)
    };
    QuadNeighbour quad[2];

    int depth = 0;          // 0 at the camera hit
    uint32_t shapeId = 0;   // index of the shape in the scene
    uint32_t primId = 0;    // triangle index
    bool frontFacing = true;  // the ray hit the side the geometric normal points to
};

}  // namespace specula
