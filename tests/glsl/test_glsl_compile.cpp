// Drift guard (static): every registered node's GLSL, called with the prototype derived from its
// PortSpecs inside a test main, compiles with glslangValidator -S frag; so does the module emitted
// for every test and example material.
#include "core/codegen/glsl_emitter.h"
#include "core/codegen/glsl_signature.h"
#include "core/codegen/glsl_sources.h"
#include "core/graph/graph.h"
#include "core/util/error.h"
#include "glsl_harness.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

using namespace specula;
using namespace specula::graph;
namespace fs = std::filesystem;

namespace {

std::string literalOf(const PortSpec& p) {
    if (p.type == TypeDesc::Closure) return "spc_test_closure";
    if (p.type == TypeDesc::String) return codegen::glslEnumConstant(p, 0);
    return codegen::glslLiteral(p.type, p.def);
}

// A fragment shader calling 'spec' once with its defaults.
std::string nodeTestShader(const NodeSpec& spec) {
    std::string src = "#version 450\n" + codegen::glslPrelude() + codegen::glslEnumConstants(spec) +
                      codegen::glslNodeLibraries(spec.glslLibraries) + *spec.glslSource() + "\n";
    src += "layout(location = 0) out vec4 spc_out;\n";
    std::vector<std::string> resources;
    for (size_t r = 0; r < spec.resources.size(); ++r) {
        resources.push_back("spc_test_res" + std::to_string(r));
        src += "layout(binding = " + std::to_string(r) + ") uniform " + spec.resources[r].glslType + " " + resources.back() + ";\n";
    }
    src += "void main() {\n";
    src += "    SpeculaShadingInputs s = specula_shading_inputs(gl_FragCoord.xyz, vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, 1.0),\n"
           "                                                    vec4(1.0, 0.0, 0.0, 1.0), gl_FragCoord.xy / 64.0);\n";
    src += "    SpeculaClosureQuery q = specula_direction_query(vec3(0.0, 0.0, 1.0), normalize(vec3(0.3, 0.1, 1.0)), 1.0 / 0.0);\n";
    src += "    SpeculaClosure spc_test_closure = spc_closure_none();\n    spc_test_closure.f = vec3(0.25);\n";
    std::vector<std::string> outs;
    std::string sum = "vec4(0.0)";
    for (size_t k = 0; k < spec.outputs.size(); ++k) {
        std::string v = "o" + std::to_string(k);
        src += std::string("    ") + glslTypeName(spec.outputs[k].type) + " " + v + ";\n";
        outs.push_back(v);
        switch (spec.outputs[k].type) {
            case TypeDesc::Closure: sum += " + vec4(" + v + ".f + " + v + ".emission, 1.0)"; break;
            case TypeDesc::Float: sum += " + vec4(" + v + ")"; break;
            case TypeDesc::Vec2: sum += " + vec4(" + v + ", 0.0, 0.0)"; break;
            default: sum += " + vec4(" + v + ", 0.0)"; break;
        }
    }
    src += "    " + glsltest::nodeCall(spec, [&](int k) { return literalOf(spec.inputs[k]); }, outs, resources) + ";\n";
    src += "    spc_out = " + sum + ";\n}\n";
    return src;
}

}  // namespace

TEST(GlslCompile, EveryNodeCompilesWithGlslang) {
    auto specs = NodeRegistry::instance().all();
    ASSERT_FALSE(specs.empty());
    for (const NodeSpec* spec : specs) {
        SCOPED_TRACE(spec->id + "  " + spec->glslPrototype());
        ASSERT_NE(spec->glslSource(), nullptr) << "no GLSL for " << spec->id;
        std::string log;
        EXPECT_TRUE(glsltest::glslangCompile(nodeTestShader(*spec), &log)) << log;
    }
}

TEST(GlslCompile, EveryEmbeddedFileBelongsToANode) {
    // A .glsl no NodeSpec refers to is dead code that would silently drift.
    for (const std::string& path : codegen::embeddedGlslPaths()) {
        bool used = false;
        for (const NodeSpec* s : NodeRegistry::instance().all()) {
            used |= s->glslFile == path;
            for (const std::string& lib : s->glslLibraries) used |= lib == path;  // a shared library (shared/ltc.glsl)
        }
        EXPECT_TRUE(used) << path;
    }
}

