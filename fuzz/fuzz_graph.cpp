// libFuzzer target: a material graph (JSON) through validation, compilation and evaluation on the CPU: parseGraph,
// Program::compile (with a texture store), one shade at a shading point with differentials, then queries and
// samples of the closure. Only specula::Error (and the JSON parser's exceptions) may leave; anything else, a crash or
// a non-finite closure value for finite inputs is a finding.
#include "core/color/color_config.h"
#include "core/graph/graph.h"
#include "core/graph/graph_material.h"
#include "core/texture/texture_store.h"
#include "core/util/error.h"
#include "fuzz/fuzz_common.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>

using namespace specula;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    // Sides capped as in fuzz_scene (kFuzzTextureSide): generated normal maps obey the cap too.
    static TextureStore store(ColorConfig::load("builtin"), fuzz::kFuzzTextureSide);
    static const std::string baseDir = std::string(SPECULA_SOURCE_DIR) + "/examples";
    nlohmann::json material;
    if (!fuzz::parseJson(data, size, material)) return 0;
    try {
        graph::GraphDesc g = graph::parseGraph(material, "/m", graph::ParseOptions{false});
        GraphLoadContext load{&store, baseDir, nullptr};
        graph::Program p = graph::Program::compile(g, {{g.outputNode, g.outputPort}}, &load);
        const ShadingPoint sp = fuzz::fuzzShadingPoint();
        ScratchArena arena;
        Closure cl;
        Color3 emission(0.f);
        p.run(sp, arena, g.nodes[g.outputNode].spec->outputs[g.outputPort].type == graph::TypeDesc::Closure ? &cl : nullptr,
              &emission);
        const Vec3 dirs[] = {glm::normalize(Vec3(0.2f, 0.1f, 1.f)), glm::normalize(Vec3(-0.7f, 0.3f, 0.4f)),
                             glm::normalize(Vec3(0.f, -0.9f, 0.2f))};
        for (const Vec3& wo : dirs)
            for (const Vec3& wi : dirs) {
                BsdfQuery q;
                q.wo = sp.frame.toWorld(wo);
                q.wi = sp.frame.toWorld(wi);
                BsdfValue v = cl.evalPdf(q);
                (void)v;
                BsdfSample s;
                cl.sample(q, 0.37f, Vec2(0.21f, 0.83f), s);
            }
    } catch (const Error&) {
        // a documented, clear error: fine
    }
    return 0;
}
