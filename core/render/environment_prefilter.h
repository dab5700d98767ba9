// The prefiltered environment of the raster integrator and the GPU preview (split sum, docs/preview.md): one
// GGX-convolved lat-long mip chain and one irradiance map, built once on the CPU and read by the same lookup twice.
#pragma once

#include "core/render/lights.h"

#include <vector>

namespace specula {

// Mip level k of the specular chain holds the environment convolved with the GGX lobe of roughness α = k / (levels-1)
// for N = V = R (Karis 2013, "Real Shading in Unreal Engine 4", the split sum's first factor); level 0 (α = 0) is the
// map box-filtered to the chain's base size. The lookup reads level α·(levels-1), trilinearly.
inline constexpr int kEnvironmentLevels = 6;
// Base edge of the chain (width; height = width/2): the map's width rounded down to a power of two, within these.
inline constexpr int kEnvironmentMinWidth = 32;
inline constexpr int kEnvironmentMaxWidth = 256;
// Width of the irradiance map (E(n)/π, the cosine convolution) and of the source the convolutions sum over.
inline constexpr int kEnvironmentIrradianceWidth = 32;
inline constexpr int kEnvironmentSourceWidth = 128;

// One RGB float image in the environment's lat-long layout (rows top to bottom: row 0 is +z).
struct EnvironmentImage {
    int width = 0, height = 0;
    std::vector<float> rgb;  // 3 floats per texel
};

struct PrefilteredEnvironment {
    bool hasMap = false;
    Color3 constant{0.f};                  // !hasMap: the radiance in every direction, for every α
    std::vector<EnvironmentImage> levels;  // hasMap: kEnvironmentLevels images, each half the size of the one before
    EnvironmentImage irradiance;           // hasMap
    float rotation = 0.f;                  // the map's turn about +z (radians), as RasterLight::mapRotation

    // Radiance for the split sum at world direction dir: alpha ≥ 0 reads the specular chain at level
    // alpha·(levels-1) (clamped to the chain), alpha < 0 the irradiance map. Both sample as OpenGL does with
    // GL_LINEAR_MIPMAP_LINEAR, GL_REPEAT in u and GL_CLAMP_TO_EDGE in v, so the GPU's textureLod reads the same.
    Color3 lookup(const Vec3& dir, float alpha) const;
};

// The lat-long (u, v) of a world direction, the map turned by 'rotation' about +z (EnvironmentLight::dirToUv).
Vec2 environmentUv(const Vec3& dir, float rotation);
// GL's bilinear read of an image at (u, v): texel centres at (i + 0.5)/width, u wraps, v clamps.
Color3 sampleBilinear(const EnvironmentImage& image, const Vec2& uv);

// The prefiltered environment of an environment light's raster description (deterministic: the same bits for any
// thread count). A constant environment needs no images.
PrefilteredEnvironment prefilterEnvironment(const RasterLight& light);

}  // namespace specula
