// bsdf.glint_pndf as a node (issue 12 items 1, 4, 5): the closure equals F·G1·G1·D_P/(4 cosθo) of the manifold built
// from the same map, the footprint is k·(|du/dx|+|du/dy|)/2 texels of the pixel step whatever the spp, the input
// errors name the file and the JSON pointer, and the GLSL emitter declares its substitute with one warning.
#include "core/codegen/glsl_emitter.h"
#include "core/color/color_config.h"
#include "core/graph/graph_material.h"
#include "core/io/image_io.h"
#include "core/render/lobes/fresnel.h"
#include "core/render/material.h"
#include "core/render/shading.h"
#include "core/texture/normal_map_gen.h"
#include "core/texture/texture_store.h"
#include "core/util/error.h"
#include "nodes/bsdf/glint_pndf/pndf_eval.h"
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"
#include "nodes/bsdf/glint_pndf/pndf_masking.h"
#include "tests/unit/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

using namespace specula;
using nlohmann::json;

namespace {

constexpr const char* kMap = "generate:bumps:64:3";
constexpr int kMapSize = 64;

json pndfGraph(const json& inputs) {
    json in = inputs;
    if (!in.contains("normal_map")) in["normal_map"] = kMap;
    return json{{"nodes", {{"g", {{"type", "bsdf.glint_pndf"}, {"inputs", in}}}}}, {"output", "@g.bsdf"}};
}
std::shared_ptr<Material> pndfMaterial(const json& inputs, const GraphLoadContext& load = {}) {
    return loadGraphMaterial(pndfGraph(inputs), "/materials/m", load);
}

// A shading point whose pixel step is `texels` texels of the map along u and v (world frame, normal +z), with the
// ray differentials shrunk by `scale` as the renderer does at spp = 1/scale² (ShadingPoint::differentialScale).
ShadingPoint pixelPoint(const Vec3& wo, double texels, float scale = 1.f) {
    ShadingPoint sp;
    sp.n = sp.ng = Vec3(0, 0, 1);
    sp.tangent = Vec4(1, 0, 0, 1);
    sp.frame = Frame();
    sp.uv = Vec2(0.37f, 0.61f);
    const float step = float(texels / kMapSize);
    sp.duvdx = Vec2(step * scale, 0.f);
    sp.duvdy = Vec2(0.f, step * scale);
    sp.differentialScale = Vec2(scale);
    sp.hasDifferentials = true;
    sp.wo = wo;
    return sp;
}

// The manifold of kMap as the node decodes it: colour (n + 1)/2 -> 2c - 1, normalised, rows bottom-up.
const pndf::PndfManifold& referenceManifold() {
    static const pndf::PndfManifold m = [] {
        const NormalMap map = generateNormalMapFromName(kMap);
        const std::vector<float> px = encodeNormalMapRgb(map);
        std::vector<Vec3> normals(size_t(kMapSize) * kMapSize);
        for (int y = 0; y < kMapSize; ++y)
            for (int x = 0; x < kMapSize; ++x) {
                const float* p = &px[(size_t(kMapSize - 1 - y) * kMapSize + x) * 3];
                Vec3 n(2.f * p[0] - 1.f, 2.f * p[1] - 1.f, 2.f * p[2] - 1.f);
                normals[size_t(y) * kMapSize + x] = n / glm::length(n);
            }
        return pndf::PndfManifold(normals, kMapSize, kMapSize);
    }();
    return m;
}

std::vector<Vec3> directionsAbove(unsigned seed, int n) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g(0.f, 1.f);
    std::vector<Vec3> v;
    while (int(v.size()) < n) {
        Vec3 d(g(rng), g(rng), std::abs(g(rng)) + 0.05f);
        v.push_back(glm::normalize(d));
    }
    return v;
}

}  // namespace

