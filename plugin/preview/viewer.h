// `specula view`: a GLFW window that draws a JSON scene with the GPU preview (PreviewRenderer) through the scene's
// OCIO view on the GPU, an orbit camera, and a reload whenever the scene file or a file it names changes.
#pragma once

#include "core/scene/scene_loader.h"

#include <atomic>
#include <string>

namespace specula::preview {

struct ViewerOptions {
    std::string scenePath;
    SceneOverrides overrides;    // width/height: the window's first size (else the scene's resolution)
    std::string screenshotPath;  // written at exit and on key S: .png the window as shown, .exr the AOVs (+ PNG)
    int exitAfterFrames = 0;     // > 0: draw this many frames (continuously), then exit; 0: until the window closes
    bool events = false;         // one JSON line per event on stdout (docs/preview.md)
    double pollSeconds = 0.2;    // how often the watched files are looked at
};

// Runs the window until it is closed, 'stop' becomes true (the CLI's SIGINT/SIGTERM) or exitAfterFrames is reached;
// returns the exit code (docs/cli.md). A scene that fails to load at start is an error (its code); one that fails
// on reload is reported (stderr, the title, a "reload_failed" event) and the last good scene stays on screen.
int runViewer(const ViewerOptions& options, const std::atomic<bool>& stop);

}  // namespace specula::preview
