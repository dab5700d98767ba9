// Test support for the GLSL backend: glslangValidator runs, headless EGL (Mesa surfaceless,
// llvmpipe) contexts, RGBA32F targets/data textures, and GLSL calls generated from a NodeSpec.
#pragma once

#include "core/graph/node_spec.h"
#include "plugin/preview/gl_util.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace specula::glsltest {

// Runs glslangValidator -S frag on 'source'; returns true on success, the log in *log.
bool glslangCompile(const std::string& source, std::string* log);

// Headless GL 4.5 core context (EGL_PLATFORM_SURFACELESS_MESA, EGL_SURFACE_TYPE = EGL_PBUFFER_BIT).
// Created once per process; returns false (with a reason) if unavailable.
bool glContext(std::string* why);
std::string glRenderer();

// Compiles a fullscreen-triangle program with 'fragment' as fragment shader; 0 on failure (log).
unsigned glProgram(const std::string& fragment, std::string* log);
// Uploads w*h RGBA32F texels (row-major, row 0 first) as a texture with nearest filtering.
unsigned glDataTexture(int w, int h, const std::vector<float>& rgba);
// Draws 'program' into a w*h RGBA32F target and reads back w*h*4 floats (row 0 = y 0).
std::vector<float> glRun(unsigned program, int w, int h, const std::function<void()>& bind = {});

// "fn(args...)" for a node, its parameters bound by name (codegen::glslNodeCall): inputExpr(k) gives the GLSL
// expression of input port k (numeric, enum or closure), outVars the output variables, resourceVars the uniforms of
// the node's resources (NodeSpec::resources order); the query is 'q' and the shading inputs 's'.
std::string nodeCall(const graph::NodeSpec& spec, const std::function<std::string(int)>& inputExpr,
                     const std::vector<std::string>& outVars, const std::vector<std::string>& resourceVars = {});

// Resource textures and manifest bindings: the preview's own (plugin/preview/gl_util.h), so tests bind exactly as
// a host does.
using GlTexture = gl::Texture;
inline GlTexture glResourceTexture(const graph::ResourceImage& image, const std::string& glslType) {
    return gl::resourceTexture(image, glslType);
}
using ManifestBindings = gl::ManifestBindings;

}  // namespace specula::glsltest
