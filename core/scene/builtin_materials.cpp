// Interim built-in materials.
#include "core/scene/builtin_materials.h"

#include "core/render/lobes/ggx.h"
#include "core/render/lobes/lambert.h"

namespace specula {

void DiffuseMaterial::shade(ShadingPoint& sp, ScratchArena& arena, Closure& out) const {
    Color3 c = color_;
    if (textures_ && tex_.valid()) c *= textures_->sampleRgb(tex_, sp.uv, sp.duvdx, sp.duvdy);
    out.add(Color3(1.f), arena.make<LambertLobe>(c));
}

void GgxMaterial::shade(ShadingPoint& sp, ScratchArena& arena, Closure& out) const {
    out.add(Color3(1.f), arena.make<GgxLobe>(ax_, ay_, fresnel_));
}

}  // namespace specula
