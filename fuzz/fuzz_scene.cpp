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
    SceneOverrides ov;
    ov.width = 16;
    ov.height = 12;
    ov.spp = 1;
    // Textures (files and generated normal maps) capped at 256 a side, as a host would through SceneLimits: every
    // texture of the seeds fits, and a mutant asking for a 1024² P-NDF or LTC prefilter (over 60 s under ASan) takes
    // the refusal path instead of stalling the campaign.
    ov.limits.maxTextureSide = fuzz::kFuzzTextureSide;
    try {
        Scene scene = loadSceneFromString(std::string(reinterpret_cast<const char*>(data), size), baseDir, ov, "fuzz.json");
        RenderOptions ro;
        ro.threads = 1;
        RenderOutput out = renderScene(scene, ro);
        (void)out;
    } catch (const Error&) {
    }
    return 0;
}
