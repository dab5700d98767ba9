// The in-memory scene the renderer consumes: render settings, camera, world-space shapes with their
// materials, lights, colour settings and the shared texture store. Built by the JSON loader.
#pragma once

#include "core/geometry/mesh.h"
#include "core/render/camera.h"
#include "core/render/lights.h"
#include "core/render/material.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace specula {

class ColorConfig;
class TextureStore;

enum class IntegratorKind { Direct, Path, Raster };
enum class PixelFilterKind { Box, Gaussian };
// Screen-space derivatives of camera hits: "ray" = ray differentials (pbrt-v4); "quad" = emulated GPU 2×2-quad fine
// finite differences (dFdxFine/dFdyFine) between pixel-centre hits, for like-for-like CPU/GLSL comparisons
// (filtered-ggx.md §5.2).
enum class DerivativeMode { Ray, Quad };

struct CropWindow {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // pixel bounds, [x0,x1) x [y0,y1)
};

enum class AreaLightMode : uint8_t { Sampled, Ltc };

struct RenderSettings {
    int width = 640, height = 480;
    int spp = 16;
    uint64_t seed = 0;
    int tile = 32;
    IntegratorKind integrator = IntegratorKind::Path;
    int maxDepth = 8;          // path vertices after the camera hit (path tracer)
    PixelFilterKind filter = PixelFilterKind::Box;
    float gaussianSigma2 = 1.f / (2.f * kPi);  // σ² of the Gaussian filter in pixel² (T&K 2021 reference)
    bool pixelCenter = false;  // spp = 1 samples the pixel centre (validation.md §1)
    DerivativeMode derivatives = DerivativeMode::Ray;  // "derivatives": "ray" | "quad"
    float clampIndirect = 0.f; // max component of one indirect contribution (Cycles' clamp_indirect); 0 = off
    // "area_lights": quad lights integrated analytically by the lobes that can (LTC, with the shadow ratio of Heitz,
    // Hill & McGuire 2018) or sampled only; "ltc_horizon": exact clipping or the clip-free sphere approximation.
    AreaLightMode areaLights = AreaLightMode::Ltc;
    // "mesh_lights": shapes whose material emits are also sampled as lights (next-event estimation with MIS); false:
    // their light is found only by paths that hit them.
    bool meshLights = true;
    uint8_t ltcHorizon = 0;    // ltc::Horizon: 0 clip, 1 clipless
    // "ltc_max_depth": the deepest path vertex (0 = the camera hit) that integrates quad lights analytically; deeper
    // vertices sample them (their light is already noisy, and the analytic path costs a polygon sample and a shadow
    // ray per lobe and light).
    int ltcMaxDepth = 0;
    // "ltc_shadow_rays": visibility rays per analytic lobe and light (stratified), the shadow ratio's sample count. Two
    // rays whose random pairs are half a period apart split the light between them: in penumbrae the 4-spp RMSE of
    // the CI scene drops from 0.53x to 0.22x of sampled's (tests/unit/test_ltc_render.cpp).
    int ltcShadowRays = 2;
    // "shadow_map_size": texels per edge of each shadow map of the raster integrator and the GPU preview (one map per
    // spot or directional light, a cube of six per point light; core/render/shadow_maps.h).
    int shadowMapSize = 1024;
    std::optional<CropWindow> crop;
    // "sample_block": the film sums each pixel's samples in blocks of this many consecutive sample indices and adds the
    // block sums in order (0: one block of spp). A render split into spp/sample_block pieces of one block each
    // (sampleSplitIndex/Count, `render --sample-split`) is merged bit for bit into this render (docs/farm.md).
    int sampleBlock = 0;
    // Render only block sampleSplitIndex of sampleSplitCount (blocks of spp/sampleSplitCount samples); the images then
    // hold the block's sums, not averages, with the valid-sample count as AOV "samples" (a farm piece).
    int sampleSplitIndex = 0, sampleSplitCount = 0;
    int frame = 0;  // the animation frame this scene was evaluated at (scene "animation"; 0 without one)
};

struct ColorSettings {
    std::string config = "builtin";
    std::string view;            // empty = the config's default view
    float exposure = 0.f;        // stops, applied before the view transform (PNG only)
};

struct ShapeInstance {
    std::string name;
    TriangleMesh mesh;  // world space
    std::shared_ptr<const AnalyticSurface> surface;  // object-space exact surface, or null
    Mat4 objectToWorld{1.f}, worldToObject{1.f};
    Mat3 normalToWorld{1.f};   // inverse transpose of the linear part
    int material = -1;         // index into Scene::materials; -1 for light geometry
    int areaLight = -1;        // index into Scene::lights for emitting quads
    std::string meshFile;      // the file of a "mesh" shape ("" for built-in shapes)
    MeshAttributeSources attributes;  // where a mesh file's normals, uvs and tangents came from
    int meshLight = -1;        // index into Scene::lights of this shape's MeshLight (emissive material), or -1
};

struct Scene {
    std::string sourcePath;  // the JSON file, for messages
    // FNV-1a 64 (hex) of the scene text and the settings that change pixels (all but the crop window and the sample
    // split): farm pieces of one image carry the same hash, and `specula merge` refuses pieces that differ.
    std::string sourceHash;
    std::vector<std::string> warnings;  // non-fatal findings of the loader ("<JSON pointer>: <message>")
    RenderSettings render;
    ColorSettings color;
    CameraDesc camera;
    std::vector<ShapeInstance> shapes;
    std::vector<std::shared_ptr<Material>> materials;
    std::vector<std::unique_ptr<Light>> lights;
    std::shared_ptr<const ColorConfig> colorConfig;
    std::shared_ptr<TextureStore> textures;

    Scene();
    ~Scene();
    Scene(Scene&&) noexcept;
    Scene& operator=(Scene&&) noexcept;
};

}  // namespace specula
