// bsdf.dielectric (rough glass, Walter et al. 2007) against closed forms: in the smooth limit the reflected fraction is
// the Fresnel reflectance and reflected + refracted flux is 1, the refracted direction obeys Snell's law, total internal
// reflection transmits nothing; and through the path tracer a glass sphere in a constant environment is (nearly)
// invisible, which holds only if the radiance factor (n_o / n_i)² of each crossing and the inverted IOR inside are right.
// Generic properties (χ², pdf, generalised reciprocity, flux ≤ 1) are in test_lobe_conformance.cpp.
#include "core/graph/graph_material.h"
#include "core/render/bsdf.h"
#include "core/render/lobes/dielectric.h"
#include "core/render/material.h"
#include "core/render/renderer.h"
#include "core/render/sampler.h"
#include "core/render/shading.h"
#include "core/scene/scene_loader.h"
#include "render_support.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

using namespace specula;

namespace {

using test::Rng;

Vec3 dirFromTheta(float thetaDeg) {
    const float t = glm::radians(thetaDeg);
    return {std::sin(t), 0.f, std::cos(t)};
}

// The node's closure at a shading point whose frame is the world frame, viewer outside (front) or inside.
struct Glass {
    std::shared_ptr<Material> material;
    ScratchArena arena;
    Closure closure;
    Glass(float roughness, float ior, bool front, const Vec3& wo) {
        nlohmann::json m = {{"nodes", {{"g", {{"type", "bsdf.dielectric"},
                                              {"inputs", {{"roughness", roughness}, {"ior", ior}}}}}}},
                            {"output", "@g.bsdf"}};
        material = loadGraphMaterial(m, "/materials/glass", GraphLoadContext{});
        ShadingPoint sp;
        sp.wo = wo;
        sp.frontFacing = front;
        material->shade(sp, arena, closure);
    }
};

// Monte Carlo over the closure's own sampling: reflected fraction, refracted flux (radiance times (n_wi/n_wo)²) and
// the mean refracted direction.
struct Split {
    double reflected = 0, transmittedFlux = 0;
    Vec3 meanRefracted{0.f};
};
Split split(const Closure& cl, const Vec3& wo, float etaP, int n = 200000) {
    Split r;
    Rng rng{12345};
    for (int k = 0; k < n; ++k) {
        BsdfSample s;
        BsdfQuery q;
        q.wo = wo;
        const float ul = rng.next();
        if (!cl.sample(q, ul, rng.next2(), s)) continue;
        const double w = s.f.total().y / s.pdf;
        if (s.wi.z > 0.f) {
            r.reflected += w;
        } else {
            r.transmittedFlux += w * etaP * etaP;
            r.meanRefracted += s.wi * float(w);
        }
    }
    r.reflected /= n;
    r.transmittedFlux /= n;
    if (glm::length(r.meanRefracted) > 0.f) r.meanRefracted = glm::normalize(r.meanRefracted);
    return r;
}

}  // namespace

TEST(Dielectric, SmoothLimitSplitsIntoFresnelReflectionAndRefractionAlongSnell) {
    const float ior = 1.5f;
    for (bool front : {true, false}) {
        const float eta = front ? ior : 1.f / ior;  // far side over the viewer's
        for (float theta : {0.f, 30.f, 60.f, 80.f}) {
            SCOPED_TRACE(std::string(front ? "outside" : "inside") + ", θo = " + std::to_string(theta));
            const Vec3 wo = dirFromTheta(theta);
            Glass g(0.03f, ior, front, wo);  // α = 9e-4: a nearly polished interface
            const Split s = split(g.closure, wo, eta);
            const double F = fresnelDielectric(wo.z, eta);
            std::printf("  %s θo=%2.0f°: R %.4f (Fresnel %.4f), T flux %.4f, R+T %.4f\n", front ? "outside" : "inside ",
                        theta, s.reflected, F, s.transmittedFlux, s.reflected + s.transmittedFlux);
            EXPECT_NEAR(s.reflected, F, 0.01);
            EXPECT_NEAR(s.reflected + s.transmittedFlux, 1.0, 0.01);  // nothing is lost at a smooth interface
            const float sinT = std::sin(glm::radians(theta)) / eta;
            if (sinT >= 1.f) {
                EXPECT_EQ(s.transmittedFlux, 0.0) << "total internal reflection transmits nothing";
            } else {
                // Snell: the refracted direction is at θt with sin θt = sin θo / η, opposite in x.
                const Vec3 expected(-sinT, 0.f, -std::sqrt(1.f - sinT * sinT));
                EXPECT_GT(glm::dot(s.meanRefracted, expected), std::cos(glm::radians(0.5f)));
            }
        }
    }
}

