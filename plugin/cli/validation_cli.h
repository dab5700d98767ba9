// The validation options of the `specula` CLI (docs/cli.md, docs/validation/README.md):
//   render --camera-shift-px DX,DY [--print-camera]   sub-pixel camera offsets for flicker sequences
//   compare --mask FILE:LAYER ... --mask-top-rows N/D --frames K   masked metrics and flicker over frame sequences
// Kept out of main.cpp so that the hunks there stay two calls each.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace specula {

struct Scene;
struct SceneOverrides;

struct CameraShiftOptions {
    std::string shift;         // "DX,DY" in pixels; empty = no shift
    bool printCamera = false;  // print the (shifted) camera as JSON and exit without rendering
};
void addCameraShiftOptions(CLI::App& render, CameraShiftOptions& o);
// Loads 'path' like loadScene, with the camera shifted when o.shift is set. Throws like loadScene; throws
// std::invalid_argument on a malformed --camera-shift-px.
Scene loadSceneForRender(const std::string& path, const SceneOverrides& ov, const CameraShiftOptions& o);
// With --print-camera: prints {"position": [...], "look_at": [...]} (the loaded floats) and returns true.
bool printCameraIfAsked(const Scene& scene, const CameraShiftOptions& o);

struct CompareMaskOptions {
    std::vector<std::string> masks;  // FILE:LAYER (pixels where any channel of LAYER > 0; union) or "all"
    std::string topRows;             // "N/D": keep the first (rows of the mask) * N / D rows of the mask
    int frames = 0;                  // > 0: A, B and masks are printf patterns of the frame index (flicker)
    bool active() const { return !masks.empty() || !topRows.empty() || frames > 0; }
};
void addCompareMaskOptions(CLI::App& compare, CompareMaskOptions& o);
// Runs the masked / sequence comparison; prints text or one JSON object; returns the exit code. 'diffPng' (frame 0
// only) is the --diff map of the plain compare.
int runMaskedCompare(const std::string& a, const std::string& b, const std::string& aov, const CompareMaskOptions& o,
                     bool json, const std::string& diffPng = "");

}  // namespace specula
