// GLSL backend: turns a validated material graph into a self-contained `#version 450` module with a
// uniform block for literals, samplers for textures, one function per used node and specula_eval().
#pragma once

#include "core/graph/graph.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace specula::codegen {

struct GlslOptions {
    std::string materialName;        // for the header comment
    bool literalsAsUniforms = true;  // JSON literals -> uniform block (tweakable); false: inline constants
};

// One member of the std140 uniform block SpeculaMaterialParams (binding 0).
struct GlslUniform {
    std::string name;            // member name, e.g. u_spec_roughness
    graph::TypeDesc type;
    uint32_t offset = 0;         // std140 byte offset
    std::array<float, 3> value;  // the literal's value (upload this)
    std::string pointer;         // JSON pointer of the literal
};

// One sampler2D the host must bind: the TextureStore image (working space, MIP-mapped, rows
// bottom-up), with wrap mode 'wrap' and trilinear filtering.
struct GlslTexture {
    std::string name;  // uniform name, e.g. spc_tex_albedo
    int binding = 0;   // texture unit
    std::string nodeId, file, colorspace, wrap;
};

struct GlslModule {
    std::string source;
    std::vector<GlslUniform> uniforms;
    uint32_t uniformBlockSize = 0;  // bytes (0: no block)
    std::vector<GlslTexture> textures;
    std::vector<std::string> nodeTypes;  // used node types, sorted
};

GlslModule emitGlsl(const graph::GraphDesc& g, const GlslOptions& opt = {});

// Bit-exact GLSL spelling of a float ("%.9g" round-trips every float; always has '.' or 'e').
std::string glslFloat(float v);
// A GLSL literal of a numeric type from its components (float, vec2(..), vec3(..)).
std::string glslLiteral(graph::TypeDesc t, const std::array<float, 3>& v);
// A valid, readable GLSL identifier from a node id.
std::string glslIdentifier(const std::string& s);

}  // namespace specula::codegen
