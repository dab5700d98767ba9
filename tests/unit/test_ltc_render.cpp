// LTC area lights in the renderer (issue 10 item 3/6): render.area_lights = "ltc" against "sampled": the same image
// without occluders (closed form vs Monte Carlo), no bias beyond noise with shadows, and lower noise at low spp.
#include "core/render/renderer.h"
#include "core/scene/scene_loader.h"
#include "render_support.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace specula;

namespace {

// render.ltc_shadow_rays of the scenes (the default; measured with 1: 0.53 at pixel centres, 0.56 jittered).
const int kShadowRays = 2;

// A large floor under a downward-facing quad light (out of the frame), with an optional small occluder 0.2 above the
// floor that casts a shadow with a penumbra; the light crosses no horizon, the floor's edge is beyond the frame.
std::string shadowScene(const std::string& material, bool occluder, int spp, const char* mode, int seed = 0) {
    std::string shapes = R"([{"type": "quad", "size": [80, 80], "material": "m"})";
    if (occluder)
        shapes += R"(, {"type": "quad", "size": [0.4, 0.4], "transform": {"translate": [0.5, 0.2, 0.2]}, "material": "m"})";
    shapes += "]";
    return R"({
        "render": {"width": 32, "height": 24, "spp": )" + std::to_string(spp) + R"(, "integrator": "direct", "seed": )" +
           std::to_string(seed) + R"(, "area_lights": ")" + mode + R"(", "ltc_shadow_rays": )" +
           std::to_string(kShadowRays) + R"(},
        "camera": {"position": [0, -2, 1.8], "look_at": [0.3, 0.3, 0], "fov": 40},
        "materials": {"m": )" + material + R"(},
        "shapes": )" + shapes + R"(,
        "lights": [{"type": "quad", "position": [0, 0, 1.5], "look_at": [0, 0, 0], "size": [0.6, 0.6], "power": 20}]})";
}

const char* kDiffuse = R"({"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": 0.6}}}, "output": "@d.bsdf"})";

// pixelCentres: every sample at the pixel centre, no coverage noise (none of these scenes asks for it itself).
std::vector<float> beauty(const std::string& json, bool pixelCentres = false) {
    return test::renderAov(json, test::sourcePath("examples"), "beauty", pixelCentres);
}

using test::meanOf;
using test::rmseOf;

}  // namespace

TEST(LtcRender, UnshadowedDiffuseQuadLightEqualsMonteCarloPerPixel) {
    // Lambert's form factor is the exact integral: each pixel of the noise-free LTC image equals the path-traced
    // (light + BSDF sampling, MIS) estimate within its noise (measured by a second seed). Pixel centres: no coverage.
    auto ltc = beauty(shadowScene(kDiffuse, false, 1, "ltc"), true);
    auto mc = beauty(shadowScene(kDiffuse, false, 2048, "sampled", 1), true);
    auto mc2 = beauty(shadowScene(kDiffuse, false, 2048, "sampled", 2), true);
    const double sigma = rmseOf(mc, mc2) / std::sqrt(2.0);
    double worst = 0;
    for (size_t i = 0; i < ltc.size(); ++i) worst = std::max(worst, std::abs(double(ltc[i]) - mc[i]));
    EXPECT_LT(worst, 5.0 * sigma) << "sigma " << sigma;
    EXPECT_LT(rmseOf(ltc, mc), 1.2 * sigma);
    EXPECT_NEAR(meanOf(ltc) / meanOf(mc), 1.0, 2e-3);
}

TEST(LtcRender, ShadowedLtcConvergesToSampledAndIsLessNoisy) {
    // 4096 spp: ltc and sampled agree up to noise (the shadow ratio is unbiased). The noise floor of sampled is
    // measured by a second seed; a bias would make |ltc − sampled| exceed it.
    const int N = 4096;
    for (bool centres : {false, true}) {
        auto ref = beauty(shadowScene(kDiffuse, true, N, "sampled", 1), centres);
        auto ref2 = beauty(shadowScene(kDiffuse, true, N, "sampled", 2), centres);
        auto ltc = beauty(shadowScene(kDiffuse, true, N, "ltc", 3), centres);
        const double noise = rmseOf(ref, ref2);  // √2 × the per-image noise of one sampled render
        const double diff = rmseOf(ltc, ref);
        EXPECT_LT(diff, noise) << "ltc-vs-sampled " << diff << " sampled-vs-sampled " << noise;
        EXPECT_NEAR(meanOf(ltc) / meanOf(ref), 1.0, 2e-3);
        // 4 spp: RMSE against the 4096-spp reference. With pixel-centre samples the RMSE is the shading estimator's
        // alone (issue 10: ltc <= 0.5× sampled); with pixel jitter both also carry the same coverage noise of the
        // occluder's silhouette and the shadow's edge, which bounds the ratio from below.
        auto s4 = beauty(shadowScene(kDiffuse, true, 4, "sampled", 5), centres);
        auto l4 = beauty(shadowScene(kDiffuse, true, 4, "ltc", 5), centres);
        const double ratio = rmseOf(l4, ref) / rmseOf(s4, ref);
        std::printf("%s: 4-spp RMSE ltc %.5f sampled %.5f ratio %.3f; 4096-spp ltc-vs-sampled %.5f, noise floor %.5f\n",
                    centres ? "pixel centres" : "jittered", rmseOf(l4, ref), rmseOf(s4, ref), ratio, diff, noise);
        EXPECT_LE(ratio, centres ? 0.35 : 0.55);  // measured 0.223 / 0.437 (issue 10 asks <= 0.5)
    }
}

TEST(LtcRender, FullyLitPixelsAreNoiseFree) {
    // Two seeds at 1 spp at pixel centres: without occluders the image is the closed form (V = 1), no noise at all.
    auto a = beauty(shadowScene(kDiffuse, false, 1, "ltc", 1), true);
    auto b = beauty(shadowScene(kDiffuse, false, 1, "ltc", 2), true);
    double worst = 0;
    for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, double(std::abs(a[i] - b[i])));
    EXPECT_EQ(worst, 0.0);
    // And with the occluder, pixels outside the penumbra still are (fully lit: V = 1; umbra: V = 0).
    auto c = beauty(shadowScene(kDiffuse, true, 1, "ltc", 1), true);
    auto d = beauty(shadowScene(kDiffuse, true, 1, "ltc", 2), true);
    int same = 0;
    for (size_t i = 0; i < c.size(); ++i) same += c[i] == d[i];
    EXPECT_GT(same, int(0.8 * c.size()));
}
