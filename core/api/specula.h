// libspecula's front-end policies over the internal types (the CLI uses them; the public API in
// include/specula/specula.h wraps them): the output policy (atomic, partial-on-cancel, never clobbering),
// the exit-code mapping and the progress-event JSON of `specula render --progress json`.
#pragma once

#include "core/color/color_config.h"
#include "core/io/image_io.h"
#include "core/render/renderer.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "core/util/error.h"

#include <exception>
#include <string>
#include <vector>

namespace specula {

struct WrittenFiles {
    std::string exr, png;  // exr empty for a PNG-only output, png empty for a partial image
    bool partial = false;
};

// OUT.exr: writes every AOV there and the OCIO-viewed PNG next to it (same stem); OUT.png: only the viewed PNG.
// Atomic: the files appear whole, together, or not at all.
WrittenFiles writeRenderOutputs(const std::string& outPath, const Scene& scene, const ImageSet& images);
bool isPngOutput(const std::string& outPath);  // ends in .png (any case)

// OUT.exr or OUT.png -> OUT.partial.exr (a cancelled render keeps every AOV, whatever the output asked for).
std::string partialOutputPath(const std::string& outPath);

// Checks an output path before rendering: Error(Usage) unless it ends in .exr or .png, Error(Usage) if it (or its
// PNG) is the input scene file 'inputPath' (never clobber the input), Error(Io) if its folder is missing.
// The messages are the CLI's ("output 'x' must end in .exr (...) or .png (...)", ...).
void checkOutputPath(const std::string& exrPath, const std::string& inputPath = "");

// No command writes over its own input: Error(Usage) "<option> 'out' is the input file 'in'" if 'output' names the
// same file as one of 'inputs' (after resolving links and relative paths; missing files never match).
void refuseOverwritingInput(const std::string& output, const std::vector<std::string>& inputs, const std::string& option);

// The output policy of a finished or cancelled render: complete -> OUT.exr + OUT.png, or OUT.png alone
// (writeRenderOutputs); cancelled -> only OUT.partial.exr with metadata specula:partial = "true",
// OUT.exr untouched. Throws IoError / ImageIoError.
WrittenFiles writeRenderResult(const std::string& exrPath, const Scene& scene, ImageSet& images, const RenderStats& stats);

// The one table of option ranges that every front end applies (issue 35): the CLI's checks are built from it and the
// C++ API, the C ABI and the Python module call checkOption with it, so `--threads -3` and `threads = -3` are the same
// usage error (exit 2, SPC_USAGE). 'name' is the CLI's option; the API names it the same way without dashes.
struct OptionRule {
    const char* name;
    double min, max;  // inclusive; NaN is outside every range
    constexpr bool contains(double value) const { return value >= min && value <= max; }
};
namespace option_rules {
inline constexpr OptionRule spp{"--spp", 1, 1 << 20};
inline constexpr OptionRule threads{"--threads", 0, 1024};  // 0: all cores
inline constexpr OptionRule seed{"--seed", 0, 2147483647};
inline constexpr OptionRule frame{"--frame", -1000000, 1000000};
inline constexpr OptionRule sampleBlock{"--sample-block", 0, 1 << 20};
inline constexpr OptionRule resolutionSide{"--resolution", 1, 16384};  // either side
inline constexpr OptionRule brushAngle{"--angle", -360, 360};         // normalmap, degrees
inline constexpr OptionRule footprint{"--footprint", 0, 1e6};         // plot, d(uv) per pixel
}  // namespace option_rules
// Error(Usage) "<name> <value> is outside <min>..<max>" unless min <= value <= max.
void checkOption(const OptionRule& rule, double value);

// The exit code of an error reaching a front end (docs/cli.md): Error -> its code; std::invalid_argument
// -> usage (2); anything else (a malformed value deep in a loader) -> bad input (1).
int exitCodeFor(const std::exception& e);

// The progress events of `specula render --progress json` (docs/cli.md), without the trailing newline.
std::string tileEventJson(const RenderProgress& p);
std::string cancelledEventJson(const RenderStats& st, const std::string& partialPath);
std::string doneEventJson(const RenderStats& st, const std::string& exrPath, const std::string& pngPath);

}  // namespace specula
