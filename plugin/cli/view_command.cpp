// `specula view`: options, the signals that close the window (SIGINT, SIGTERM: the last frame is still written as
// the screenshot), then the viewer's loop (plugin/preview/viewer.h).
#include "plugin/cli/view_command.h"

#include "core/api/specula.h"
#include "core/util/error.h"
#include "plugin/cli/preview_command.h"
#include "plugin/preview/viewer.h"

#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace specula {

namespace {
std::atomic<bool> gStopView{false};
extern "C" void onViewSignal(int) { gStopView.store(true); }
}  // namespace

void addViewCommand(CLI::App& app, int& exitCode) {
    auto* cmd = app.add_subcommand("view", "Open a window that draws a JSON scene on the GPU (the preview) with an orbit "
                                           "camera, and redraws when the scene or a file it names changes");
    static preview::ViewerOptions opt;
    static std::string resolution;
    cmd->add_option("scene", opt.scenePath, "Scene file (JSON, format v1)")->required();
    cmd->add_option("--resolution", resolution, "The window's first size WxH (default: the scene's resolution)");
    cmd->add_option("--screenshot", opt.screenshotPath,
                    "Written at exit and on key S: a .png is the window as shown (OCIO view on the GPU), an .exr the "
                    "AOVs (and the render's PNG beside it)");
    cmd->add_option("--exit-after", opt.exitAfterFrames, "Draw this many frames, write the screenshot, exit")
        ->check(CLI::Range(1, 1000000));
    cmd->add_flag("--events", opt.events, "Print one JSON line per event (loaded, reload_failed, shown, screenshot, closed)");
    cmd->add_option("--poll", opt.pollSeconds, "Seconds between looks at the watched files")->check(CLI::Range(0.01, 60.0));
    cmd->callback([&exitCode] {
        if (!parseResolutionOption(resolution, opt.overrides)) {
            exitCode = kExitUsage;
            return;
        }
        if (!opt.screenshotPath.empty()) {
            const std::string ext = fs::path(opt.screenshotPath).extension().string();
            try {
                if (ext == ".exr") {
                    checkOutputPath(opt.screenshotPath, opt.scenePath);
                } else if (ext != ".png") {
                    throw Error(ErrorCode::Usage, "", "--screenshot '" + opt.screenshotPath + "' must end in .png or .exr");
                } else {
                    std::error_code ec;
                    if (fs::equivalent(opt.screenshotPath, opt.scenePath, ec))
                        throw Error(ErrorCode::Usage, "", "--screenshot would overwrite the scene file");
                    const fs::path dir = fs::path(opt.screenshotPath).parent_path();
                    if (!dir.empty() && !fs::is_directory(dir, ec))
                        throw IoError("the folder of --screenshot '" + opt.screenshotPath + "' does not exist");
                }
            } catch (const std::exception& e) {
                std::fprintf(stderr, "specula: error: %s\n", e.what());
                exitCode = exitCodeFor(e);
                return;
            }
        }
        std::signal(SIGINT, onViewSignal);
        std::signal(SIGTERM, onViewSignal);
        exitCode = preview::runViewer(opt, gStopView);
    });
}

}  // namespace specula
