// GLSL backend: turns a validated material graph into a self-contained `#version 450` module with a
// uniform block for literals, samplers for textures, one function per used node and specula_eval().
#pragma once

#include "core/graph/graph.h"
#include "core/graph/graph_material.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace specula::codegen {

struct GlslOptions {
    std::string materialName;        // for the header comment
    bool literalsAsUniforms = true;  // JSON literals -> uniform block (tweakable); false: inline constants
    // Prefix of every material-specific name (entry points, uniform block and members, resources), so that several
    // materials live in one shader: "" gives specula_eval(...), "gold" gives specula_gold_eval(...). Node functions,
    // the prelude and enum constants are shared and guarded.
    std::string prefix;
    int bindingBase = 0;  // the uniform block takes bindingBase, resources bindingBase + 1, + 2, ...
    int set = -1;         // Vulkan descriptor set (layout(set = S, ...)); -1: none (OpenGL)
};

// One member of the std140 uniform block SpeculaMaterialParams (binding 0).
struct GlslUniform {
    std::string name;            // member name, e.g. u_spec_roughness
    graph::TypeDesc type;
    uint32_t offset = 0;         // std140 byte offset
    std::array<float, 3> value;  // the literal's value (upload this)
    std::string pointer;         // JSON pointer of the literal
};

// One GPU resource the host must bind (graph::ResourceSpec of a live node): its uniform, binding and what it holds.
// exportGlslResources() produces the texels and sampler state. A built-in table (same texels for every instance) is
// listed once per module and shared by all the nodes that read it; nodeId/nodeType name the first of them.
struct GlslResource {
    std::string name;      // uniform name in the module, e.g. spc_res_albedo_image
    std::string glslType;  // sampler2D, sampler1DArray, ...
    int binding = 0, set = -1;
    std::string nodeId, nodeType, resource;  // the node instance and the resource's parameter name
    graph::ResourceSpec::Kind kind = graph::ResourceSpec::Kind::ImageFile;
    std::string file, colorspace;  // image-file resources: the file as given in the material, its colour space
};

struct GlslModule {
    std::string source;
    std::vector<GlslUniform> uniforms;
    uint32_t uniformBlockSize = 0;  // bytes (0: no block)
    int uniformBinding = 0, uniformSet = -1;
    std::vector<GlslResource> resources;
    std::vector<std::string> nodeTypes;  // used node types, sorted
    // One line per used node type whose model the GPU cannot run (NodeSpec::gpuSubstitute): "<type>: <what the GLSL
    // computes instead>". Front ends print each once; the module's header comment repeats them.
    std::vector<std::string> warnings;
    std::string entryPrefix;             // "specula_" + prefix + "_" (or "specula_"): entry points are <entryPrefix>eval ...
};

GlslModule emitGlsl(const graph::GraphDesc& g, const GlslOptions& opt = {});

// The texels of every resource of one node instance (its string inputs, their JSON pointers and its numeric input
// values, in port order; values null = the ports' defaults), prepared with 'load' as the graph loader would.
std::vector<graph::ResourceImage> nodeResourceImages(const graph::NodeSpec& spec, const std::vector<std::string>& strings,
                                                     const std::vector<std::string>& pointers, const GraphLoadContext& load,
                                                     const std::vector<std::array<float, 3>>* values = nullptr);
// The texels and sampler state of every resource of 'mod' (same order), from the material's nodes prepared with
// 'load' (texture files are read through its TextureStore). Throws specula::InputError like the graph loader.
std::vector<graph::ResourceImage> exportGlslResources(const graph::GraphDesc& g, const GlslModule& mod,
                                                      const GraphLoadContext& load);

// Bit-exact GLSL spelling of a float ("%.9g" round-trips every float; always has '.' or 'e').
std::string glslFloat(float v);
// A GLSL literal of a numeric type from its components (float, vec2(..), vec3(..)).
std::string glslLiteral(graph::TypeDesc t, const std::array<float, 3>& v);
// A valid, readable GLSL identifier from a node id.
std::string glslIdentifier(const std::string& s);
// Scene-supplied text (names, ids, file names) made safe inside a // comment: bytes outside printable ASCII and
// backslashes become '?'.
std::string glslCommentText(const std::string& s);

}  // namespace specula::codegen
