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

// The include guard of a GLSL file (a path relative to nodes/): one macro per file whether it is emitted as a node's own
// file or as another node's library (bsdf.glint_pndf's GPU substitute calls into texture/lean/lean.glsl and
// bsdf/ggx_filtered/ggx_filtered.glsl), so a module that also uses those nodes holds each file once.
std::string glslFileGuard(const std::string& relPath);
// A shared GLSL library (NodeSpec::glslLibraries, a path relative to nodes/) wrapped in an include guard derived from
// its path, so that several modules or nodes may each carry a copy; an #error line if it was not embedded.
std::string glslLibraryText(const std::string& relPath);
// The guarded libraries one node needs, in its listed order (what a test shader puts before the node's own file).
std::string glslNodeLibraries(const std::vector<std::string>& relPaths);

// The prelude every emitted module starts with: SpeculaShadingInputs, SpeculaClosure, frame and
// Fresnel helpers shared by the node functions (core/codegen/glsl_prelude.cpp).
const std::string& glslPrelude();

}  // namespace specula::codegen
