// Public library API of Specula, the surface the CLI and host plugins build on: load a scene, render
// it with a progress callback and a cancel flag, get the AOV buffers, write colour-managed images.
#pragma once

#include "core/color/color_config.h"
#include "core/io/image_io.h"
#include "core/render/renderer.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "core/util/error.h"

namespace specula {

// Writes OUT.exr (all AOVs) and the OCIO-viewed PNG next to it (same stem), both atomically.
// Returns the PNG path.
std::string writeRenderOutputs(const std::string& exrPath, const Scene& scene, const ImageSet& images);

}  // namespace specula