TEST(GlintPndfNode, ClosureIsFresnelMaskingAndTheExactPndf) {
    // σ = k (|du/dx| + |du/dy|)/2 = 2 · 4/2 = 4 texels; exact D (no cluster cut), fresnel none, GGX-fit masking.
    auto m = pndfMaterial({{"fresnel", "none"}, {"cluster_threshold", 0.0}});
    const Vec3 wo = glm::normalize(Vec3(0.2f, -0.3f, 1.f));
    ScratchArena arena;
    Closure cl;
    m->shade(pixelPoint(wo, 4.0), arena, cl);
    ASSERT_EQ(cl.size(), 1);
    const pndf::PndfManifold& ref = referenceManifold();
    const pndf::Footprint fp = pndf::Footprint::fromUv(Vec2(0.37f, 0.61f), 1.0, kMapSize, kMapSize, 4.0, 4.0,
                                                       pndf::FootprintKernel::Gaussian);
    const pndf::PndfGgxFit fit(ref);
    // The lobe's masking: the fit's roughness, sheared by the footprint's own tilt at σ <= 8 (pndf_lobe.cpp).
    pndf::GgxAlpha alpha = fit.alphaAt(fp);
    const pndf::Vec2d tilt = pndf::footprintTilt(ref, fp);
    alpha.tiltX = tilt.x;
    alpha.tiltY = tilt.y;
    // Half vectors where D is non-zero: manifold normals at points well inside triangles of the footprint (not at
    // vertices or edges of the normal image, where D jumps and float rounding of h decides which triangles count).
    int nonZero = 0;
    double worst = 0;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> off(-3.0, 3.0), inner(0.2, 0.4);
    for (int k = 0; k < 64; ++k) {
        pndf::ManifoldTriangle tris[2];
        ref.cellTriangles(int(std::floor(fp.centreY + off(rng))), int(std::floor(fp.centreX + off(rng))), tris);
        const pndf::ManifoldTriangle& tri = tris[k % 2];
        const double t1 = inner(rng), t2 = inner(rng);
        const Vec2 s(float(tri.sOrigin.x + t1 * tri.sEdge1.x + t2 * tri.sEdge2.x),
                     float(tri.sOrigin.y + t1 * tri.sEdge1.y + t2 * tri.sEdge2.y));
        const Vec3 h(s.x, s.y, std::sqrt(std::max(0.f, 1.f - s.x * s.x - s.y * s.y)));
        const Vec3 wi = 2.f * glm::dot(wo, h) * h - wo;
        if (wi.z <= 0.05f) continue;
        const Vec3 hh = glm::normalize(wo + wi);
        const double d = pndf::evalPndfHierarchy(ref, fp, {hh.x, hh.y});
        const double expect = pndf::smithG1GgxFit(alpha, wo) * pndf::smithG1GgxFit(alpha, wi) * d / (4.0 * wo.z);
        const BsdfValue v = test::query(cl, wo, wi);
        if (d > 0) ++nonZero;
        const double got = v.f.total().x;
        worst = std::max(worst, std::abs(got - expect) / std::max(expect, 1e-3));
        // pdf = D cosθh / (4 wo·h) (spec §2.4), the density sample() draws.
        if (d > 0) EXPECT_NEAR(v.pdf, d * hh.z / (4.0 * glm::dot(wo, hh)), 1e-4 * v.pdf);
    }
    std::printf("eval vs F G D/(4 cos): %d non-zero probes, worst relative error %.3g\n", nonZero, worst);
    EXPECT_GE(nonZero, 40);
    EXPECT_LT(worst, 1e-4);
}

TEST(GlintPndfNode, FootprintIsOnePixelStepAtAnySpp) {
    // The ports bind the pixel steps (duv / differentialScale): shrinking the differentials as the renderer does at
    // 16 and 256 spp leaves every value unchanged.
    auto m = pndfMaterial({});
    const Vec3 wo = glm::normalize(Vec3(-0.3f, 0.1f, 1.f));
    std::vector<std::vector<float>> runs;
    for (float scale : {1.f, 0.25f, 0.0625f}) {
        ScratchArena arena;
        Closure cl;
        m->shade(pixelPoint(wo, 6.0, scale), arena, cl);
        std::vector<float> r;
        for (const Vec3& wi : directionsAbove(3, 256)) r.push_back(test::query(cl, wo, wi).f.total().x);
        runs.push_back(r);
    }
    int nonZero = 0;
    for (size_t k = 0; k < runs[0].size(); ++k) {
        nonZero += runs[0][k] > 0.f;
        EXPECT_EQ(runs[0][k], runs[1][k]) << k;
        EXPECT_EQ(runs[0][k], runs[2][k]) << k;
    }
    EXPECT_GT(nonZero, 0);
}

