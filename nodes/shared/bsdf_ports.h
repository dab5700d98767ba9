// Port groups that several BSDF nodes share, declared once: the Fresnel choice (Schlick F0, exact dielectric IOR,
// exact conductor eta + ik) and the roughness -> GGX/Beckmann α mapping. GLSL twins: spc_fresnel_* in the prelude.
#pragma once

#include "core/graph/node_params.h"
#include "core/render/lobes/fresnel.h"

namespace specula::nodes {

enum class FresnelModel : int { Schlick, Dielectric, Conductor, None };

}  // namespace specula::nodes

SPECULA_ENUM(specula::nodes::FresnelModel, "SPC_FRESNEL", "schlick", "dielectric", "conductor", "none");

namespace specula::nodes {

// Declares the ports fresnel, f0, ior, eta, k on a parameter struct P with members of those names.
template <class P>
graph::NodeParams<P>& fresnelPorts(graph::NodeParams<P>& l, Vec3 defaultF0 = Vec3(0.04f)) {
    return l.choice("fresnel", &P::fresnel, "Fresnel model at wo·h")
        .c3("f0", &P::f0, defaultF0, "Schlick F0").range(0.f, 1.f).hard(0.f, 1.f)
        .f("ior", &P::ior, 1.5f, "dielectric IOR").range(1.f, 3.f).hard(1e-3f, 1e3f)
        .c3("eta", &P::eta, Vec3(0.143f, 0.374f, 1.442f), "conductor IOR real part (gold)").range(0.1f, 3.f).hard(0.f, 1e3f)
        .c3("k", &P::k, Vec3(3.983f, 2.385f, 1.603f), "conductor IOR imaginary part (gold)").range(0.f, 10.f).hard(0.f, 1e3f);
}

// The Fresnel term the ports of fresnelPorts() select.
template <class P>
Fresnel fresnelOf(const P& p) {
    switch (p.fresnel) {
        case FresnelModel::Schlick: return Fresnel::schlick(p.f0);
        case FresnelModel::Dielectric: return Fresnel::dielectric(p.ior);
        case FresnelModel::Conductor: return Fresnel::conductor(p.eta, p.k);
        case FresnelModel::None: break;
    }
    return Fresnel::one();
}

// α = roughness² (Burley 2012); anisotropy stretches it by the aspect a = sqrt(1 − 0.9·anisotropy): αx = α/a, αy = α·a
// (Burley 2012, addendum B.2).
inline Vec2 alphaFromRoughness(float roughness, float anisotropy) {
    float alpha = roughness * roughness;
    float aspect = std::sqrt(std::max(1.f - 0.9f * anisotropy, 0.f));
    return {alpha / aspect, alpha * aspect};
}

}  // namespace specula::nodes
