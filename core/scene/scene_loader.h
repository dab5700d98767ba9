// Scene format v1 (docs/scene-format.md): JSON file -> Scene, strictly validated. Every error is an
// InputError naming the JSON pointer and the nearest valid key; missing files are IoErrors.
#pragma once

#include "core/scene/scene.h"
#include "core/util/error.h"

#include <string>

namespace specula {

// Command-line overrides applied on top of the file's render settings (before validation of sizes).
struct SceneOverrides {
    int spp = 0;               // 0 = keep
    int width = 0, height = 0; // 0 = keep
    int64_t seed = -1;         // <0 = keep
    std::optional<CropWindow> crop;
    std::optional<AreaLightMode> areaLights;  // render.area_lights
    std::optional<IntegratorKind> integrator; // render.integrator
};

// Parses and builds a scene from a file. Relative paths in the scene resolve against its folder.
Scene loadScene(const std::string& path, const SceneOverrides& overrides = {});
// Same from JSON text; baseDir resolves relative paths, 'name' is used in messages.
Scene loadSceneFromString(const std::string& text, const std::string& baseDir, const SceneOverrides& overrides = {},
                          const std::string& name = "<string>");

// One-line-per-item human summary (used by `specula info`).
std::string describeScene(const Scene& scene);

}  // namespace specula
