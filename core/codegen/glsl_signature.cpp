// Parsing node GLSL prototypes and binding their parameters to ports by name (glsl_signature.h).
#include "core/codegen/glsl_signature.h"

#include "core/util/error.h"

#include <algorithm>
#include <cctype>
#include <set>
#include <stdexcept>

namespace specula::codegen {

using namespace specula::graph;

namespace {

std::string trim(const std::string& s) {
    size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
    return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

// Source text with // and /* */ comments replaced by spaces (positions kept).
std::string stripComments(const std::string& src) {
    std::string r = src;
    for (size_t i = 0; i + 1 < r.size(); ++i) {
        if (r[i] == '/' && r[i + 1] == '/') {
            while (i < r.size() && r[i] != '\n') r[i++] = ' ';
        } else if (r[i] == '/' && r[i + 1] == '*') {
            while (i + 1 < r.size() && !(r[i] == '*' && r[i + 1] == '/')) r[i++] = ' ';
            if (i + 1 < r.size()) r[i] = r[i + 1] = ' ';
        }
    }
    return r;
}

bool isIdent(char c) { return std::isalnum((unsigned char)c) || c == '_'; }

}  // namespace

std::vector<GlslPrototype> parseGlslPrototypes(const std::string& source, const std::string& function) {
    std::vector<GlslPrototype> out;
    const std::string src = stripComments(source);
    for (size_t pos = src.find(function); pos != std::string::npos; pos = src.find(function, pos + 1)) {
        if (pos > 0 && isIdent(src[pos - 1])) continue;
        size_t after = pos + function.size();
        if (after < src.size() && isIdent(src[after])) continue;
        // "void" before the name: a definition or declaration, not a call.
        size_t b = src.find_last_not_of(" \t\r\n", pos == 0 ? 0 : pos - 1);
        if (b == std::string::npos || b < 3 || src.compare(b - 3, 4, "void") != 0) continue;
        size_t open = src.find_first_not_of(" \t\r\n", after);
        if (open == std::string::npos || src[open] != '(') continue;
        size_t close = src.find(')', open);
        if (close == std::string::npos) continue;
        GlslPrototype p;
        p.function = function;
        std::string list = src.substr(open + 1, close - open - 1);
        size_t start = 0;
        while (start <= list.size()) {
            size_t comma = list.find(',', start);
            std::string part = trim(list.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
            if (!part.empty()) {
                std::vector<std::string> words;
                std::string w;
                for (char c : part + " ") {
                    if (isIdent(c)) w += c;
                    else if (!w.empty()) words.push_back(w), w.clear();
                }
                GlslParam prm;
                size_t k = 0;
                for (; k < words.size() && (words[k] == "in" || words[k] == "out" || words[k] == "inout" || words[k] == "const"); ++k)
                    prm.out |= words[k] == "out" || words[k] == "inout";
                if (words.size() - k >= 2) {
                    prm.type = words[k];
                    prm.name = words[k + 1];
                    p.params.push_back(prm);
                }
            }
            if (comma == std::string::npos) break;
            start = comma + 1;
        }
        out.push_back(std::move(p));
    }
    return out;
}

std::string glslParamName(const std::string& portName) {
    // GLSL 4.50 keywords and reserved words a port name could plausibly collide with.
    static const std::set<std::string> kReserved = {
        "in", "out", "inout", "uniform", "filter", "sample", "input", "output", "common", "partition", "active",
        "precision", "texture", "buffer", "shared", "patch", "flat", "smooth", "layout", "const", "struct",
        "discard", "return", "switch", "case", "default", "float", "int", "bool", "vec2", "vec3", "vec4",
        "mat2", "mat3", "mat4", "highp", "mediump", "lowp", "invariant", "precise", "subroutine", "attribute",
        "varying", "noperspective", "centroid", "coherent", "volatile", "restrict", "readonly", "writeonly",
        "resource", "half", "fixed", "long", "short", "double", "unsigned", "superp", "namespace", "using",
        "class", "union", "enum", "typedef", "template", "this", "goto", "inline", "noinline", "public",
        "static", "extern", "external", "interface", "sizeof", "cast", "asm", "true", "false", "while", "do",
        "for", "if", "else", "break", "continue", "void",
        // built-in functions a parameter would hide
        "sign", "length", "normalize", "dot", "cross", "mix", "clamp", "pow", "min", "max", "abs", "floor", "step",
        "exp", "log", "sqrt", "reflect", "distance", "fract", "mod"};
    return kReserved.count(portName) ? portName + "_" : portName;
}

std::string glslPortType(const PortSpec& p) {
    if (p.type == TypeDesc::String) return "int";
    return glslTypeName(p.type);
}

std::string glslOutputParamName(const NodeSpec& spec, int k) {
    const std::string& n = spec.outputs[size_t(k)].name;
    for (const PortSpec& in : spec.inputs)
        if (in.name == n) return glslParamName(n + "_out");
    return glslParamName(n);
}

namespace {

// Binds one prototype; returns "" on success or the reason it does not fit.
std::string tryBind(const NodeSpec& spec, const GlslPrototype& proto, std::vector<GlslArgRole>& roles) {
    roles.clear();
    std::vector<char> inUsed(spec.inputs.size(), 0), outUsed(spec.outputs.size(), 0), resUsed(spec.resources.size(), 0);
    for (const GlslParam& prm : proto.params) {
        if (prm.type == "SpeculaClosureQuery" && !prm.out) {
            roles.push_back({GlslArgRole::Query});
            continue;
        }
        if (prm.type == "SpeculaShadingInputs" && !prm.out) {
            roles.push_back({GlslArgRole::Shading});
            continue;
        }
        bool found = false;
        if (prm.out) {
            for (size_t k = 0; k < spec.outputs.size() && !found; ++k)
                if (glslOutputParamName(spec, int(k)) == prm.name) {
                    if (glslTypeName(spec.outputs[k].type) != prm.type)
                        return "output '" + spec.outputs[k].name + "' is " + glslTypeName(spec.outputs[k].type) + ", parameter '" +
                               prm.name + "' is " + prm.type;
                    roles.push_back({GlslArgRole::Output, int(k)});
                    outUsed[k] = 1;
                    found = true;
                }
        } else {
            for (size_t k = 0; k < spec.inputs.size() && !found; ++k)
                if (glslParamName(spec.inputs[k].name) == prm.name) {
                    const PortSpec& p = spec.inputs[k];
                    if (p.type == TypeDesc::String && p.enumValues.empty())
                        return "string input '" + p.name + "' has no GLSL value; parameter '" + prm.name + "' cannot take it";
                    if (glslPortType(p) != prm.type)
                        return "input '" + p.name + "' is " + glslPortType(p) + ", parameter '" + prm.name + "' is " + prm.type;
                    roles.push_back({GlslArgRole::Input, int(k)});
                    inUsed[k] = 1;
                    found = true;
                }
            for (size_t k = 0; k < spec.resources.size() && !found; ++k)
                if (spec.resources[k].name == prm.name) {
                    if (spec.resources[k].glslType != prm.type)
                        return "resource '" + prm.name + "' is " + spec.resources[k].glslType + ", parameter is " + prm.type;
                    roles.push_back({GlslArgRole::Resource, int(k)});
                    resUsed[k] = 1;
                    found = true;
                }
        }
        if (!found) {
            std::vector<std::string> names;
            if (prm.out)
                for (size_t k = 0; k < spec.outputs.size(); ++k) names.push_back(glslOutputParamName(spec, int(k)));
            else
                for (auto& p : spec.inputs) names.push_back(glslParamName(p.name));
            for (auto& r : spec.resources) names.push_back(r.name);
            std::string near = nearestName(prm.name, names);
            return std::string(prm.out ? "out " : "") + "parameter '" + prm.name + "' matches no " +
                   (prm.out ? "output" : "input or resource") + (near.empty() ? "" : " (nearest: '" + near + "')");
        }
    }
    for (size_t k = 0; k < spec.inputs.size(); ++k) {
        const PortSpec& p = spec.inputs[k];
        if (!inUsed[k] && !(p.type == TypeDesc::String && p.enumValues.empty()))
            return "input '" + p.name + "' has no parameter '" + glslParamName(p.name) + "'";
    }
    for (size_t k = 0; k < spec.outputs.size(); ++k)
        if (!outUsed[k]) return "output '" + spec.outputs[k].name + "' has no out parameter '" + glslOutputParamName(spec, int(k)) + "'";
    for (size_t k = 0; k < spec.resources.size(); ++k)
        if (!resUsed[k]) return "resource '" + spec.resources[k].name + "' has no parameter";
    return "";
}

}  // namespace

GlslNodeBinding bindGlslFunction(const NodeSpec& spec) {
    const std::string* src = spec.glslSource();
    if (!src) throw std::runtime_error(spec.id + ": no GLSL source '" + spec.glslFile + "'");
    std::vector<GlslPrototype> protos = parseGlslPrototypes(*src, spec.glslFunction);
    if (protos.empty()) throw std::runtime_error(spec.id + ": nodes/" + spec.glslFile + " defines no function " + spec.glslFunction);
    std::string why;
    for (const GlslPrototype& p : protos) {
        GlslNodeBinding b;
        std::string r = tryBind(spec, p, b.roles);
        if (r.empty()) {
            b.prototype = p;
            return b;
        }
        if (why.empty()) why = r;
    }
    throw std::runtime_error(spec.id + ": no prototype of " + spec.glslFunction + " in nodes/" + spec.glslFile +
                             " binds its ports by name: " + why);
}

std::string glslNodeCall(const NodeSpec& spec, const std::function<std::string(const GlslArgRole&)>& arg) {
    GlslNodeBinding b = bindGlslFunction(spec);
    std::string s = spec.glslFunction + "(";
    for (size_t i = 0; i < b.roles.size(); ++i) s += (i ? ", " : "") + arg(b.roles[i]);
    return s + ")";
}

std::string glslEnumConstant(const PortSpec& p, int index) {
    std::string v = p.enumValues.at(size_t(index));
    for (char& c : v) c = isIdent(c) ? char(std::toupper((unsigned char)c)) : '_';
    return p.enumDesc ? p.enumDesc->glslPrefix + "_" + v : std::to_string(index);
}

std::string glslEnumConstants(const NodeSpec& spec) {
    std::string r;
    std::set<std::string> done;
    // Every node sharing spec's .glsl file, or whose .glsl file spec uses as a library: the code may use any of their
    // constants.
    std::vector<const PortSpec*> ports;
    auto isLibrary = [&](const std::string& file) {
        return !file.empty() && std::find(spec.glslLibraries.begin(), spec.glslLibraries.end(), file) != spec.glslLibraries.end();
    };
    for (const NodeSpec* other : NodeRegistry::instance().all())
        if (other == &spec || (!spec.glslFile.empty() && other->glslFile == spec.glslFile) || isLibrary(other->glslFile))
            for (const PortSpec& p : other->inputs) ports.push_back(&p);
    if (!NodeRegistry::instance().find(spec.id))
        for (const PortSpec& p : spec.inputs) ports.push_back(&p);
    for (const PortSpec* pp : ports) {
        const PortSpec& p = *pp;
        if (!p.enumDesc || !done.insert(p.enumDesc->glslPrefix).second) continue;
        r += "#ifndef SPC_ENUM_" + p.enumDesc->glslPrefix + "\n#define SPC_ENUM_" + p.enumDesc->glslPrefix + "\n";
        for (size_t i = 0; i < p.enumValues.size(); ++i)
            r += "const int " + glslEnumConstant(p, int(i)) + " = " + std::to_string(i) + ";\n";
        r += "#endif\n";
    }
    return r;
}

}  // namespace specula::codegen
