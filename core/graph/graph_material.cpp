// GraphMaterial: Material implemented by a compiled node-graph Program; loadGraphMaterial.
#include "core/graph/graph_material.h"

namespace specula {

void GraphMaterial::shade(ShadingPoint& sp, ScratchArena& arena, Closure& out) const {
    out.clear();
    program_.shade(sp, arena, &out, nullptr);
}

Color3 GraphMaterial::emission(const ShadingPoint& sp) const {
    if (!program_.emissive()) return Color3(0.f);
    thread_local ScratchArena arena(16 * 1024);
    ShadingPoint copy = sp;
    Color3 e(0.f);
    program_.shade(copy, arena, nullptr, &e);
    arena.reset();
    return e;
}

std::shared_ptr<Material> loadGraphMaterial(const nlohmann::json& material, const std::string& jsonPointer,
                                            const GraphLoadContext& ctx) {
    graph::GraphDesc desc = graph::parseGraph(material, jsonPointer);
    graph::Program prog = graph::Program::compile(desc, {{desc.outputNode, desc.outputPort}}, &ctx);
    return std::make_shared<GraphMaterial>(std::move(desc), std::move(prog));
}

}  // namespace specula
