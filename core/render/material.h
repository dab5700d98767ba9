// Material interface between the renderer and whatever builds BSDFs (compiled node graphs): given a const
// shading point, one shading pass fills a Closure (lobes in a scratch arena) and the emitted radiance.
#pragma once

#include "core/render/bsdf.h"
#include "core/render/shading.h"

#include <string>

namespace specula {

class Material {
public:
    virtual ~Material() = default;
    // The closure at sp (lobes allocated in arena, each with its own frame) and, if 'emission' is given, the radiance
    // emitted towards sp.wo, in the same pass. 'out' is replaced: it is cleared here, the one place that does it, so
    // neither a caller nor a material repeats the rule (a material only adds lobes, in build).
    void shade(const ShadingPoint& sp, ScratchArena& arena, Closure& out, Color3* emission = nullptr) const {
        out.clear();
        build(sp, arena, out, emission);
    }
    // shade() of n points at once (the renderer's batched camera hits, issue 37): out[k] and, if given, emission[k]
    // for *sps[k], exactly as n calls of shade() give them; all lobes in 'arena'.
    void shadeBatch(const ShadingPoint* const* sps, size_t n, ScratchArena& arena, Closure* const* out,
                    Color3* emission = nullptr) const {
        for (size_t k = 0; k < n; ++k) out[k]->clear();
        buildBatch(sps, n, arena, out, emission);
    }
    virtual bool isEmissive() const { return false; }
    // Whether shading reads the screen-space differentials (dp/dx, duv/dx, dn/dx, dwo/dx, the quad partners) or the
    // normal's partials dn/du, dn/dv they are built from. When false the renderer skips building them (issue 15: they
    // were about 5 % of a path-traced GGX scene); the closure is the same either way.
    virtual bool needsDerivatives() const { return true; }
    const std::string& name() const { return name_; }
    void setName(std::string n) { name_ = std::move(n); }

protected:
    // Adds the lobes of sp to the empty closure 'out' (and writes *emission if given): what shade() does after clearing.
    virtual void build(const ShadingPoint& sp, ScratchArena& arena, Closure& out, Color3* emission) const = 0;
    // build() of n points into n empty closures. A material that can amortise its per-shade work over the batch
    // (GraphMaterial: one interpreter pass per batch) overrides it.
    virtual void buildBatch(const ShadingPoint* const* sps, size_t n, ScratchArena& arena, Closure* const* out,
                            Color3* emission) const {
        for (size_t k = 0; k < n; ++k) build(*sps[k], arena, *out[k], emission ? &emission[k] : nullptr);
    }

private:
    std::string name_;
};

}  // namespace specula
