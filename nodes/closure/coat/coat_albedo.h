// Directional albedo E(μo, roughness, ior) of closure.coat's dielectric GGX coat lobe, tabulated: the energy the coat
// reflects, which closure.coat removes from the base below it (albedo scaling; coat.node.cpp, coat.glsl).
#pragma once

#include "core/graph/node_spec.h"

#include <vector>

namespace specula::coat {

// E(μo, r, η) = ∫ F_η(wo·h) D(h) G2(wo, wi) / (4 μo) dωi over the reflected hemisphere: GgxLobe with α = max(r², 1e-4)
// and Fresnel::dielectric(η) (core/render/lobes/ggx.h), Walter et al. 2007 Eq. 20 with the height-correlated G2 of
// Heitz 2014 Eq. 99.
//
// Grid: kMu × kRough × kF0 nodes, μo = i/(kMu−1), r = j/(kRough−1), and the IOR through its normal-incidence
// reflectance F0 = ((η−1)/(η+1))², F0 = k/(kF0−1) · kMaxF0 (η ∈ [1, 3]): E is close to linear in F0 (E ≈ F0·A + B),
// so a coarse F0 axis interpolates well where an η axis would not. μo = 0 is stored at μo = 1e-4 (the limit).
// Each node integrates by deterministic quadrature over the visible normals: with h drawn from D_wo (Heitz 2018),
// f·cos / pdf = F(wo·h) G2 / G1(wo), integrated over the sampler's unit square by a kQuad × kQuad midpoint rule in
// (θ, u.y) with u.x = sin²θ (smooth in θ; coat_albedo.cpp).
constexpr int kMu = 32, kRough = 32, kF0 = 16, kQuad = 32;
constexpr float kMaxF0 = 0.25f;  // η = 3
constexpr float kMinIor = 1.f, kMaxIor = 3.f;

// The table, built once on first use (thread-safe). Index ((k·kRough + j)·kMu + i).
const std::vector<float>& albedoTable();
// One node computed directly (what the table stores): E for μo, α, η by the quadrature above with n × n points.
float albedoQuadrature(float mu, float alpha, float ior, int n);
// The same for 'count' IORs at once (out[k] for iors[k], each the same bits as the one-IOR call): the visible normals
// and the masking do not depend on the IOR, so the table computes them once per (μo, r) node.
void albedoQuadrature(float mu, float alpha, const float* iors, int count, int n, float* out);
// Trilinear interpolation of the table at (μo, r, η); μo ≤ 0 gives 0 (the lobe is zero there). The GLSL twin is
// spc_coat_albedo in coat.glsl (same formula on the texelFetch'ed table).
float albedo(float mu, float roughness, float ior);

// The table as a GPU resource: kMu × (kRough·kF0) RGBA32F, texel (i, k·kRough + j) = (E, 0, 0, 0); nearest,
// clamp_to_edge (interpolated in the shader with texelFetch, exactly as albedo()).
graph::ResourceSpec albedoResource();

}  // namespace specula::coat
