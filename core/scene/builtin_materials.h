// Interim built-in materials of scene format v1 (diffuse, GGX metal, emission): a minimal set that
// the node-graph materials replace; kept small and built on the shared lobes of core/render/lobes.
#pragma once

#include "core/render/material.h"
#include "core/render/lobes/fresnel.h"
#include "core/texture/texture_store.h"

namespace specula {

class DiffuseMaterial final : public Material {
public:
    DiffuseMaterial(const Color3& color, const TextureStore* textures = nullptr, TextureHandle tex = {})
        : color_(color), textures_(textures), tex_(tex) {}
    void shade(ShadingPoint& sp, ScratchArena& arena, Closure& out) const override;

private:
    Color3 color_;
    const TextureStore* textures_;
    TextureHandle tex_;
};

class GgxMaterial final : public Material {
public:
    GgxMaterial(float alphaX, float alphaY, const Fresnel& fresnel) : ax_(alphaX), ay_(alphaY), fresnel_(fresnel) {}
    void shade(ShadingPoint& sp, ScratchArena& arena, Closure& out) const override;

private:
    float ax_, ay_;
    Fresnel fresnel_;
};

class EmissionMaterial final : public Material {
public:
    explicit EmissionMaterial(const Color3& radiance) : L_(radiance) {}
    void shade(ShadingPoint&, ScratchArena&, Closure&) const override {}
    Color3 emission(const ShadingPoint& sp) const override { return sp.frontFacing ? L_ : Color3(0.f); }
    bool isEmissive() const override { return true; }

private:
    Color3 L_;
};

}  // namespace specula
