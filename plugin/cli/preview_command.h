// The `specula preview` subcommand: the scene rasterised on the GPU with its materials' generated GLSL
// (plugin/preview), written like a render (EXR with the AOVs, OCIO-viewed PNG beside it).
#pragma once

namespace CLI {
class App;
}

namespace specula {

// Registers `preview SCENE.json [-o OUT.exr] [--resolution WxH] [--frames N] [--json]`; the callback stores its exit
// code (kExitOk, kExitBadInput, kExitUsage, kExitIo) in 'exitCode'.
void addPreviewCommand(CLI::App& app, int& exitCode);

}  // namespace specula