TEST(GlintPndfNode, PixelCentredFootprintIgnoresTheSampleOffset) {
    // Two samples of one pixel: uv = uv_centre + duvdx·offset.x + duvdy·offset.y. With footprint_centre "pixel" both
    // centre the kernel on uv_centre; with "sample" (default) each on its own uv.
    const Vec3 wo(0, 0, 1);
    auto centreOf = [&](const char* mode, Vec2 offset) {
        auto m = pndfMaterial({{"footprint_centre", mode}});
        ShadingPoint sp = pixelPoint(wo, 6.0);
        sp.pixelOffset = offset;
        sp.uv += sp.duvdx * offset.x + sp.duvdy * offset.y;
        ScratchArena arena;
        Closure cl;
        m->shade(sp, arena, cl);
        LobeParameters p;
        cl.lobe(0)->parameters(LobeQuery{wo, wo}, p);
        for (auto& [name, v] : p)
            if (name == "footprint_centre_texels") return Vec2(float(v[0]), float(v[1]));
        return Vec2(-1.f);
    };
    const Vec2 a = centreOf("pixel", Vec2(0.3f, -0.2f)), b = centreOf("pixel", Vec2(-0.4f, 0.45f));
    EXPECT_NEAR(a.x, b.x, 1e-3f);
    EXPECT_NEAR(a.y, b.y, 1e-3f);
    EXPECT_NEAR(a.x, 0.37f * kMapSize, 1e-3f);  // the pixel centre's uv (0.37, 0.61)
    EXPECT_NEAR(a.y, 0.61f * kMapSize, 1e-3f);
    const Vec2 c = centreOf("sample", Vec2(0.3f, -0.2f));
    EXPECT_NEAR(c.x, 0.37f * kMapSize + 0.3f * 6.f, 1e-3f);  // 6 texels per pixel step
    EXPECT_NEAR(c.y, 0.61f * kMapSize - 0.2f * 6.f, 1e-3f);
}

TEST(GlintPndfNode, FootprintHalfWidthFollowsScaleTilesAndClamp) {
    const Vec3 wo(0, 0, 1);
    auto sigmaOf = [&](const json& in, double texels) {
        auto m = pndfMaterial(in);
        ScratchArena arena;
        Closure cl;
        m->shade(pixelPoint(wo, texels), arena, cl);
        LobeParameters p;
        cl.lobe(0)->parameters(LobeQuery{wo, wo}, p);
        for (auto& [name, v] : p)
            if (name == "footprint_sigma_texels") return v[0];
        return -1.0;
    };
    EXPECT_DOUBLE_EQ(sigmaOf({}, 6.0), 6.0);                              // k = 2: σ = 2 · 6/2
    EXPECT_DOUBLE_EQ(sigmaOf({{"footprint_scale", 1.0}}, 6.0), 3.0);      // k = 1
    EXPECT_DOUBLE_EQ(sigmaOf({{"uv_scale", 4.0}}, 6.0), 24.0);            // tiles: 4 x the texels per uv unit
    EXPECT_DOUBLE_EQ(sigmaOf({}, 0.1), 1.0);                              // clamped below at one texel
    EXPECT_DOUBLE_EQ(sigmaOf({{"footprint_scale", 8.0}}, 40.0), 128.0);   // and above at 128 (spec §1)
}

TEST(GlintPndfNode, SamplesFollowThePdfTheyReport) {
    auto m = pndfMaterial({{"fresnel", "conductor"}});
    const Vec3 wo = glm::normalize(Vec3(0.4f, 0.2f, 1.f));
    ScratchArena arena;
    Closure cl;
    m->shade(pixelPoint(wo, 8.0), arena, cl);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int ok = 0;
    for (int k = 0; k < 2000; ++k) {
        BsdfSample s;
        if (!test::sample(cl, wo, u(rng), Vec2(u(rng), u(rng)), s)) continue;
        ++ok;
        const BsdfValue v = test::query(cl, wo, s.wi);
        ASSERT_GT(v.pdf, 0.f);
        EXPECT_NEAR(s.pdf, v.pdf, 1e-5f * v.pdf);
        EXPECT_NEAR(s.f.total().y, v.f.total().y, 1e-5f * v.f.total().y + 1e-12f);
    }
    std::printf("accepted samples: %d of 2000\n", ok);
    EXPECT_GT(ok, 1500);  // rejections: microfacets reflecting below the horizon or facing away
}

