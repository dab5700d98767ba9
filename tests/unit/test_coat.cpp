// closure.coat (nodes/closure/coat): the tabulated coat albedo E(μo, roughness, ior) against independent Monte Carlo,
// the white furnace (coat over a white Lambertian keeps albedo 1), weight 0 = the base unchanged, the weight/tint
// formula, and quad-light polygon queries passing through (the coat lobe's LTC plus the scaled base's).
#include "core/graph/graph_material.h"
#include "core/render/lobes/ggx.h"
#include "core/render/material.h"
#include "core/render/renderer.h"
#include "core/render/sampling.h"
#include "core/render/shading.h"
#include "core/scene/scene_loader.h"
#include "nodes/closure/coat/coat_albedo.h"
#include "tests/unit/render_support.h"
#include "tests/unit/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <random>

using namespace specula;
using nlohmann::json;

namespace {

constexpr double kPiD = 3.14159265358979323846;

// wo at cos θo = mu in the xz plane (the shading frame is the world frame: normal +z, tangent +x).
Vec3 viewAt(float mu) { return {std::sqrt(std::max(0.f, 1.f - mu * mu)), 0.f, mu}; }

ShadingPoint shadingPoint(const Vec3& wo) {
    ShadingPoint sp;
    sp.p = Vec3(0.f);
    sp.n = sp.ng = Vec3(0, 0, 1);
    sp.tangent = Vec4(1, 0, 0, 1);
    sp.uv = Vec2(0.5f);
    sp.frame = Frame();
    sp.wo = wo;
    return sp;
}

std::shared_ptr<Material> material(const json& nodes, const std::string& output) {
    return loadGraphMaterial(json{{"nodes", nodes}, {"output", output}}, "/m", GraphLoadContext{});
}

// A white Lambertian under closure.coat with the given inputs.
std::shared_ptr<Material> coatOverWhite(float weight, float roughness, float ior) {
    return material({{"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", {1, 1, 1}}}}}},
                     {"c", {{"type", "closure.coat"},
                            {"inputs", {{"base", "@d.bsdf"}, {"weight", weight}, {"roughness", roughness}, {"ior", ior}}}}}},
                    "@c.bsdf");
}

// ∫ f·cos dωi of a closure by one-sample MIS (balance heuristic) of two samplers, half the samples each: cosine-weighted
// hemisphere directions (pdf μi/π, computed here) and an independent GGX visible-normal sampler of roughness alpha
// (pdf D_wo(h)/(4 wo·h), computed here from ggx::visibleNdf). Only the closure's evalPdf().f is used, so the estimate is
// independent of the closure's own sampling and of the coat table's quadrature. Returns the mean; 'stderr_' its error.
double hemisphereIntegral(const Closure& cl, const Vec3& wo, float alpha, int n, uint32_t seed, double* stderr_) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    alpha = std::max(alpha, ggx::kMinAlpha);
    double sum = 0.0, sum2 = 0.0;
    for (int s = 0; s < n; ++s) {
        Vec2 u(u01(rng), u01(rng));
        Vec3 wi;
        if (s & 1) {
            wi = ggx::reflect(wo, ggx::sampleVisibleNormal(wo, u, alpha, alpha));
        } else {
            wi = sampleCosineHemisphere(u);
        }
        double v = 0.0;
        if (wi.z > 0.f) {
            const Vec3 h = glm::normalize(wo + wi);
            const double woh = glm::dot(wo, h);
            const double pGgx = woh > 0.0 ? ggx::visibleNdf(wo, h, alpha, alpha) / (4.0 * woh) : 0.0;
            const double pCos = wi.z / kPiD;
            const double f = luminance(test::query(cl, wo, wi).f.total());
            v = f / (0.5 * pCos + 0.5 * pGgx);
        }
        sum += v;
        sum2 += v * v;
    }
    const double mean = sum / n;
    if (stderr_) *stderr_ = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
    return mean;
}

