// Helpers for closure-producing nodes: build a BSDF's frame from its normal/tangent inputs exactly as
// the GLSL prelude does, and add the lobe with that frame to the node's closure.
#pragma once

#include "core/graph/node_params.h"
#include "core/graph/node_spec.h"
#include "core/render/bsdf.h"
#include "core/render/shading.h"

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace specula::graph {

// Frame of a BSDF node: n normalised, tangent Gram-Schmidt-orthogonalised (Frame::fromNormalTangent);
// GLSL: spc_frame() in the prelude.
// n / sqrt(l2) is one four-lane SSE division, and the (0, 0, 1) of a zero (or NaN) normal is selected without a branch:
// each lane is the same IEEE division as the three scalar ones (the same bits), where three divisions and a branch sat
// on the shading point's chain (issue 37). Its time gain is not measured: a harness figure once quoted here compared two
// builds that both had it, and code placement alone moves bench_graph by about 10 % (docs/performance.md).
inline Frame bsdfFrame(Vec3 n, Vec3 t) {
    const float l2 = glm::dot(n, n);
#if defined(__SSE2__)
    const __m128 keep = _mm_cmpgt_ps(_mm_set1_ps(l2), _mm_setzero_ps());
    const __m128 q = _mm_div_ps(_mm_setr_ps(n.x, n.y, n.z, 1.f), _mm_set1_ps(std::sqrt(l2)));
    const __m128 u = _mm_or_ps(_mm_and_ps(keep, q), _mm_andnot_ps(keep, _mm_setr_ps(0.f, 0.f, 1.f, 0.f)));
    alignas(16) float v[4];
    _mm_store_ps(v, u);
    n = Vec3(v[0], v[1], v[2]);
#else
    n = l2 > 0.f ? n / std::sqrt(l2) : Vec3(0, 0, 1);
#endif
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
