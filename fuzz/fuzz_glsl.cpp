// libFuzzer target: a material graph (JSON) through the GLSL emitter (uniform literals and inline literals, with a
// prefix); every module the emitter returns must compile with glslang's library as a GLSL 4.50 fragment shader.
// Only specula::Error (and the JSON parser's exceptions) may leave; a module that does not compile is a finding.
#include "core/codegen/glsl_emitter.h"
#include "core/graph/graph.h"
#include "core/util/error.h"
#include "fuzz/fuzz_common.h"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstdlib>

using namespace specula;

namespace {

bool compiles(const std::string& module, std::string& log) {
    static const bool initialised = glslang::InitializeProcess();
    (void)initialised;
    const std::string src = module +
                            "layout(location = 0) out vec4 spc_out;\n"
                            "void main() {\n"
                            "    SpeculaShadingInputs s = specula_shading_inputs(gl_FragCoord.xyz, vec3(0, 0, 1), vec3(0, 0, 1),\n"
                            "                                                    vec4(1, 0, 0, 1), gl_FragCoord.xy / 64.0);\n"
                            "    vec3 wo = vec3(0, 0, 1);\n"
                            "    spc_out = vec4(specula_fz_eval(s, wo, normalize(vec3(0.2, 0.1, 1.0))) + specula_fz_emission(s, wo), 1.0);\n"
                            "}\n";
    glslang::TShader shader(EShLangFragment);
    const char* text = src.c_str();
    shader.setStrings(&text, 1);
    const bool ok = shader.parse(GetDefaultResources(), 450, false, EShMsgDefault);
    if (!ok) log = std::string(shader.getInfoLog()) + "\n" + src;
    return ok;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    nlohmann::json material;
    if (!fuzz::parseJson(data, size, material)) return 0;
    try {
        graph::GraphDesc g = graph::parseGraph(material, "/m");
        for (bool uniforms : {true, false}) {
            codegen::GlslOptions opt;
            opt.materialName = "fuzz";
            opt.prefix = "fz";
            opt.literalsAsUniforms = uniforms;
            codegen::GlslModule m = codegen::emitGlsl(g, opt);
            std::string log;
            if (!compiles(m.source, log)) {
                std::fprintf(stderr, "emitted GLSL does not compile:\n%s\n", log.c_str());
                std::abort();
            }
        }
    } catch (const Error&) {
    }
    return 0;
}