// E_coat table vs Monte Carlo of the GgxLobe itself (f·cos from GgxLobe::evalPdf, not the table's F·G2/G1 quadrature),
// at grid and off-grid points: within 0.005 absolute (0.5 % of the incident energy).
TEST(CoatAlbedo, TableMatchesIndependentMonteCarlo) {
    double worstAbs = 0.0, worstRel = 0.0;
    int cases = 0;
    for (float ior : {1.3f, 1.5f, 2.0f, 2.6f})
        for (float r : {0.05f, 0.17f, 0.3f, 0.52f, 0.7f, 0.93f})
            for (float mu : {0.1f, 0.137f, 0.25f, 0.5f, 0.61f, 0.75f, 1.0f}) {
                GgxLobe lobe(r * r, r * r, Fresnel::dielectric(ior));
                Closure cl;
                cl.add(Color3(1.f), &lobe, Frame());
                double err = 0.0;
                const Vec3 wo = viewAt(mu);
                const double mc = hemisphereIntegral(cl, wo, r * r, 200000, 17u + uint32_t(cases), &err);
                const double tab = coat::albedo(mu, r, ior);
                const double d = std::abs(tab - mc);
                worstAbs = std::max(worstAbs, d);
                worstRel = std::max(worstRel, d / mc);
                EXPECT_LE(d, 0.005 + 3.0 * err) << "ior " << ior << " r " << r << " mu " << mu << ": table " << tab
                                                << " MC " << mc << " +- " << err;
                EXPECT_LT(err, 0.0015) << "MC too noisy to judge";
                ++cases;
            }
    std::printf("COAT table vs MC: %d cases, worst |E_tab - E_mc| = %.5f, worst relative %.4f\n", cases, worstAbs, worstRel);
}

// The table's own nodes against a much finer quadrature (128²): the 32² quadrature per node is converged.
TEST(CoatAlbedo, TableNodesAreConvergedQuadrature) {
    double worst = 0.0;
    for (int k : {0, 5, 15})
        for (int j : {0, 1, 8, 31})
            for (int i : {1, 3, 16, 31}) {
                const float r = float(j) / (coat::kRough - 1), f0 = float(k) / (coat::kF0 - 1) * coat::kMaxF0;
                const float s = std::sqrt(f0), ior = (1.f + s) / (1.f - s);
                const double stored = coat::albedoTable()[(size_t(k) * coat::kRough + j) * coat::kMu + i];
                const double fine = coat::albedoQuadrature(float(i) / (coat::kMu - 1), r * r, ior, 128);
                worst = std::max(worst, std::abs(stored - fine));
            }
    std::printf("COAT table nodes vs 128^2 quadrature: worst %.2e\n", worst);
    EXPECT_LE(worst, 1e-3);
}

// The table computes each (μo, r) node once for all its IORs: every entry is the same bits as the one-IOR quadrature.
TEST(CoatAlbedo, TableEntriesEqualTheOneIorQuadrature) {
    int compared = 0;
    for (int k : {0, 1, 7, 15})
        for (int j : {0, 2, 9, 31})
            for (int i : {0, 1, 12, 31}) {
                const float r = float(j) / (coat::kRough - 1), f0 = float(k) / (coat::kF0 - 1) * coat::kMaxF0;
                const float s = std::sqrt(std::min(f0, 0.999f)), ior = (1.f + s) / (1.f - s);
                const float stored = coat::albedoTable()[(size_t(k) * coat::kRough + j) * coat::kMu + i];
                const float alone = coat::albedoQuadrature(float(i) / (coat::kMu - 1), r * r, ior, coat::kQuad);
                EXPECT_EQ(stored, alone) << "k " << k << " j " << j << " i " << i;
                ++compared;
            }
    EXPECT_EQ(compared, 64);
}

// White furnace: a full coat over a white Lambertian (albedo 1) reflects all the energy: weight·E + (1 − weight·E) = 1,
// measured by Monte Carlo over the layered closure's evalPdf for μo ∈ {0.1..1}, roughness {0.05, 0.3, 0.7}, ior {1.3,
// 1.5, 2.0}, and half a coat.
TEST(Coat, WhiteFurnaceKeepsAlbedoOne) {
    double worst = 0.0;
    ScratchArena arena;
    for (float weight : {1.f, 0.5f})
        for (float ior : {1.3f, 1.5f, 2.0f})
            for (float r : {0.05f, 0.3f, 0.7f}) {
                auto m = coatOverWhite(weight, r, ior);
                for (int k = 1; k <= 10; ++k) {
                    const float mu = 0.1f * float(k);
                    const Vec3 wo = viewAt(mu);
                    Closure cl;
                    m->shade(shadingPoint(wo), arena, cl);
                    ASSERT_EQ(cl.size(), 2) << "white Lambertian + coat lobe";
                    double err = 0.0;
                    const double a = hemisphereIntegral(cl, wo, r * r, 40000, 1000u + uint32_t(k), &err);
                    worst = std::max(worst, std::abs(a - 1.0));
                    EXPECT_NEAR(a, 1.0, 0.01) << "weight " << weight << " ior " << ior << " r " << r << " mu " << mu
                                              << " (MC error " << err << ")";
                    arena.reset();
                }
            }
    std::printf("COAT white furnace: worst |albedo - 1| = %.5f over 180 cases\n", worst);
}

