// Helpers for closure-producing nodes: build a BSDF's frame from its normal/tangent inputs exactly as
// the GLSL prelude does, and add the lobe with that frame to the node's closure.
#pragma once

#include "core/graph/node_params.h"
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

// Adds weight·lobe, built in frame f (world space), to the closure of output k. Every lobe keeps its own
// frame (Closure::add); nothing is written back to the shading point.
inline void emitLobe(EvalContext& c, const Instr& i, OutPort<ClosureRef> k, const Frame& f, const Color3& weight,
                     const BsdfLobe* lobe) {
    int slot = slotOf(c, i, k);
    Closure& cl = *c.closures[slot];
    cl.clear();
    c.emission[slot] = Color3(0.f);
    cl.add(weight, lobe, f);
}

}  // namespace specula::graph
