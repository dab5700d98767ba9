// GraphMaterial: Material implemented by a compiled node-graph Program; loadGraphMaterial.
#include "core/graph/graph_material.h"

namespace specula {

void GraphMaterial::build(const ShadingPoint& sp, ScratchArena& arena, Closure& out, Color3* emission) const {
    program_.shade(sp, arena, &out, emission);
}

void GraphMaterial::buildBatch(const ShadingPoint* const* sps, size_t n, ScratchArena& arena, Closure* const* out,
                               Color3* emission) const {
    program_.shadeBatch(sps, n, arena, out, emission);
}

std::shared_ptr<Material> loadGraphMaterial(const nlohmann::json& material, const std::string& jsonPointer,
                                            const GraphLoadContext& ctx) {
    graph::GraphDesc desc = graph::parseGraph(material, jsonPointer);
    if (ctx.warnings) ctx.warnings->insert(ctx.warnings->end(), desc.warnings.begin(), desc.warnings.end());
    graph::Program prog = graph::Program::compile(desc, {{desc.outputNode, desc.outputPort}}, &ctx);
    return std::make_shared<GraphMaterial>(std::move(desc), std::move(prog));
}

}  // namespace specula
