// The GPU preview (docs/preview.md): rasterises a loaded scene with each material's generated GLSL module through
// OpenGL 4.5 (headless EGL or a window's context), one sample at each pixel centre, with the CPU renderer's AOVs.
#pragma once

#include "core/render/camera.h"
#include "core/render/renderer.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

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

// The scene's GPU state in the GL context current on the calling thread: one program per material (its module plus
// the light loop), meshes, lights, shadow maps, the prefiltered environment. Draw as often as wanted, from any
// camera, at any size; keep the context current and the scene alive while the renderer lives.
class PreviewRenderer {
public:
    // 'materials' is the scene document's "materials" object (the graphs the GLSL is emitted from); 'baseDir'
    // resolves their texture files. Throws specula::Error (bad_input) when a material's GLSL does not compile.
    PreviewRenderer(const Scene& scene, const nlohmann::json& materials, const std::string& baseDir);
    ~PreviewRenderer();
    PreviewRenderer(const PreviewRenderer&) = delete;
    PreviewRenderer& operator=(const PreviewRenderer&) = delete;

    // Draws one frame into the renderer's AOV target (re-made when the size changes); returns GL_TIME_ELAPSED in ns
    // (0 when the driver's timer query gives nothing). Leaves the target bound as the draw framebuffer.
    double draw(const CameraDesc& camera, int width, int height);
    unsigned beautyTexture() const;  // GL texture name of the last draw's beauty (RGBA32F, linear, GL row 0 = bottom)
    // The last draw's colour attachments: 0 beauty, 1 diffuse, 2 specular, 3 normal (xyz), 4 (depth, u, v).
    unsigned aovTexture(int attachment) const;
    unsigned framebuffer() const;    // the AOV target's framebuffer object (attachment 0 = beauty)
    // The last draw's AOVs in the renderer's layout (beauty, diffuse, specular, normal, uv, depth; rows top first).
    ImageSet readBack() const;
    const std::vector<std::string>& warnings() const;

private:
    struct State;
    std::unique_ptr<State> s_;
};

// A scene file as the preview needs it: the loaded scene, its document's "materials" (the graphs the GLSL is emitted
// from) and the folder its relative paths resolve against. The file is read once (the two can never disagree).
struct PreviewScene {
    Scene scene;
    nlohmann::json materials = nlohmann::json::object();
    std::string baseDir;
};
PreviewScene loadPreviewScene(const std::string& path, const SceneOverrides& overrides = {});

// One headless render: gl::context(), a PreviewRenderer, options.frames draws from the scene camera, read back.
// Throws specula::Error (io) when there is no GL 4.5 context.
PreviewOutput renderPreview(const Scene& scene, const nlohmann::json& materials, const std::string& baseDir,
                            const PreviewOptions& options = {});

}  // namespace specula::preview
