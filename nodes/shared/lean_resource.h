// The GPU resource of a LEAN slope-moment pyramid (core/texture/lean_moments.h) as nodes/texture/lean/lean.glsl reads
// it: shared by texture.lean and the GPU substitute of bsdf.glint_pndf, which filter the same kind of pyramid.
#pragma once

#include "core/graph/node_spec.h"
#include "core/texture/lean_moments.h"

#include <memory>
#include <vector>

namespace specula::nodes {

// LeanPyramid's packed GLSL levels (glslPackedLevel), every level given, read with texelFetch (nearest, clamp).
graph::ResourceImage leanMomentImage(const LeanPyramid& pyramid);

// Pyramids shared between materials that use the same pixels, keyed by a content hash of the encoded texels (so a
// texture store destroyed and re-created at the same address can never hand out a stale pyramid). Thread-safe.
std::shared_ptr<const LeanPyramid> sharedLeanPyramid(const std::vector<float>& pixels, int width, int height,
                                                     int channels);

}  // namespace specula::nodes
