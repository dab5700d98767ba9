// Registry of embedded node GLSL files (filled by the generated node_glsl_sources.cpp).
#include "core/codegen/glsl_sources.h"

#include <cctype>
#include <map>

namespace specula::codegen {

static std::map<std::string, std::string>& table() {
    static std::map<std::string, std::string> t;
    return t;
}

GlslSourceRegistrar::GlslSourceRegistrar(const char* relPath, const char* text) { table()[relPath] = text; }

const std::string* embeddedGlsl(const std::string& relPath) {
    auto it = table().find(relPath);
    return it == table().end() ? nullptr : &it->second;
}

std::vector<std::string> embeddedGlslPaths() {
    std::vector<std::string> r;
    for (auto& [k, v] : table()) r.push_back(k);
    return r;
}

std::string glslFileGuard(const std::string& relPath) {
    // The guard is a macro (not a const): #ifndef works across concatenated modules of one shader.
    std::string guard = "SPC_FILE_";
    for (char c : relPath) guard += std::isalnum((unsigned char)c) ? char(std::toupper((unsigned char)c)) : '_';
    return guard;
}

std::string glslLibraryText(const std::string& relPath) {
    const std::string guard = glslFileGuard(relPath);
    const std::string* src = embeddedGlsl(relPath);
    std::string r = "// ---- nodes/" + relPath + " (shared library)\n#ifndef " + guard + "\n#define " + guard + "\n";
    r += src ? *src : "#error missing GLSL library " + relPath + "\n";
    return r + "#endif\n";
}

std::string glslNodeLibraries(const std::vector<std::string>& relPaths) {
    std::string r;
    for (const std::string& p : relPaths) r += glslLibraryText(p);
    return r;
}

}  // namespace specula::codegen