// Without the albedo scaling the same closure would gain energy: the furnace test can fail.
TEST(Coat, FurnaceDetectsMissingScaling) {
    ScratchArena arena;
    auto m = coatOverWhite(1.f, 0.3f, 1.5f);
    const Vec3 wo = viewAt(0.2f);
    Closure cl;
    m->shade(shadingPoint(wo), arena, cl);
    ASSERT_EQ(cl.size(), 2);
    Closure unscaled;  // the white base at full weight plus the same coat lobe
    unscaled.add(Color3(1.f), cl.lobe(0), cl.frame(0));
    unscaled.add(cl.weight(1), cl.lobe(1), cl.frame(1));
    const double a = hemisphereIntegral(unscaled, wo, 0.09f, 40000, 5u, nullptr);
    std::printf("COAT unscaled furnace at mu 0.2: %.4f (E = %.4f)\n", a, coat::albedo(0.2f, 0.3f, 1.5f));
    EXPECT_GT(a, 1.05);
}

// weight 0: the base closure exactly (same lobes, weights, frames, values, emission).
TEST(Coat, WeightZeroIsTheBaseExactly) {
    const json base = {{"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", {0.7, 0.4, 0.2}}}}}},
                       {"g", {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", 0.4}, {"fresnel", "conductor"}}}}},
                       {"e", {{"type", "bsdf.emission"}, {"inputs", {{"color", {0.3, 0.2, 0.1}}}}}},
                       {"m", {{"type", "closure.mix"}, {"inputs", {{"a", "@d.bsdf"}, {"b", "@g.bsdf"}, {"t", 0.4}}}}},
                       {"b", {{"type", "closure.add"}, {"inputs", {{"a", "@m.bsdf"}, {"b", "@e.bsdf"}}}}}};
    json coated = base;
    coated["c"] = {{"type", "closure.coat"},
                   {"inputs", {{"base", "@b.bsdf"}, {"weight", 0.0}, {"roughness", 0.2}, {"tint", {0.5, 0.6, 0.7}}}}};
    auto plain = material(base, "@b.bsdf"), coat = material(coated, "@c.bsdf");
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    ScratchArena a1, a2;
    for (float mu : {0.15f, 0.6f, 0.95f}) {
        const Vec3 wo = viewAt(mu);
        Closure c1, c2;
        Color3 e1(0.f), e2(0.f);
        plain->shade(shadingPoint(wo), a1, c1, &e1);
        coat->shade(shadingPoint(wo), a2, c2, &e2);
        ASSERT_EQ(c1.size(), c2.size());
        EXPECT_EQ(e1, e2);
        for (int i = 0; i < c1.size(); ++i) {
            EXPECT_EQ(c1.weight(i), c2.weight(i));
            EXPECT_STREQ(c1.lobe(i)->modelName(), c2.lobe(i)->modelName());
        }
        for (int s = 0; s < 64; ++s) {
            const Vec3 wi = sampleCosineHemisphere(Vec2(u01(rng), u01(rng)));
            const BsdfValue v1 = test::query(c1, wo, wi), v2 = test::query(c2, wo, wi);
            EXPECT_EQ(v1.f.total(), v2.f.total());
            EXPECT_EQ(v1.pdf, v2.pdf);
        }
        a1.reset();
        a2.reset();
    }
}

// The formula: closure = weight·coat + (1 − weight + weight·tint·(1 − E(μo)))·base, checked against a hand-built
// GgxLobe and the base alone.
TEST(Coat, WeightAndTintScaleTheBase) {
    const float w = 0.6f, r = 0.25f, ior = 1.7f;
    const Color3 tint(0.9f, 0.5f, 0.2f);
    const json base = {{"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", {0.8, 0.8, 0.8}}}}}}};
    json coated = base;
    coated["c"] = {{"type", "closure.coat"},
                   {"inputs", {{"base", "@d.bsdf"}, {"weight", w}, {"roughness", r}, {"ior", ior}, {"tint", {tint.x, tint.y, tint.z}}}}};
    auto plain = material(base, "@d.bsdf"), coat = material(coated, "@c.bsdf");
    GgxLobe ref(r * r, r * r, Fresnel::dielectric(ior));
    ScratchArena arena;
    for (float mu : {0.2f, 0.8f}) {
        const Vec3 wo = viewAt(mu);
        Closure cb, cc;
        plain->shade(shadingPoint(wo), arena, cb);
        coat->shade(shadingPoint(wo), arena, cc);
        const Color3 scale = Color3(1.f - w) + w * tint * (1.f - coat::albedo(mu, r, ior));
        for (const Vec3& wi : {Vec3(-0.3f, 0.1f, 0.95f), viewAt(0.7f) * Vec3(-1, 1, 1), Vec3(0.f, 0.6f, 0.8f)}) {
            const Color3 got = test::query(cc, wo, wi).f.total();
            const Color3 want = test::query(cb, wo, wi).f.total() * scale + w * ref.eval(wo, wi);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1e-5f * std::max(1.f, want[c]));
        }
        arena.reset();
    }
}

