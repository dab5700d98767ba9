// The LTC tables as GPU resources (graph::ResourceSpec, kind BuiltinTable) for the GLSL of the LTC lobes
// (nodes/shared/ltc.glsl): texel layouts, sampler state and the resource declarations the nodes share.
// It lives with the nodes, not in core/ltc, because it speaks the graph's resource type: core/ltc sits below
// core/graph (graph -> render -> ltc), and an ltc -> graph include would close a folder cycle (issue 36).
#pragma once

#include "core/graph/node_spec.h"

namespace specula::ltc {

// ltc_matrix: 64×64 RGBA32F, texel (x = roughness index a, y = view index t) = the four non-trivial entries of the
// isotropic inv(M) as LtcTables::ggxInv stores them ((0,0), (2,0), (0,2), (2,2)); GL_LINEAR, CLAMP_TO_EDGE, no MIPs
// (ltc-filtering.md §2 "Packing", ltc_code's texture 1), read with texture() at c·63/64 + 0.5/64.
graph::ResourceImage matrixImage(const void* prepared);
// ltc_amplitude: 64×64 RGBA32F, texel (x, y) = (mag, fres, 0, sphere) with mag/fres of cell (a = x, t = y) and the
// clip-free sphere scale of (z index x, len index y) (§3 step 5; ltc_code's texture 2). GL_LINEAR, CLAMP_TO_EDGE.
graph::ResourceImage amplitudeImage(const void* prepared);
// ltc_anisotropic: the 8⁴ t-EM table, 3 RGBA32F texels per cell, (3·n²) × (n·nφ) = 192×64 texels: cell (i, j, t, k)
// (αx, αy, θ, φ indices, LtcTables::anisoInv order) at x = 3·(j·n + i) + s, y = k·n + t, with s = 0: inv entries 0-3,
// s = 1: entries 4-7, s = 2: (entry 8, mag, fres, 0) (glm column-major inv(M), det 1). GL_NEAREST, CLAMP_TO_EDGE:
// the GLSL interpolates the 16 corners itself with texelFetch, exactly as ltc::ggxAnisotropic does.
graph::ResourceImage anisotropicImage(const void* prepared);

// The declarations (name = the GLSL parameter name, glslType sampler2D, doc for the manifest and docs/nodes.md).
graph::ResourceSpec matrixResource();
graph::ResourceSpec amplitudeResource();
graph::ResourceSpec anisotropicResource();

}  // namespace specula::ltc
