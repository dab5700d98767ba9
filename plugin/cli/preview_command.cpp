// `specula preview`: load the scene as for a render, rasterise it (plugin/preview/preview.h), write the outputs with
// the render's policy (core/api/specula.h: atomic EXR + PNG, never over the input).
#include "plugin/cli/preview_command.h"

#include "core/api/specula.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "core/util/error.h"
#include "plugin/preview/preview.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace specula {

bool parseResolutionOption(const std::string& resolution, SceneOverrides& ov) {
    if (resolution.empty()) return true;
    char x = 0;
    std::istringstream in(resolution);
    if (!(in >> ov.width >> x >> ov.height) || x != 'x' || ov.width < 1 || ov.height < 1 || ov.width > 16384 ||
        ov.height > 16384 || !in.eof()) {
        std::fprintf(stderr, "specula: error: --resolution expects WxH within 1x1..16384x16384, got '%s'\n",
                     resolution.c_str());
        return false;
    }
    return true;
}

void addPreviewCommand(CLI::App& app, int& exitCode) {
    auto* cmd = app.add_subcommand("preview", "Rasterise a JSON scene on the GPU with the generated GLSL (OpenGL 4.5, "
                                              "headless EGL) to EXR (AOVs) and an OCIO-viewed PNG");
    static std::string scenePath, outPath, resolution;
    static int frames = 1;
    static bool json = false, noOutput = false;
    cmd->add_option("scene", scenePath, "Scene file (JSON, format v1)")->required();
    cmd->add_option("-o,--output", outPath, "Output EXR (default: <scene name>.preview.exr in the current folder)");
    cmd->add_option("--resolution", resolution, "Image size WxH (overrides the scene)");
    cmd->add_option("--frames", frames, "Frames to draw (the GPU time is their mean)")->check(CLI::Range(1, 10000));
    cmd->add_flag("--json", json, "Print the timing as one JSON line on stdout");
    // Timing runs (bench/bench_preview.py) on a machine that has a GPU but not the image libraries.
    cmd->add_flag("--no-output", noOutput, "Draw and time only: write no image")->excludes("--output");
    cmd->callback([&exitCode] {
        SceneOverrides ov;
        if (!parseResolutionOption(resolution, ov)) {
            exitCode = kExitUsage;
            return;
        }
        if (outPath.empty() && !noOutput) outPath = fs::path(scenePath).stem().string() + ".preview.exr";
        try {
            if (!noOutput) checkOutputPath(outPath, scenePath);
            preview::PreviewScene ps = preview::loadPreviewScene(scenePath, ov);
            const Scene& scene = ps.scene;
            for (const std::string& w : scene.warnings) std::fprintf(stderr, "specula: warning: %s\n", w.c_str());
            preview::PreviewOptions po;
            po.frames = frames;
            preview::PreviewOutput out = preview::renderPreview(scene, ps.materials, ps.baseDir, po);
            for (const std::string& w : out.warnings) std::fprintf(stderr, "specula: warning: %s\n", w.c_str());
            WrittenFiles written;
            if (!noOutput) written = writeRenderResult(outPath, scene, out.output.images, out.output.stats);
            if (json) {
                nlohmann::json line = {{"event", "done"}, {"renderer", out.renderer}, {"width", scene.render.width},
                                       {"height", scene.render.height}, {"frames", frames},
                                       {"gpu_ms_per_frame", out.gpuMsPerFrame}, {"wall_ms_per_frame", out.wallMsPerFrame},
                                       {"setup_seconds", out.setupSeconds},
                                       {"exr", written.exr.empty() ? nlohmann::json() : nlohmann::json(written.exr)},
                                       {"png", written.png.empty() ? nlohmann::json() : nlohmann::json(written.png)}};
                std::printf("%s\n", line.dump().c_str());
            }
            std::fprintf(stderr,
                         "specula: preview %dx%d on %s: %.3f ms/frame on the GPU timer, %.3f ms/frame wall (%d frames), "
                         "set-up %.2fs\n",
                         scene.render.width, scene.render.height, out.renderer.c_str(), out.gpuMsPerFrame,
                         out.wallMsPerFrame, frames, out.setupSeconds);
            if (!noOutput)
                std::fprintf(stderr, "specula: wrote %s\n",
                             (written.exr.empty() ? written.png : written.exr + " and " + written.png).c_str());
        } catch (const std::exception& e) {
            std::fprintf(stderr, "specula: error: %s\n", e.what());
            exitCode = exitCodeFor(e);
        }
    });
}

}  // namespace specula
