// Binding a node's GLSL function to its ports by name: the prototype is parsed from the node's .glsl, each parameter
// is matched to the closure query, the shading inputs, an input or output port, or a declared GPU resource.
#pragma once

#include "core/graph/node_spec.h"

#include <functional>
#include <string>
#include <vector>

namespace specula::codegen {

struct GlslParam {
    std::string type;  // GLSL type spelling, e.g. "vec3", "SpeculaClosure", "sampler2D"
    std::string name;
    bool out = false;
};

struct GlslPrototype {
    std::string function;
    std::vector<GlslParam> params;
};

// Every prototype of 'function' defined in 'source' (definitions `void function(...) {`), in source order.
std::vector<GlslPrototype> parseGlslPrototypes(const std::string& source, const std::string& function);

// GLSL spelling of a port name: the name itself, or name + "_" where it is a GLSL keyword or reserved word
// (e.g. the output "out", the enum input "filter").
std::string glslParamName(const std::string& portName);

// GLSL name of output k's out parameter: glslParamName of its name, with "_out" appended when an input has the same
// name (texture.normal_map: input and output 'normal').
std::string glslOutputParamName(const graph::NodeSpec& spec, int k);

// GLSL type of an input port's value (enum ports: int).
std::string glslPortType(const graph::PortSpec& p);

// What one parameter of a node's GLSL function receives.
struct GlslArgRole {
    enum Kind : uint8_t { Query, Shading, Input, Output, Resource };
    Kind kind;
    int index = -1;  // input/output port index, or resource index (NodeSpec::resources)
};

// A node's GLSL function bound by name: the chosen prototype (typed overloads are told apart by the types of their
// ports) and the role of each parameter, in parameter order.
struct GlslNodeBinding {
    GlslPrototype prototype;
    std::vector<GlslArgRole> roles;
};

// Binds spec's GLSL function; throws std::runtime_error naming the node, the parameter and the nearest port when a
// parameter matches nothing, a port has no parameter, or types differ.
GlslNodeBinding bindGlslFunction(const graph::NodeSpec& spec);

// The call "fn(a, b, ...)" with each argument produced by 'arg' for its role.
std::string glslNodeCall(const graph::NodeSpec& spec, const std::function<std::string(const GlslArgRole&)>& arg);

// GLSL constants of every typed enum port of spec and of the nodes sharing its .glsl file (guarded, so several modules
// or nodes may repeat them):
// "#ifndef SPC_ENUM_<PREFIX> ... const int <PREFIX>_<VALUE> = i; ... #endif".
std::string glslEnumConstants(const graph::NodeSpec& spec);
// The constant naming enum value 'index' of port p: e.g. SPC_FRESNEL_CONDUCTOR.
std::string glslEnumConstant(const graph::PortSpec& p, int index);

}  // namespace specula::codegen
