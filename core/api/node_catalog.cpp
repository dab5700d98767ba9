// The node catalogue as JSON (moved here from plugin/cli/nodes_command.cpp so the CLI and the API share it).
#include "core/api/node_catalog.h"

#include "core/codegen/glsl_signature.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace specula {

using namespace specula::graph;
using ojson = nlohmann::ordered_json;

// Shortest decimal text that reads back as the same float ("0.04", not "0.0399999991").
std::string shortestFloatText(float v) {
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buf[40];
    for (int prec = 1; prec <= 9; ++prec) {
        std::snprintf(buf, sizeof buf, "%.*g", prec, double(v));
        if (std::strtof(buf, nullptr) == v) {
            // %g switches to an exponent once the exponent reaches the precision ("1e+01"): widen it for
            // magnitudes below 1e7 so integers read naturally ("10").
            // (log10(0) is -inf, whose conversion to int is undefined: zero is handled first.)
            if (v != 0.f) {
                const int e = int(std::floor(std::log10(std::fabs(double(v)))));
                if (e >= prec && e < 7) std::snprintf(buf, sizeof buf, "%.*g", e + 1, double(v));
            }
            break;
        }
    }
    return buf;
}

// The same value as a JSON number (parsed from the shortest text, so the JSON shows it too).
static ojson jsonNum(float v) {
    if (!std::isfinite(v)) return nullptr;
    return std::strtod(shortestFloatText(v).c_str(), nullptr);
}

static ojson portJson(const PortSpec& p, bool input) {
    ojson j;
    j["name"] = p.name;
    j["type"] = typeName(p.type);
    if (input) {
        if (p.type == TypeDesc::String)
            j["default"] = p.required ? ojson(nullptr) : ojson(p.defString);
        else if (!isNumeric(p.type))
            j["default"] = nullptr;
        else if (typeWidth(p.type) == 1)
            j["default"] = jsonNum(p.def[0]);
        else {
            ojson a = ojson::array();
            for (int k = 0; k < typeWidth(p.type); ++k) a.push_back(jsonNum(p.def[size_t(k)]));
            j["default"] = a;
        }
        j["required"] = p.required;
        if (!p.enumValues.empty()) j["enum"] = p.enumValues;
        j["min"] = jsonNum(p.minValue);
        j["max"] = jsonNum(p.maxValue);
        j["soft_min"] = jsonNum(p.softMin);
        j["soft_max"] = jsonNum(p.softMax);
        j["hard_min"] = jsonNum(p.hardMin);
        j["hard_max"] = jsonNum(p.hardMax);
        j["binding"] = p.binding == GeomBinding::None ? ojson(nullptr) : ojson(bindingName(p.binding));
    }
    j["doc"] = p.doc;
    return j;
}

ojson nodeSpecJson(const NodeSpec& s) {
    ojson j;
    j["id"] = s.id;
    j["version"] = s.version;
    j["category"] = s.category;
    j["doc"] = s.doc;
    ojson in = ojson::array(), out = ojson::array();
    for (auto& p : s.inputs) in.push_back(portJson(p, true));
    for (auto& p : s.outputs) out.push_back(portJson(p, false));
    j["inputs"] = in;
    j["outputs"] = out;
    bool query = false, shading = false;
    try {
        for (const codegen::GlslArgRole& r : codegen::bindGlslFunction(s).roles) {
            query |= r.kind == codegen::GlslArgRole::Query;
            shading |= r.kind == codegen::GlslArgRole::Shading;
        }
    } catch (const std::exception&) {  // an unbound function shows in "prototype"
    }
    j["flags"] = {{"pure", s.has(kPure)},
                  {"needs_derivatives", s.has(kNeedsDerivatives)},
                  {"emissive", s.has(kEmissive)},
                  {"glsl_query", query},
                  {"glsl_shading", shading}};
    ojson res = ojson::array();
    for (const ResourceSpec& r : s.resources)
        res.push_back({{"name", r.name}, {"glsl_type", r.glslType}, {"kind", resourceKindName(r.kind)}, {"doc", r.doc}});
    j["resources"] = res;
    j["glsl"] = {{"function", s.glslFunction},
                 {"file", s.glslFile.empty() ? std::string() : "nodes/" + s.glslFile},
                 {"prototype", s.glslPrototype()}};
    j["parity"] = {{"tolerance", jsonNum(s.parityTolerance)}, {"note", s.parityNote}};
    if (!s.gpuSubstitute.empty()) j["gpu_substitute"] = s.gpuSubstitute;
    if (!s.notes.empty()) j["notes"] = s.notes;
    return j;
}

ojson nodeCatalogJson() {
    ojson j;
    j["nodes"] = ojson::array();
    for (auto* s : NodeRegistry::instance().all()) j["nodes"].push_back(nodeSpecJson(*s));
    return j;
}

}  // namespace specula
