// Test support for the GLSL backend: glslangValidator runs, headless EGL (Mesa surfaceless,
// llvmpipe) contexts, RGBA32F targets/data textures, and GLSL calls generated from a NodeSpec.
#pragma once

#include "core/graph/node_spec.h"

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

// A texture made from a resource's texels and sampler state (graph::ResourceImage), of the target its GLSL type
// needs (sampler2D: GL_TEXTURE_2D, sampler1DArray: GL_TEXTURE_1D_ARRAY, sampler2DArray:
// GL_TEXTURE_2D_ARRAY with ResourceImage::Level::layers). Bind it at the resource's binding.
struct GlTexture {
    unsigned name = 0, target = 0;
};
GlTexture glResourceTexture(const graph::ResourceImage& image, const std::string& glslType);

// What a host does with emitted modules: each module's uniform block (member values at their offsets) and resource
// textures bound at the bindings its manifest lists, nothing else. Owns the GL objects.
class ManifestBindings {
public:
    ManifestBindings() = default;
    ManifestBindings(const ManifestBindings&) = delete;
    ManifestBindings& operator=(const ManifestBindings&) = delete;
    ~ManifestBindings();
    // images: the module's resources in manifest order (codegen::exportGlslResources).
    void add(const nlohmann::json& manifest, const std::vector<graph::ResourceImage>& images);
    void bind() const;

private:
    std::vector<unsigned> buffers_, bufferBindings_;
    std::vector<GlTexture> textures_;
    std::vector<int> textureBindings_;
};

}  // namespace specula::glsltest
