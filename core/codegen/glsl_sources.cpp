// Registry of embedded node GLSL files (filled by the generated node_glsl_sources.cpp).
#include "core/codegen/glsl_sources.h"

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

}  // namespace specula::codegen
