// The `specula preview` subcommand: the scene rasterised on the GPU with its materials' generated GLSL
// (plugin/preview), written like a render (EXR with the AOVs, OCIO-viewed PNG beside it).
#pragma once

namespace CLI {
class App;
}

#include "core/scene/scene_loader.h"

#include <string>

namespace specula {

// --resolution WxH of `preview` and `view` into ov.width/height ("" leaves them); false after printing the usage error.
bool parseResolutionOption(const std::string& resolution, SceneOverrides& ov);

// Registers `preview SCENE.json [-o OUT.exr] [--resolution WxH] [--frames N] [--json]`; the callback stores its exit
// code (kExitOk, kExitBadInput, kExitUsage, kExitIo) in 'exitCode'.
void addPreviewCommand(CLI::App& app, int& exitCode);

}  // namespace specula
