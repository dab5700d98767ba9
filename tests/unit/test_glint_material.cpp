// bsdf.glint's material ports (issue 11 item 5): the fresnelPorts() group (schlick | dielectric | conductor | none,
// evaluated at wo·h) and base_color. The defaults keep the look of scenes made before them (Schlick F0 = 1: F = 1),
// and at a glinty footprint every model multiplies the same sparkles by base_color · F(wo·h).
#include "core/graph/graph_material.h"
#include "core/render/lobes/fresnel.h"
#include "core/render/material.h"
#include "core/render/sampling.h"
#include "core/render/shading.h"
#include "tests/unit/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <random>

using namespace specula;
using nlohmann::json;

namespace {

std::shared_ptr<Material> glint(const json& inputs) {
    json in = inputs;
    in["ggaa"] = "off";  // the footprint alone selects the cells: the same sparkles for every Fresnel model
    return loadGraphMaterial(json{{"nodes", {{"g", {{"type", "bsdf.glint"}, {"inputs", in}}}}}, {"output", "@g.bsdf"}},
                             "/m", GraphLoadContext{});
}

// A shading point with a small pixel footprint (sparkles, not the converged lobe); frame = world (normal +z).
ShadingPoint glintyPoint(const Vec3& wo) {
    ShadingPoint sp;
    sp.n = sp.ng = Vec3(0, 0, 1);
    sp.tangent = Vec4(1, 0, 0, 1);
    sp.frame = Frame();
    sp.uv = Vec2(0.37f, 0.61f);
    sp.duvdx = Vec2(0.002f, 0.f);
    sp.duvdy = Vec2(0.f, 0.002f);
    sp.hasDifferentials = true;
    sp.wo = wo;
    return sp;
}

struct Probe {
    Vec3 wi;
    Color3 f;
};

// f·cos of material m at wo for the given directions.
std::vector<Color3> evalAt(const Material& m, const Vec3& wo, const std::vector<Vec3>& wis, bool footprint = true) {
    ScratchArena arena;
    Closure cl;
    ShadingPoint sp = glintyPoint(wo);
    if (!footprint) sp.duvdx = sp.duvdy = Vec2(0.f), sp.hasDifferentials = false;  // the converged lobe
    m.shade(sp, arena, cl);
    std::vector<Color3> r;
    for (const Vec3& wi : wis) r.push_back(test::query(cl, wo, wi).f.total());
    return r;
}

TEST(GlintMaterial, FresnelModelsAndBaseColorScaleTheSameSparkles) {
    const Vec3 wo = glm::normalize(Vec3(0.4f, 0.1f, 0.9f));
    // Directions around the mirror direction, where the sparkles are.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<Vec3> wis;
    for (int k = 0; k < 4000; ++k) {
        Vec3 d = glm::normalize(Vec3(-wo.x, -wo.y, wo.z) + 0.5f * Vec3(u01(rng) - 0.5f, u01(rng) - 0.5f, 0.f));
        wis.push_back(d);
    }
    const std::vector<Color3> plain = evalAt(*glint(json::object()), wo, wis);
    const std::vector<Color3> f0one = evalAt(*glint({{"fresnel", "schlick"}, {"f0", 1.0}}), wo, wis);
    const std::vector<Color3> none = evalAt(*glint({{"fresnel", "none"}}), wo, wis);
    const Color3 tint(0.8f, 0.6f, 0.4f), eta(0.2f, 0.9f, 1.1f), kk(3.9f, 2.4f, 1.6f);
    const std::vector<Color3> conductor = evalAt(
        *glint({{"fresnel", "conductor"}, {"eta", {eta.x, eta.y, eta.z}}, {"k", {kk.x, kk.y, kk.z}}, {"base_color", {tint.x, tint.y, tint.z}}}),
        wo, wis);
    const std::vector<Color3> dielectric = evalAt(*glint({{"fresnel", "dielectric"}, {"ior", 1.7}}), wo, wis);
    const Color3 f0(0.95f, 0.64f, 0.54f);  // an old scene's Schlick tint (examples/glint/tubes.json)
    const std::vector<Color3> schlick = evalAt(*glint({{"f0", {f0.x, f0.y, f0.z}}}), wo, wis);
    int lit = 0;
    double worst = 0.0;
    for (size_t k = 0; k < wis.size(); ++k) {
        // Defaults: F = 1 exactly, as before the Fresnel ports.
        EXPECT_EQ(plain[k], f0one[k]);
        EXPECT_EQ(plain[k], none[k]);
        if (plain[k].x <= 0.f) continue;
        ++lit;
        const float c = glm::dot(wo, glm::normalize(wo + wis[k]));  // wo·h
        const Color3 wantC = plain[k] * tint *
                             Color3(fresnelConductor(c, eta.x, kk.x), fresnelConductor(c, eta.y, kk.y), fresnelConductor(c, eta.z, kk.z));
        const Color3 wantD = plain[k] * fresnelDielectric(c, 1.7f);
        const Color3 wantS = plain[k] * fresnelSchlick(c, f0);
        for (int ch = 0; ch < 3; ++ch) {
            for (auto [got, want] : {std::pair{conductor[k][ch], wantC[ch]}, std::pair{dielectric[k][ch], wantD[ch]},
                                     std::pair{schlick[k][ch], wantS[ch]}}) {
                const double rel = std::abs(got - want) / std::max(want, 1e-30f);
                worst = std::max(worst, rel);
                EXPECT_LE(rel, 1e-5) << "direction " << k << " channel " << ch << ": " << got << " vs " << want;
            }
        }
    }
    std::printf("GLINT fresnel: %d of %zu directions lit at footprint 0.002; worst rel. error vs plain x base_color x F(wo.h) %.2e\n",
                lit, wis.size(), worst);
    EXPECT_GT(lit, 20);
    // ... and it is sparkles, not a smooth lobe: a few directions far brighter than the typical one.
    auto peakToMedian = [](const std::vector<Color3>& v) {
        std::vector<float> lum;
        for (const Color3& c : v) lum.push_back(luminance(c));
        std::sort(lum.begin(), lum.end());
        return lum.back() / std::max(lum[lum.size() / 2], 1e-30f);
    };
    const double sparkles = peakToMedian(plain), converged = peakToMedian(evalAt(*glint(json::object()), wo, wis, false));
    std::printf("GLINT max / median f over the %zu directions: footprint 0.002 %.3g, converged %.3g\n", wis.size(),
                sparkles, converged);
    EXPECT_GT(sparkles, 2.0 * converged);
}

// The raster integrator runs what spc_bsdf_glint computes (NodeSpec::gpuSubstituteCpu): the GLSL has no polygon answer,
// so quad_lights "integrated" gives one on the CPU model and none on its GPU twin; directions answer the same.
TEST(GlintMaterial, GpuTwinLeavesQuadLightsToTheHostAsTheGlslDoes) {
    const json mat{{"nodes", {{"g", {{"type", "bsdf.glint"}, {"inputs", {{"quad_lights", "integrated"}, {"ggaa", "off"}}}}}}},
                   {"output", "@g.bsdf"}};
    GraphLoadContext twin;
    twin.gpuSubstitutes = true;
    const std::shared_ptr<Material> cpuModel = loadGraphMaterial(mat, "/m", GraphLoadContext{});
    const std::shared_ptr<Material> gpuTwin = loadGraphMaterial(mat, "/m", twin);
    const Vec3 wo = glm::normalize(Vec3(0.3f, -0.2f, 0.9f));
    const Vec3 quad[4] = {{-0.5f, -0.5f, 2.f}, {0.5f, -0.5f, 2.f}, {0.5f, 0.5f, 2.f}, {-0.5f, 0.5f, 2.f}};
    LobeMask masks[2];
    std::vector<Color3> dirs[2];
    std::vector<Vec3> wis;
    for (int k = 0; k < 64; ++k) wis.push_back(glm::normalize(Vec3(-wo.x + 0.02f * (k % 8), -wo.y + 0.02f * (k / 8), wo.z)));
    for (int m = 0; m < 2; ++m) {
        ScratchArena arena;
        Closure cl;
        (m == 0 ? cpuModel : gpuTwin)->shade(glintyPoint(wo), arena, cl);
        BsdfQuery q;
        q.wo = wo;
        BsdfEval e;
        masks[m] = cl.integratePolygon(q, quad, 4, e);
        dirs[m] = evalAt(m == 0 ? *cpuModel : *gpuTwin, wo, wis);
    }
    EXPECT_NE(masks[0], 0u) << "the CPU model integrates the glints over the quad light";
    EXPECT_EQ(masks[1], 0u) << "the GPU twin has no polygon answer, as spc_bsdf_glint";
    int lit = 0;
    for (size_t k = 0; k < wis.size(); ++k) {
        lit += maxComponent(dirs[0][k]) > 0.f;
        for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(dirs[0][k][ch], dirs[1][k][ch]) << "direction " << k;
    }
    EXPECT_GT(lit, 0);
}

// GGAA derivative sources: "quad" (default) differences h against the 2x2-quad partners in their own frames, as
// dFdxFine does on a GPU; "analytic" ignores the partners and equals the chain rule of a point without them.
TEST(GlintMaterial, AnalyticDerivativesIgnoreTheQuadPartners) {
    auto material = [](const char* source) {
        return loadGraphMaterial(json{{"nodes", {{"g", {{"type", "bsdf.glint"},
                                                         {"inputs", {{"derivatives", source}, {"log_density", 12}}}}}}},
                                      {"output", "@g.bsdf"}},
                                 "/m", GraphLoadContext{});
    };
    const Vec3 wo = glm::normalize(Vec3(0.4f, 0.1f, 0.9f));
    std::vector<Vec3> wis;
    for (int k = 0; k < 400; ++k)
        wis.push_back(glm::normalize(Vec3(-wo.x + 0.01f * (k % 20 - 10), -wo.y + 0.01f * (k / 20 - 10), wo.z)));
    auto eval = [&](const Material& m, bool partners) {
        ShadingPoint sp = glintyPoint(wo);
        sp.dndx = Vec3(0.01f, 0.f, 0.f);
        sp.dndy = Vec3(0.f, 0.01f, 0.f);
        if (partners) {  // partners whose frames are tilted far more than dndx says: a normal-mapped neighbourhood
            for (int k = 0; k < 2; ++k) {
                ShadingPoint::QuadNeighbour& nb = sp.quad[k];
                nb.valid = true;
                nb.sign = 1.f;
                nb.p = sp.p + (k == 0 ? Vec3(0.01f, 0, 0) : Vec3(0, 0.01f, 0));
                nb.wo = wo;
                const Vec3 n = glm::normalize(Vec3(k == 0 ? 0.15f : 0.f, k == 1 ? -0.15f : 0.f, 1.f));
                nb.frame = Frame::fromNormalTangent(n, Vec3(1, 0, 0));
            }
        }
        ScratchArena arena;
        Closure cl;
        m.shade(sp, arena, cl);
        std::vector<Color3> r;
        for (const Vec3& wi : wis) r.push_back(test::query(cl, wo, wi).f.total());
        return r;
    };
    const auto quad = material("quad"), analytic = material("analytic");
    const auto quadWith = eval(*quad, true), quadWithout = eval(*quad, false);
    const auto analyticWith = eval(*analytic, true), analyticWithout = eval(*analytic, false);
    double quadMoved = 0;
    for (size_t k = 0; k < wis.size(); ++k) {
        for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(analyticWith[k][ch], analyticWithout[k][ch]) << "direction " << k;
        for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(quadWithout[k][ch], analyticWithout[k][ch]) << "direction " << k;
        quadMoved += std::abs(luminance(quadWith[k]) - luminance(quadWithout[k]));
    }
    EXPECT_GT(quadMoved, 0.0) << "quad GGAA did not read the partners";
}

}  // namespace

