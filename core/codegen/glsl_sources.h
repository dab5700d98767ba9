// Embedded GLSL text of the node files (nodes/**/*.glsl): a build step generates a source that
// registers each file's text under its path relative to nodes/, so the binary is self-contained.
#pragma once

#include <string>
#include <vector>

namespace specula::codegen {

// nullptr if no file with that path was embedded.
const std::string* embeddedGlsl(const std::string& relPath);
std::vector<std::string> embeddedGlslPaths();

struct GlslSourceRegistrar {
    GlslSourceRegistrar(const char* relPath, const char* text);
};

// The prelude every emitted module starts with: SpeculaShadingInputs, SpeculaClosure, frame and
// Fresnel helpers shared by the node functions (core/codegen/glsl_prelude.cpp).
const std::string& glslPrelude();

}  // namespace specula::codegen