// Every graph material in the test data and in examples/ emits a module that compiles.
TEST(GlslCompile, EmittedMaterialsCompile) {
    std::vector<fs::path> files = {fs::path(SPECULA_SOURCE_DIR) / "tests/glsl/data/materials.json"};
    if (fs::exists(fs::path(SPECULA_SOURCE_DIR) / "examples"))
        for (auto& e : fs::recursive_directory_iterator(fs::path(SPECULA_SOURCE_DIR) / "examples"))
            if (e.path().extension() == ".json") files.push_back(e.path());
    int compiled = 0;
    for (auto& f : files) {
        nlohmann::json scene;
        std::ifstream(f) >> scene;
        if (!scene.contains("materials")) continue;
        for (auto it = scene["materials"].begin(); it != scene["materials"].end(); ++it) {
            if (!it.value().is_object() || !it.value().contains("nodes")) continue;  // not a graph material
            SCOPED_TRACE(f.string() + " " + it.key());
            GraphDesc g = parseGraph(it.value(), "/materials/" + it.key());
            for (bool uniforms : {true, false}) {
                codegen::GlslOptions opt;
                opt.materialName = it.key();
                opt.literalsAsUniforms = uniforms;
                codegen::GlslModule m = codegen::emitGlsl(g, opt);
                std::string src = m.source +
                                  "layout(location = 0) out vec4 spc_out;\n"
                                  "void main() {\n"
                                  "    SpeculaShadingInputs s = specula_shading_inputs(gl_FragCoord.xyz, vec3(0, 0, 1), vec3(0, 0, 1),\n"
                                  "                                                    vec4(1, 0, 0, 1), gl_FragCoord.xy / 64.0);\n"
                                  "    vec3 wo = vec3(0, 0, 1);\n"
                                  "    spc_out = vec4(specula_eval(s, wo, normalize(vec3(0.2, 0.1, 1.0))) + specula_emission(s, wo), 1.0);\n"
                                  "}\n";
                std::string log;
                EXPECT_TRUE(glsltest::glslangCompile(src, &log)) << log << "\n" << src;
                ++compiled;
            }
        }
    }
    EXPECT_GE(compiled, 8);
}

TEST(GlslEmitter, ReadableDeterministicOutput) {
    std::ifstream in(std::string(SPECULA_SOURCE_DIR) + "/tests/glsl/data/materials.json");
    nlohmann::json scene;
    in >> scene;
    GraphDesc g = parseGraph(scene["materials"]["bumpy_copper"], "/materials/bumpy_copper");
    codegen::GlslModule a = codegen::emitGlsl(g), b = codegen::emitGlsl(g);
    EXPECT_EQ(a.source, b.source);
    EXPECT_NE(a.source.find("#version 450"), std::string::npos);
    EXPECT_NE(a.source.find("// node 'nmap' (texture.normal_map)"), std::string::npos);
    EXPECT_NE(a.source.find("vec3 nmap_normal;"), std::string::npos);
    EXPECT_NE(a.source.find("uniform SpeculaMaterialParams"), std::string::npos);
    EXPECT_NE(a.source.find("vec3 specula_eval(SpeculaShadingInputs s, vec3 wo, vec3 wi)"), std::string::npos);
    // each node file once, even though math.mul/mix variants share files
    size_t first = a.source.find("void spc_bsdf_ggx("), second = a.source.find("void spc_bsdf_ggx(", first + 1);
    EXPECT_NE(first, std::string::npos);
    EXPECT_EQ(second, std::string::npos);
    // std140 layout: vec3 members 16-aligned
    for (auto& u : a.uniforms)
        if (typeWidth(u.type) == 3) EXPECT_EQ(u.offset % 16, 0u) << u.name;
    EXPECT_EQ(codegen::glslFloat(0.1f), "0.100000001");
    EXPECT_EQ(codegen::glslFloat(2.f), "2.0");
}

// Issue 16: names from the scene file reach the module only as identifiers (glslIdentifier) or inside comments
// (glslCommentText): a newline in a material name or node id, or a trailing backslash (line splicing), must not
// inject or swallow source. The hostile module must still compile and hold no injected line.
TEST(GlslEmitter, SceneNamesCannotInjectSource) {
    const std::string evil = "x\n#error injected\nvoid injected() {}\n// \\";
    nlohmann::json material = {{"nodes", {{evil, {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", 0.3}}}}},
                                          {"tail\\", {{"type", "bsdf.diffuse"}}},
                                          {"sum", {{"type", "closure.add"}, {"inputs", {{"a", "@" + evil + ".bsdf"}, {"b", "@tail\\.bsdf"}}}}}}},
                               {"output", "@sum.bsdf"}};
    GraphDesc g = parseGraph(material, "/materials/" + specula::pointerEscape(evil));
    codegen::GlslOptions opt;
    opt.materialName = evil;
    codegen::GlslModule m = codegen::emitGlsl(g, opt);
    EXPECT_EQ(m.source.find("\n#error injected"), std::string::npos);
    EXPECT_EQ(m.source.find("\nvoid injected"), std::string::npos);
    for (size_t at = m.source.find("//"); at != std::string::npos; at = m.source.find("//", at + 2)) {
        size_t eol = m.source.find('\n', at);
        ASSERT_NE(eol, std::string::npos);
        EXPECT_NE(m.source[eol - 1], '\\') << m.source.substr(at, eol - at);
    }
    std::string src = m.source +
                      "layout(location = 0) out vec4 spc_out;\n"
                      "void main() {\n"
                      "    SpeculaShadingInputs s = specula_shading_inputs(gl_FragCoord.xyz, vec3(0, 0, 1), vec3(0, 0, 1),\n"
                      "                                                    vec4(1, 0, 0, 1), gl_FragCoord.xy / 64.0);\n"
                      "    spc_out = vec4(specula_eval(s, vec3(0, 0, 1), vec3(0, 0, 1)), 1.0);\n"
                      "}\n";
    std::string log;
    EXPECT_TRUE(glsltest::glslangCompile(src, &log)) << log << "\n" << src;
}