// footprint_centre (issue 38 item 2): two samples of one pixel sit at uv = uv_c + duvdx·offset.x + duvdy·offset.y with
// normal n = n_c + dndx·offset.x + dndy·offset.y (a curved surface). With "pixel" both shade as the pixel centre does:
// the cells of its footprint around its half vectors; with "sample" (default) each follows its sample, and the
// sparkles change.
TEST(GlintMaterial, PixelCentredFootprintGivesEverySampleOfAPixelTheSameSparkles) {
    auto material = [](const char* centre) {
        return loadGraphMaterial(json{{"nodes", {{"g", {{"type", "bsdf.glint"},
                                                         {"inputs", {{"footprint_centre", centre}, {"log_density", 12},
                                                                     {"sigma_x", 0.1}, {"sigma_y", 0.1}}}}}}},
                                      {"output", "@g.bsdf"}},
                                 "/m", GraphLoadContext{});
    };
    const Vec3 wo = glm::normalize(Vec3(0.3f, -0.2f, 0.9f));
    std::vector<Vec3> wis;
    for (int k = 0; k < 900; ++k)
        wis.push_back(glm::normalize(Vec3(-wo.x + 0.008f * (k % 30 - 15), -wo.y + 0.008f * (k / 30 - 15), wo.z)));
    const Vec3 dndx(0.03f, 0.f, 0.f), dndy(0.f, -0.02f, 0.f);  // per pixel step: a sphere seen from far
    auto eval = [&](const Material& m, Vec2 offset) {
        ShadingPoint sp = glintyPoint(wo);
        sp.pixelOffset = offset;
        sp.uv += sp.duvdx * offset.x + sp.duvdy * offset.y;
        sp.dndx = dndx, sp.dndy = dndy;
        sp.n += dndx * offset.x + dndy * offset.y;  // first order, as the port reads it (the frame normalises)
        ScratchArena arena;
        Closure cl;
        m.shade(sp, arena, cl);
        std::vector<double> r;
        for (const Vec3& wi : wis) r.push_back(luminance(test::query(cl, wo, wi).f.total()));
        return r;
    };
    // Mean |a - b| over the directions, relative to the mean of a.
    auto difference = [](const std::vector<double>& a, const std::vector<double>& b) {
        double d = 0, s = 0;
        for (size_t k = 0; k < a.size(); ++k) d += std::abs(a[k] - b[k]), s += a[k];
        return d / std::max(s, 1e-30);
    };
    const auto pixel = material("pixel"), sample = material("sample");
    const Vec2 a(0.3f, -0.2f), b(-0.4f, 0.45f);
    const auto centre = eval(*pixel, Vec2(0.f)), pixelA = eval(*pixel, a), pixelB = eval(*pixel, b);
    const auto sampleA = eval(*sample, a), sampleB = eval(*sample, b);
    int lit = 0;
    for (double v : centre) lit += v > 0.0;
    ASSERT_GT(lit, 50) << "the footprint has sparkles in this cone of directions";
    // Measured 0 and 0 (bit for bit here; the margin is for the rounding of the step back), 0.98 between the two
    // sample-centred samples and 0.89 between the centre and sample a.
    EXPECT_LT(difference(centre, pixelA), 1e-4) << "pixel: the sample at offset a shades as the centre";
    EXPECT_LT(difference(centre, pixelB), 1e-4) << "pixel: the sample at offset b shades as the centre";
    EXPECT_EQ(difference(centre, eval(*sample, Vec2(0.f))), 0.0) << "at the pixel centre both modes are one lobe";
    EXPECT_GT(difference(sampleA, sampleB), 0.3) << "sample: two samples' footprints see other sparkles";
    EXPECT_GT(difference(centre, sampleA), 0.3) << "sample: the sample at offset a does not shade as the centre";
}
