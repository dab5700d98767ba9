// The GPU preview (docs/preview.md): rasterises a loaded scene with each material's generated GLSL module through
// OpenGL 4.5 (headless EGL), one sample at each pixel centre, and returns the same AOV buffers as the CPU renderer.
#pragma once

#include "core/render/renderer.h"

#include <nlohmann/json.hpp>

#include <string>

namespace specula {
struct Scene;
}

namespace specula::preview {

struct PreviewOptions {
    int frames = 1;  // frames drawn (the image is the last one); more give a steadier GPU time per frame
};

struct PreviewOutput {
    RenderOutput output;          // beauty, diffuse, specular, normal, uv, depth (no albedo), rows top first
    double gpuMsPerFrame = 0.0;   // GL_TIME_ELAPSED of one frame's draws, averaged over the frames
    double wallMsPerFrame = 0.0;  // the same frames on the host clock, each ended by glFinish
    double setupSeconds = 0.0;    // context, shader compilation, resource upload (wall)
    std::string renderer;         // GL_RENDERER
    std::vector<std::string> warnings;  // per material: what the GPU computes instead (GlslModule::warnings)
};

// 'materials' is the scene document's "materials" object (the graphs the GLSL is emitted from); 'baseDir' resolves
// their texture files. Throws specula::Error (io) when there is no GL 4.5 context, (bad_input) when a material's
// GLSL does not compile.
PreviewOutput renderPreview(const Scene& scene, const nlohmann::json& materials, const std::string& baseDir,
                            const PreviewOptions& options = {});

}  // namespace specula::preview
