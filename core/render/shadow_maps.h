// Shadow maps of the delta lights for the raster integrator and the GPU preview (docs/preview.md): one layout (views,
// resolution, biases), one lookup written twice (C++ and its GLSL twin, side by side), and the CPU's maps by Embree rays.
#pragma once

#include "core/render/lights.h"

#include <cstdint>
#include <string>
#include <vector>

namespace specula {

class Accel;
struct Scene;

// Biases in texels of the map at the shading point's depth: the normal offset before projecting, and the depth slack of
// the comparison. The normal offset keeps a plane lit across its own texel at any angle (the plane's depth varies by
// less than a texel diagonal times tan θ over a texel, which an offset of one texel along the normal covers).
inline constexpr float kShadowNormalBias = 1.5f;
inline constexpr float kShadowDepthBias = 1.f;
// All maps of a scene together hold at most this many texels (256 MiB of R32F on each side); the edge shrinks to fit.
inline constexpr int64_t kShadowMaxTexels = int64_t(1) << 26;
// Spot cones wider than this full angle (degrees) get a cube, as point lights do.
inline constexpr float kShadowMaxSpotFov = 160.f;

// Directions: an environment's kShadowDirections orthographic maps (shadowDirection), each over the scene's bounding
// sphere as a directional light's map.
enum class ShadowMode : int { None = 0, Cube = 1, Perspective = 2, Ortho = 3, Directions = 4 };

// The environment's shadow directions: the six axes and the eight cube diagonals, each a view (axis = the direction
// the map looks, from the sky towards the scene; right and up as a directional light's map): visibility towards -axis.
inline constexpr int kShadowDirections = 14;
struct ShadowFrame {
    Vec3 axis, right, up;
};
const ShadowFrame& shadowDirection(int k);

// One rendered map (a layer of the map array). Texel (i, j) covers ndc x = (2i+1)/N - 1, y = (2j+1)/N - 1 (j = 0 at
// the bottom, GL's window convention), with ndc = scale·(q·right, q·up) / (q·axis) for perspective maps and
// scale·(q·right, q·up) for orthographic ones, q = p - origin. It stores q·axis of the nearest surface there.
struct ShadowView {
    Vec3 origin{0.f}, axis{0.f, 0.f, 1.f}, right{1.f, 0.f, 0.f}, up{0.f, 1.f, 0.f};
    float scale = 1.f;
    float zNear = 0.f, zFar = 1.f;  // the depth range along axis that is rendered
    bool ortho = false;
};

// A light's maps: one view (spot, directional) or six cube faces from firstLayer on (kShadowCubeFace order).
struct ShadowLight {
    ShadowMode mode = ShadowMode::None;
    int firstLayer = 0;
    float scale = 1.f;
    float texelFactor = 0.f;  // a texel's world size: this times the depth (perspective), or this (ortho)
    Vec3 origin{0.f}, axis{0.f}, right{0.f}, up{0.f};  // the single view's frame (cube: origin only)
    float reach = 0.f;  // Directions: view k's origin is origin - shadowDirection(k).axis · reach (origin: the centre)
};

struct ShadowLayout {
    int size = 0;                     // texels per map edge (all maps alike)
    std::vector<ShadowLight> lights;  // one per scene light, in scene.lights order
    std::vector<ShadowView> views;    // one per layer
    int layers() const { return int(views.size()); }
    size_t texelCount() const { return size_t(views.size()) * size_t(size) * size_t(size); }
};

// Cube face f (0..5: +x, -x, +y, -y, +z, -z): its axis, right and up, rows of {x, y, z} components in {-1, 0, 1}.
extern const float kShadowCubeFace[6][3][3];

// The maps of every light of the scene but emissive meshes at render.shadow_map_size texels per edge (shrunk so that
// all maps fit kShadowMaxTexels). lights[i] is scene.lights[i]->raster(). A quad light gets a cube from its centre (its
// area is not resolved: hard shadows, as a point light there), an environment kShadowDirections orthographic maps.
ShadowLayout planShadowMaps(const Scene& scene, const std::vector<RasterLight>& lights);

// Visibility in [0, 1] of light 'light' at point p whose geometric normal ng faces the light's side: the point offset by
// kShadowNormalBias texels along ng, projected into its map, 2x2 PCF with bilinear weights over the nearest texels (a
// texel is lit where its depth + kShadowDepthBias texels >= the point's). Points outside a spot or ortho map are lit.
// texels: the layout's layers, layer-major, rows bottom to top.
// An environment's light (ShadowMode::Directions) gives 1.
float shadowVisibility(const ShadowLayout& layout, const float* texels, int light, const Vec3& p, const Vec3& ng);

// An environment's visibility at p: each direction's map visibility V_k weighted by w_k = max(0, d_k·ng)·E_k, E_k the
// channel sum of the environment's irradiance towards d_k = -axis_k (its caller's lookup):
// Σ w_k V_k / Σ w_k, 1 where every weight is 0. A discretised visibility-weighted irradiance ratio (the
// environment's share that reaches p), which scales the unshadowed split sum. irradiance[k] = E_k.
float environmentShadowVisibility(const ShadowLayout& layout, const float* texels, int light, const Vec3& p,
                                  const Vec3& ng, const float* irradiance);

// The GLSL twin of shadowVisibility, the same operations in the same order (marked precise):
//   float spc_shadow(vec4 h, vec3 origin, vec3 axis, vec3 right, vec3 up, vec3 P, vec3 Ng)
// with h = (mode, first layer, scale, texel factor), over `uniform sampler2DArray spc_shadow_maps` at texture unit
// SPC_PREVIEW_SHADOW_BINDING (a define the host puts first); and environmentShadowVisibility's:
//   float spc_shadow_environment(vec4 h, vec3 centre, float reach, float E[14], vec3 P, vec3 Ng)
// with spc_shadow_direction(k) = d_k for the caller's irradiance lookups.
std::string shadowLookupGlsl();

// The CPU's maps: one ray per texel centre through the scene's BVH, the first hit that is not a quad light's emitter
// (the GPU draws emitters in their own pass, not into the maps). Deterministic; parallel over rows with TBB.
std::vector<float> buildShadowMaps(const Scene& scene, const Accel& accel, const ShadowLayout& layout);

}  // namespace specula
