// Scene format v1 (docs/scene-format.md): JSON file -> Scene, strictly validated. Every error is an
// InputError naming the JSON pointer and the nearest valid key; missing files are IoErrors.
#pragma once

#include "core/scene/json_reader.h"
#include "core/scene/scene.h"
#include "core/util/error.h"

#include <string>

namespace specula {

// Command-line overrides applied on top of the file's render settings (before validation of sizes).
// Caps a host puts on what a scene may ask for (docs/reliability.md "Limits"; CLI --limit NAME=VALUE, the API's
// LoadOptions): each at most the built-in maximum it defaults to. A scene beyond one is bad input at the JSON pointer
// of what exceeds it, found before the thing is built (a texture's header, a mesh's triangle count).
struct SceneLimits {
    int64_t maxPixels = int64_t(1) << 26;      // width x height (64 Mpixel)
    int maxSpp = 1 << 20;                      // samples per pixel
    int64_t maxTriangles = int64_t(1) << 31;   // all shapes together
    int maxTextureSide = 65536;                // pixels, either side of any texture
    int maxGraphNodes = 1 << 16;               // nodes of one material graph
    int maxJsonDepth = 64;                     // nesting of the scene document
};
// The built-in maxima, and `name=value` for the CLI (names: pixels, spp, triangles, texture_side, graph_nodes,
// json_depth). Throws std::invalid_argument for an unknown name, a non-number, or a value outside 1 .. the maximum.
void setSceneLimit(SceneLimits& limits, const std::string& assignment);

struct SceneOverrides {
    int spp = 0;               // 0 = keep
    int width = 0, height = 0; // 0 = keep
    int64_t seed = -1;         // <0 = keep
    std::optional<CropWindow> crop;
    std::optional<AreaLightMode> areaLights;  // render.area_lights
    std::optional<IntegratorKind> integrator; // render.integrator
    SceneLimits limits;
    std::optional<int> frame;  // the animation frame (default: the scene's frame_start)
    int sampleBlock = -1;      // render.sample_block (-1 = keep)
    // A farm piece: sample block sampleSplitIndex of sampleSplitCount (count 0 = the whole render).
    int sampleSplitIndex = 0, sampleSplitCount = 0;
};

// Parses and builds a scene from a file. Relative paths in the scene resolve against its folder.
Scene loadScene(const std::string& path, const SceneOverrides& overrides = {});
// Same from JSON text; baseDir resolves relative paths, 'name' is used in messages.
Scene loadSceneFromString(const std::string& text, const std::string& baseDir, const SceneOverrides& overrides = {},
                          const std::string& name = "<string>");

// The strict JSON of scene and material files, for every reader of them (the scene loader, `specula glsl/bsdf/plot`,
// `bsdf --batch` lines): a key given twice in one object and nesting deeper than maxDepth (at most 64) are InputErrors
// naming the JSON pointer; malformed text is an InputError naming name:line:column.
Json parseStrictJson(const std::string& text, const std::string& name, int maxDepth = 64);
// A JSON file's text, read no further than 256 MiB (InputError beyond: /dev/zero, a mesh); IoError for a folder or
// an unreadable file.
std::string readJsonText(const std::string& path);

// One-line-per-item human summary (used by `specula info`).
std::string describeScene(const Scene& scene);

}  // namespace specula
