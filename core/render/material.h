// Material interface between the renderer and whatever builds BSDFs (interim built-in materials now,
// compiled node graphs later): given a shading point, fill a Closure allocated in a scratch arena.
#pragma once

#include "core/render/bsdf.h"
#include "core/render/shading.h"

#include <string>

namespace specula {

class Material {
public:
    virtual ~Material() = default;
    // Builds the closure at sp. May perturb sp.frame (normal mapping); lobes are allocated in arena.
    virtual void shade(ShadingPoint& sp, ScratchArena& arena, Closure& out) const = 0;
    // Emitted radiance towards sp.wo (emissive surfaces). Default: none.
    virtual Color3 emission(const ShadingPoint& sp) const { return Color3(0.f); }
    virtual bool isEmissive() const { return false; }
    const std::string& name() const { return name_; }
    void setName(std::string n) { name_ = std::move(n); }

private:
    std::string name_;
};

}  // namespace specula
