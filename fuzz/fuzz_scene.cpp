// libFuzzer target: a scene file (JSON text) through the scene loader and a tiny render (16x12, 1 spp, one thread)
// of what loads. Relative files resolve against examples/, so the seeds' meshes and textures load. Only
// specula::Error may leave; anything else or a crash is a finding.
#include "core/render/renderer.h"
#include "core/scene/scene_loader.h"
#include "core/util/error.h"
#include "fuzz/fuzz_common.h"

using namespace specula;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string baseDir = (fuzz::scratchDir(), std::string(SPECULA_SOURCE_DIR) + "/examples");
    fuzz::loadAndRenderTiny([&](const SceneOverrides& ov) {
        return loadSceneFromString(std::string(reinterpret_cast<const char*>(data), size), baseDir, ov, "fuzz.json");
    });
    return 0;
}
