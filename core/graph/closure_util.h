// Helpers for closure-producing nodes: build a BSDF's frame from its normal/tangent inputs exactly as
// the GLSL prelude does, and place lobes whose frame differs from the material's shading frame.
#pragma once

#include "core/graph/node_spec.h"
#include "core/render/bsdf.h"
#include "core/render/shading.h"

namespace specula::graph {

// Frame of a BSDF node: n normalised, tangent Gram-Schmidt-orthogonalised (Frame::fromNormalTangent);
// GLSL: spc_frame() in the prelude.
inline Frame bsdfFrame(Vec3 n, Vec3 t) {
    float l2 = glm::dot(n, n);
    n = l2 > 0.f ? n / std::sqrt(l2) : Vec3(0, 0, 1);
    return Frame::fromNormalTangent(n, t);
}

// A lobe expressed in its own frame F, seen from the material's shading frame S: directions are
// rotated from S-local to F-local before the inner lobe is queried (pdf is rotation invariant).
class FramedLobe final : public BsdfLobe {
public:
    FramedLobe(const BsdfLobe* inner, const Frame& rel) : inner_(inner), rel_(rel) {}
    LobeKind kind() const override { return inner_->kind(); }
    Color3 eval(const Vec3& wo, const Vec3& wi) const override { return inner_->eval(rel_.toLocal(wo), rel_.toLocal(wi)); }
    float pdf(const Vec3& wo, const Vec3& wi) const override { return inner_->pdf(rel_.toLocal(wo), rel_.toLocal(wi)); }
    bool sample(const Vec3& wo, const Vec2& u, Vec3& wi) const override {
        Vec3 w;
        if (!inner_->sample(rel_.toLocal(wo), u, w)) return false;
        wi = rel_.toWorld(w);
        return true;
    }
    Color3 albedo(const Vec3& wo) const override { return inner_->albedo(rel_.toLocal(wo)); }

private:
    const BsdfLobe* inner_;
    Frame rel_;  // F's axes in S-local coordinates
};

// Adds weight·lobe (built in frame f) to the closure of output port k. The first BSDF of a material
// fixes the shading frame (written back to sp.frame by the material); later lobes in another frame
// are wrapped in a FramedLobe.
inline void emitLobe(EvalContext& c, const Instr& i, int k, const Frame& f, const Color3& weight,
                     const BsdfLobe* lobe) {
    int slot = outClosure(c, i, k);
    Closure& cl = *c.closures[slot];
    cl.clear();
    c.emission[slot] = Color3(0.f);
    if (!c.frameSet) {
        c.frame = f;
        c.frameSet = true;
        // Published here rather than copied from c.frame after the program: reading back the frame just
        // written field by field stalled store-to-load forwarding (about 5 ns per shading point).
        if (c.shadingFrame) *c.shadingFrame = f;
    } else if (!(c.frame.n == f.n && c.frame.t == f.t)) {
        Frame rel(c.frame.toLocal(f.t), c.frame.toLocal(f.b), c.frame.toLocal(f.n));
        lobe = c.arena->make<FramedLobe>(lobe, rel);
    }
    cl.add(weight, lobe);
}

}  // namespace specula::graph
