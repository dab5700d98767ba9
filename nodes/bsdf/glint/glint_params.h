// The glint material's inputs (spec glint-brdf.md §1): RMS slopes and their correlation (C21 Eq. 18), microfacet
// density, cell occupancy, LOD jitter, the GGAA switch and kernel (C21 Eqs. 19-21), and the sampling options.
#pragma once

#include <cstdint>

namespace specula::glint {

enum class DerivMode : uint8_t { ProjectedHalf = 0, HalfSlope = 1 };

// Material inputs (spec §1). Values are clamped by GlintShape::make / the node as the authors' code does.
struct GlintParams {
    float sigmaX = 0.16f, sigmaY = 0.16f;  // RMS slopes of the converged lobe, clamped to [0.01, 1]
    float rho = 0.f;                       // slope correlation (C21 §5.2), clamped to +-0.99
    float logDensity = 15.f;               // lambda = ln(microfacets per unit UV area)
    float relArea = 1.f;                   // A: probability that a cell holds microfacets
    float jitter = 2.f;                    // zeta: std of the per-cell dictionary-LOD jitter
    float maxAniso = 8.f;                  // a_max
    bool ggaa = true;                      // C21 §4.2
    float kernelScale = 0.5f;              // s_K (C21 Eq. 19)
    DerivMode mode = DerivMode::ProjectedHalf;  // C21 Eq. 21 (default) or Eq. 20
    // GlintLobe::sample: the glint distribution of the shading point mixed with the Beckmann lobe (true), or the
    // limiting Beckmann lobe alone (false: the sampler before issue 11, kept for the variance comparisons).
    bool sampleGlints = true;
    // Quad lights (polygon queries): integrate each cell's distribution over the light's half-vector region
    // (glint_area.h; noise-free, ~10-30x the cost of a light sample) or let the integrator sample the light.
    bool integrateQuadLights = false;
    // Explicit flakes (glint_flakes.h): their size in the units of the cell grid (uv x uv_scale; 0 = off, C20's
    // counting at every distance) and the RMS slope of each flake's own lobe.
    float flakeSize = 0.f;
    float flakeRoughness = 0.04f;
};

}  // namespace specula::glint
