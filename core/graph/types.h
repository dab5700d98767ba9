// Value types of the shading-node graph (float, vec2, color3, vector3, normal3, closure, plus
// literal-only strings) and how each maps to CPU registers and to GLSL.
#pragma once

#include <cstdint>
#include <string>

namespace specula::graph {

// Port value types. Connections must match exactly; only literals are converted (see docs/graph-format.md).
enum class TypeDesc : uint8_t {
    Float,
    Vec2,
    Color3,
    Vector3,
    Normal3,
    Closure,  // weighted sum of BSDF lobes (+ emission); a register holds an index into the closure pool
    String,   // literal-only (file names, colorspaces, enum choices); never connected, never in a register
};

// Number of float registers a value of this type occupies (closure: 1 = pool index; string: 0).
inline int typeWidth(TypeDesc t) {
    switch (t) {
        case TypeDesc::Float: return 1;
        case TypeDesc::Vec2: return 2;
        case TypeDesc::Color3:
        case TypeDesc::Vector3:
        case TypeDesc::Normal3: return 3;
        case TypeDesc::Closure: return 1;
        case TypeDesc::String: return 0;
    }
    return 0;
}

inline const char* typeName(TypeDesc t) {
    switch (t) {
        case TypeDesc::Float: return "float";
        case TypeDesc::Vec2: return "vec2";
        case TypeDesc::Color3: return "color3";
        case TypeDesc::Vector3: return "vector3";
        case TypeDesc::Normal3: return "normal3";
        case TypeDesc::Closure: return "closure";
        case TypeDesc::String: return "string";
    }
    return "?";
}

// GLSL spelling of a value type (closures are the SpeculaClosure struct of the prelude).
inline const char* glslTypeName(TypeDesc t) {
    switch (t) {
        case TypeDesc::Float: return "float";
        case TypeDesc::Vec2: return "vec2";
        case TypeDesc::Color3:
        case TypeDesc::Vector3:
        case TypeDesc::Normal3: return "vec3";
        case TypeDesc::Closure: return "SpeculaClosure";
        case TypeDesc::String: return "int";  // enum strings are passed as their index
    }
    return "?";
}

inline bool isNumeric(TypeDesc t) { return t != TypeDesc::Closure && t != TypeDesc::String; }

}  // namespace specula::graph