// Quad lights: Closure::integratePolygon answers for both lobes (the coat's GgxLobe LTC and the Lambertian's), and the
// coat's share is the weighted GgxLobe integral.
TEST(Coat, PolygonQueriesPassThrough) {
    auto m = coatOverWhite(0.8f, 0.3f, 1.5f);
    auto base = material({{"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", {1, 1, 1}}}}}}}, "@d.bsdf");
    ScratchArena arena;
    const Vec3 wo = viewAt(0.7f);
    Closure cl, cb;
    m->shade(shadingPoint(wo), arena, cl);
    base->shade(shadingPoint(wo), arena, cb);
    const Vec3 quad[4] = {{-1.5f, -0.5f, 2.f}, {-0.5f, -0.5f, 2.f}, {-0.5f, 0.5f, 2.f}, {-1.5f, 0.5f, 2.f}};
    BsdfQuery q;
    q.wo = wo;
    BsdfEval all, baseOnly;
    const LobeMask mask = cl.integratePolygon(q, quad, 4, all);
    EXPECT_EQ(mask, cl.allLobes());
    cb.integratePolygon(q, quad, 4, baseOnly);
    GgxLobe ref(0.09f, 0.09f, Fresnel::dielectric(1.5f));
    Color3 coatPart;
    LobeQuery lq;
    lq.wo = wo;
    ASSERT_TRUE(ref.integratePolygon(lq, quad, 4, coatPart));
    const float scale = 1.f - 0.8f * coat::albedo(0.7f, 0.3f, 1.5f);
    EXPECT_NEAR(all.total().x, baseOnly.total().x * scale + 0.8f * coatPart.x, 1e-5f);
    EXPECT_GT(coatPart.x, 0.f);
    std::printf("COAT polygon: base %.5f x %.4f + coat %.5f\n", baseOnly.total().x, scale, 0.8f * coatPart.x);
}

// The rendered white furnace (as tests/unit/test_render_physics.cpp): a coated white sphere in a constant environment
// returns the environment, at the centre (μo ≈ 1) and in the outer ring (grazing views, μo down to ~0.2).
TEST(Coat, RenderedWhiteFurnaceReturnsTheEnvironment) {
    Scene s = loadSceneFromString(R"({
        "render": {"width": 48, "height": 48, "spp": 64, "integrator": "path"},
        "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "fov": 30},
        "materials": {"coat": {"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": 1.0}},
                                         "c": {"type": "closure.coat", "inputs": {"base": "@d.bsdf", "roughness": 0.3, "ior": 1.5}}},
                               "output": "@c.bsdf"}},
        "shapes": [{"type": "sphere", "radius": 1, "material": "coat"}],
        "lights": [{"type": "environment", "color": [0.7, 0.7, 0.7]}]})",
                                  test::sourcePath("examples"));
    RenderOutput r = renderScene(s);
    const AovBuffer* beauty = r.images.find("beauty");
    ASSERT_TRUE(beauty);
    // The sphere's silhouette is at ~22 px from the centre; the environment is 0.7.
    int ni = 0, no = 0;
    const double inner = test::greenMeanInRing(beauty->pixels, 48, -1.0, 12.0, &ni) / 0.7;
    const double outer = test::greenMeanInRing(beauty->pixels, 48, 16.0, 20.0, &no) / 0.7;
    ASSERT_GT(ni, 300);
    ASSERT_GT(no, 300);
    std::printf("COAT rendered furnace: centre %.4f, outer ring %.4f (environment = 1)\n", inner, outer);
    EXPECT_NEAR(inner, 1.0, 0.01);
    EXPECT_NEAR(outer, 1.0, 0.01);
    EXPECT_EQ(r.stats.invalidSamples, 0u);
}

}  // namespace
