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

// Writes OUT.exr (all AOVs) and the OCIO-viewed PNG next to it (same stem), both atomically.
// Returns the PNG path.
std::string writeRenderOutputs(const std::string& exrPath, const Scene& scene, const ImageSet& images);

// OUT.exr -> OUT.partial.exr.
std::string partialOutputPath(const std::string& exrPath);

// Checks an output path before rendering: Error(Usage) unless it ends in .exr, Error(Usage) if it (or its
// PNG) is the input scene file 'inputPath' (never clobber the input), Error(Io) if its folder is missing.
// The messages are the CLI's ("output 'x' must end in .exr (a PNG is written beside it)", ...).
void checkOutputPath(const std::string& exrPath, const std::string& inputPath = "");

// No command writes over its own input: Error(Usage) "<option> 'out' is the input file 'in'" if 'output' names the
// same file as one of 'inputs' (after resolving links and relative paths; missing files never match).
void refuseOverwritingInput(const std::string& output, const std::vector<std::string>& inputs, const std::string& option);

struct WrittenFiles {
    std::string exr, png;  // png empty for a partial image
    bool partial = false;
};

// The output policy of a finished or cancelled render: complete -> OUT.exr + OUT.png (atomic, each file
// appears whole or not at all); cancelled -> only OUT.partial.exr with metadata specula:partial = "true",
// OUT.exr untouched. Throws IoError / ImageIoError.
WrittenFiles writeRenderResult(const std::string& exrPath, const Scene& scene, ImageSet& images, const RenderStats& stats);

// The exit code of an error reaching a front end (docs/cli.md): Error -> its code; std::invalid_argument
// -> usage (2); anything else (a malformed value deep in a loader) -> bad input (1).
int exitCodeFor(const std::exception& e);

// The progress events of `specula render --progress json` (docs/cli.md), without the trailing newline.
std::string tileEventJson(const RenderProgress& p);
std::string cancelledEventJson(const RenderStats& st, const std::string& partialPath);
std::string doneEventJson(const RenderStats& st, const std::string& exrPath, const std::string& pngPath);

}  // namespace specula
