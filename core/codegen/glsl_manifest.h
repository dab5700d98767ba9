// The resource manifest of an emitted GLSL module: every uniform-block member and every resource with its binding,
// GLSL type, size, format and colour space, the texels written as EXR files beside it (specula glsl --resources).
#pragma once

#include "core/codegen/glsl_emitter.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace specula {
class ColorConfig;
}

namespace specula::codegen {

// The manifest of 'mod' (format version 1, documented in docs/graph-format.md). levelFiles[r][l] names the EXR of
// level l of resource r, relative to the manifest; pass {} to omit file names.
nlohmann::json glslManifest(const GlslModule& mod, const std::vector<graph::ResourceImage>& images,
                            const std::vector<std::vector<std::string>>& levelFiles);

// Writes every resource level of 'mod' as an RGBA float EXR (<resource name>_l<level>.exr; the EXR's bottom row is
// GL row 0) and manifest.json into 'dir' (which must exist; IoError otherwise), all written to temporaries and renamed
// together, so a failed write (IoError) leaves the previous set. Error(Usage) before anything is written when a target
// is a file the command read (core/util/input_files.h). Returns the manifest.
nlohmann::json writeGlslResources(const GlslModule& mod, const std::vector<graph::ResourceImage>& images,
                                  const std::string& dir, const ColorConfig& color);

}  // namespace specula::codegen