TEST(GlintPndfNode, InputErrorsNameTheFileAndThePointer) {
    const std::string dir = test::tempDir("pndf-errors");
    auto store = std::make_shared<TextureStore>(ColorConfig::load("builtin"));
    GraphLoadContext load{store.get(), dir};
    // One channel: not a tangent-space normal map.
    std::vector<float> grey(16 * 16, 0.5f);
    writeImage8(dir + "/grey.png", 16, 16, 1, grey.data());
    // Three channels of unrelated colour: the decoded vectors are far from unit length.
    std::vector<float> colour(16 * 16 * 3);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (float& c : colour) c = u(rng);
    writeImage8(dir + "/photo.png", 16, 16, 3, colour.data());
    struct Case {
        const char* file;
        const char* expect;
    };
    for (const Case& c : {Case{"grey.png", "1 channel(s)"}, Case{"photo.png", "is not a tangent-space normal map"},
                          Case{"missing.png", "cannot load"}, Case{"generate:bumpz:64:1", "cannot load"}}) {
        try {
            pndfMaterial({{"normal_map", c.file}}, load);
            ADD_FAILURE() << c.file << " was accepted";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("/materials/m/nodes/g/inputs/normal_map"), std::string::npos) << what;
            EXPECT_NE(what.find(c.file), std::string::npos) << what;
            EXPECT_NE(what.find(c.expect), std::string::npos) << what;
        }
    }
}

TEST(GlintPndfNode, GlslDeclaresTheSubstituteWithOneWarning) {
    // Two P-NDF nodes in one material: one warning line for the type, repeated in the module's header comment.
    json g = {{"nodes",
               {{"a", {{"type", "bsdf.glint_pndf"}, {"inputs", {{"normal_map", kMap}}}}},
                {"b", {{"type", "bsdf.glint_pndf"}, {"inputs", {{"normal_map", kMap}, {"kernel", "box"}}}}},
                {"mix", {{"type", "closure.add"}, {"inputs", {{"a", "@a.bsdf"}, {"b", "@b.bsdf"}}}}}}},
              {"output", "@mix.bsdf"}};
    const graph::GraphDesc desc = graph::parseGraph(g, "/materials/m");
    const codegen::GlslModule mod = codegen::emitGlsl(desc);
    ASSERT_EQ(mod.warnings.size(), 1u);
    EXPECT_NE(mod.warnings[0].find("bsdf.glint_pndf: not supported on the GPU"), std::string::npos) << mod.warnings[0];
    EXPECT_NE(mod.source.find("// WARNING: bsdf.glint_pndf"), std::string::npos);
    // Beside texture.lean and bsdf.ggx_filtered (whose files the substitute uses as libraries) each file is emitted
    // once: one include guard per file (tests/glsl/data/materials.json "pndf_beside_lean" compiles it).
    json both = {{"nodes",
                  {{"p", {{"type", "bsdf.glint_pndf"}, {"inputs", {{"normal_map", kMap}}}}},
                   {"l", {{"type", "texture.lean"}, {"inputs", {{"file", kMap}}}}},
                   {"f", {{"type", "bsdf.ggx_filtered"}, {"inputs", {{"covariance", "@l.covariance"}}}}},
                   {"s", {{"type", "closure.add"}, {"inputs", {{"a", "@p.bsdf"}, {"b", "@f.bsdf"}}}}}}},
                 {"output", "@s.bsdf"}};
    const std::string src = codegen::emitGlsl(graph::parseGraph(both, "/materials/b")).source;
    for (const char* fn : {"void spc_lean_bilinear(", "void spc_bsdf_ggx_filtered(", "vec3 spc_fresnel_f0("}) {
        const size_t first = src.find(fn);
        ASSERT_NE(first, std::string::npos) << fn;
        EXPECT_EQ(src.find(fn, first + 1), std::string::npos) << fn << " defined twice";
    }
    // A material without it has none.
    json plain = {{"nodes", {{"d", {{"type", "bsdf.diffuse"}}}}}, {"output", "@d.bsdf"}};
    EXPECT_TRUE(codegen::emitGlsl(graph::parseGraph(plain, "/materials/p")).warnings.empty());
}
