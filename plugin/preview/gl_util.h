// Headless OpenGL 4.5 core for the GPU preview and the GLSL tests: an EGL context without a window (Mesa's
// surfaceless platform, else an EGL device such as NVIDIA's), shader programs, and resources bound from a manifest.
#pragma once

#include "core/graph/node_spec.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace specula::gl {

// The process's GL 4.5 core context, created on first use and current on the calling thread from then on. Returns
// false with the reason when no driver offers one.
bool context(std::string* why = nullptr);
std::string renderer();  // GL_RENDERER of the context ("" before context())

// Links a program from vertex and fragment source; 0 on failure with the driver's log in *log.
unsigned program(const std::string& vertex, const std::string& fragment, std::string* log);

// A texture made from a resource's texels and sampler state (graph::ResourceImage), of the target its GLSL type
// needs (sampler2D: GL_TEXTURE_2D, sampler1DArray: GL_TEXTURE_1D_ARRAY, sampler2DArray: GL_TEXTURE_2D_ARRAY with
// ResourceImage::Level::layers). Bind it at the resource's binding.
struct Texture {
    unsigned name = 0, target = 0;
};
Texture resourceTexture(const graph::ResourceImage& image, const std::string& glslType);

// What a host does with emitted modules: each module's uniform block (member values at their offsets) and resource
// textures bound at the bindings its manifest lists, nothing else (docs/graph-format.md). Owns the GL objects.
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
    std::vector<Texture> textures_;
    std::vector<int> textureBindings_;
};

}  // namespace specula::gl
