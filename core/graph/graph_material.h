// Entry point for the scene loader: a material's node graph (JSON) -> a Material whose shade()
// runs the compiled graph program and builds the closure (and emission) at each shading point.
#pragma once

#include "core/graph/graph.h"
#include "core/render/material.h"

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

namespace specula {

class TextureStore;

struct GraphLoadContext {
    TextureStore* textures = nullptr;  // image textures are loaded through it (may be null: no textures)
    std::string baseDir;               // relative texture paths are resolved against it
    std::vector<std::string>* warnings = nullptr;  // where soft-range warnings go (may be null: dropped)
    // Compile every node that has one with its NodeSpec::gpuSubstituteCpu, the CPU twin of what its GLSL computes
    // (the parity suite; a CPU rendering of what the GPU will show). false: the real models.
    bool gpuSubstitutes = false;
};

// A Material backed by a compiled node graph.
class GraphMaterial final : public Material {
public:
    GraphMaterial(graph::GraphDesc desc, graph::Program program)
        : desc_(std::move(desc)), program_(std::move(program)) {}
    bool isEmissive() const override { return program_.emissive(); }
    bool needsDerivatives() const override { return program_.needsDerivatives(); }
    const graph::GraphDesc& desc() const { return desc_; }
    const graph::Program& program() const { return program_; }

protected:
    void build(const ShadingPoint& sp, ScratchArena& arena, Closure& out, Color3* emission) const override;
    void buildBatch(const ShadingPoint* const* sps, size_t n, ScratchArena& arena, Closure* const* out,
                    Color3* emission) const override;

private:
    graph::GraphDesc desc_;
    graph::Program program_;
};

// Parses, validates and compiles one material graph. 'jsonPointer' locates 'material' in the scene
// (e.g. "/materials/steel"); every InputError names the offending value's pointer.
std::shared_ptr<Material> loadGraphMaterial(const nlohmann::json& material, const std::string& jsonPointer,
                                            const GraphLoadContext& ctx);

}  // namespace specula