TEST(Dielectric, RoughInterfaceLosesOnlyWhatSingleScatteringMisses) {
    // Rougher microsurfaces lose the light that scatters more than once (not modelled): the flux stays below 1,
    // decreases with roughness, and is still most of the light at α = 0.25.
    double previous = 1.0;
    for (float roughness : {0.1f, 0.5f, 0.8f}) {
        const Vec3 wo = dirFromTheta(45.f);
        Glass g(roughness, 1.5f, true, wo);
        const Split s = split(g.closure, wo, 1.5f);
        const double total = s.reflected + s.transmittedFlux;
        std::printf("  roughness %.1f: R %.4f, T flux %.4f, R+T %.4f\n", roughness, s.reflected, s.transmittedFlux, total);
        EXPECT_LE(total, 1.0 + 0.005);
        EXPECT_LE(total, previous + 0.005);
        if (roughness <= 0.5f) EXPECT_GT(total, 0.93);
        previous = total;
    }
}

TEST(Dielectric, GlassSphereVanishesInAConstantEnvironment) {
    // Every path through the sphere ends in the same environment, so an energy-conserving glass shows the
    // environment's radiance: entering multiplies radiance by η², leaving by 1/η²; a wrong factor or a wrong IOR inside
    // shows as a bright or dark disc. What is lost: single-scattering energy (small at this roughness) and paths cut at
    // max_depth.
    const std::vector<float> beauty = test::renderAov(R"({
        "render": {"width": 40, "height": 40, "spp": 64, "integrator": "path", "max_depth": 24},
        "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "fov": 25},
        "materials": {"glass": {"nodes": {"g": {"type": "bsdf.dielectric", "inputs": {"roughness": 0.1, "ior": 1.5}}},
                                "output": "@g.bsdf"}},
        "shapes": [{"type": "sphere", "radius": 1, "material": "glass"}],
        "lights": [{"type": "environment", "color": [0.5, 0.5, 0.5]}]})",
                                                      test::sourcePath("examples"), "beauty");
    // Pixels well inside the disc (its radius is about 18 pixels).
    int n = 0;
    const double mean = test::greenMeanInRing(beauty, 40, -1.0, 14.0, &n) / 0.5;
    std::printf("  glass sphere in a furnace: %.4f of the environment over %d pixels\n", mean, n);
    ASSERT_GT(n, 500);
    EXPECT_GT(mean, 0.95);
    EXPECT_LT(mean, 1.01);
}

TEST(Dielectric, OpaqueClosuresIgnoreLightBelowTheGeometricSurface) {
    // BsdfQuery::ng: a reflecting lobe answers nothing for wi below the geometric surface even where its shading
    // normal would; a transmitting lobe nothing above it.
    Glass g(0.3f, 1.5f, true, dirFromTheta(30.f));
    BsdfQuery q;
    q.wo = dirFromTheta(30.f);
    q.wi = glm::normalize(Vec3(-0.3f, 0.f, -0.9f));  // near the refracted direction
    const Color3 free = g.closure.evalPdf(q).f.total();
    q.ng = Vec3(0, 0, 1);
    const Color3 sided = g.closure.evalPdf(q).f.total();
    EXPECT_GT(free.y, 0.f);
    EXPECT_EQ(free.y, sided.y);  // below: the refraction, untouched
    q.ng = glm::normalize(Vec3(0.f, 0.f, -1.f));  // the same wi, now "above" a flipped geometric normal
    EXPECT_EQ(g.closure.evalPdf(q).f.total().y, 0.f);
}
