// Glints in the renderer (issue 11 item 1): the glint LOD footprint is one pixel whatever the spp, so a glint image
// converges to one picture: 256 and 1024 spp agree to noise level and the sparkles sit where they sit at 16 spp.
#include "core/render/renderer.h"
#include "core/scene/scene_loader.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace specula;

namespace {

// A glint sphere filling a 48x32 image under a point light (the only noise is the pixel filter's sub-pixel jitter).
std::string glintSphere(int spp, int seed) {
    return R"({
        "render": {"width": 48, "height": 32, "spp": )" + std::to_string(spp) + R"(, "seed": )" + std::to_string(seed) +
           R"(, "integrator": "direct"},
        "camera": {"position": [0, -3, 0.6], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov": 22, "fov_axis": "x"},
        "materials": {"glint": {"nodes": {"g": {"type": "bsdf.glint", "inputs": {"sigma_x": 0.25, "sigma_y": 0.25,
            "log_density": 16, "f0": 0.9}}}, "output": "@g.bsdf"}},
        "shapes": [{"type": "sphere", "radius": 1, "material": "glint"}],
        "lights": [{"type": "point", "position": [1.5, -3, 2.5], "power": 2000}]})";
}

std::vector<double> specular(int spp, int seed) {
    Scene s = loadSceneFromString(glintSphere(spp, seed), test::sourcePath("examples"));
    RenderOutput r = renderScene(s);
    const auto& px = r.images.find("specular")->pixels;
    std::vector<double> lum(px.size() / 3);
    for (size_t i = 0; i < lum.size(); ++i) lum[i] = double(px[3 * i]) + px[3 * i + 1] + px[3 * i + 2];
    return lum;
}

double rmse(const std::vector<double>& a, const std::vector<double>& b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
    return std::sqrt(s / double(a.size()));
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
    double ma = 0, mb = 0;
    for (size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
    ma /= double(a.size()), mb /= double(b.size());
    double sab = 0, sa = 0, sb = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        sab += (a[i] - ma) * (b[i] - mb);
        sa += (a[i] - ma) * (a[i] - ma);
        sb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / std::sqrt(sa * sb);
}

}  // namespace

TEST(GlintRender, AppearanceIsIndependentOfSpp) {
    const auto s16 = specular(16, 0), s256a = specular(256, 1), s256b = specular(256, 2), s1024 = specular(1024, 3);
    // Noise of one 256-spp image, from two seeds; 256 vs 1024 then differs by sqrt(1 + 1/4) of it if both converge
    // to the same picture (with the old spp-scaled footprint, 1/4 vs 1/8 pixel below 64 spp: other glints).
    const double noise256 = rmse(s256a, s256b) / std::sqrt(2.0);
    const double d256 = rmse(s256a, s1024), c16 = correlation(s16, s1024), c256 = correlation(s256a, s1024);
    std::printf("glint sphere, specular AOV: noise(256) %.4f, rmse(256, 1024) %.4f = %.2f x noise; correlation with "
                "1024 spp: 16 spp %.4f, 256 spp %.4f\n", noise256, d256, d256 / noise256, c16, c256);
    // Measured 0.45 vs noise 0.38 (1.18x), correlations 0.990 and 0.9992; with the spp-scaled footprint of wave 1
    // the same scene gave rmse(256, 1024) 1.29 and correlation(16, 1024) 0.757.
    EXPECT_LT(d256, 1.35 * noise256);
    EXPECT_GT(c16, 0.97);
    EXPECT_GT(c256, 0.995);
}

namespace {

// A flat 1.2 m glint plate seen from 2 m above in a 96 x 96 image (about 1 cm per pixel) under the studio environment
// and a point light: flakes of 0.05 UV (6 cm, about 6 pixels) when flakeSize > 0, else the same density counted by
// C20 alone (log_density = ln(1 / 0.05^2)).
std::vector<double> flakePlate(bool flakes, int seed) {
    const std::string glint = flakes ? R"("flake_size": 0.05)" : R"("log_density": 5.991465)";
    const std::string scene = R"({
        "render": {"width": 96, "height": 96, "spp": 16, "seed": )" + std::to_string(seed) + R"(, "integrator": "direct"},
        "camera": {"position": [0, 0, 2], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 28.07, "fov_axis": "x"},
        "materials": {"glint": {"nodes": {"g": {"type": "bsdf.glint", "inputs": {"sigma_x": 0.3, "sigma_y": 0.3,
            "relative_area": 0.8, )" + glint + R"(}}}, "output": "@g.bsdf"}},
        "shapes": [{"type": "quad", "size": [1.2, 1.2], "material": "glint"}],
        "lights": [{"type": "environment", "file": "showcase/studio.hdr", "colorspace": "lin_rec709", "strength": 1},
                   {"type": "point", "position": [0.6, -0.8, 2.5], "power": 60}]})";
    Scene s = loadSceneFromString(scene, test::sourcePath("examples"));
    RenderOutput r = renderScene(s);
    const auto& px = r.images.find("specular")->pixels;
    std::vector<double> lum(px.size() / 3);
    for (size_t i = 0; i < lum.size(); ++i) lum[i] = double(px[3 * i]) + px[3 * i + 1] + px[3 * i + 2];
    return lum;
}

// Correlation of the 96 x 96 image with itself shifted by `lag` pixels, along x and y together.
double autocorrelation(const std::vector<double>& a, int lag) {
    const int n = 96;
    std::vector<double> p, q;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            if (x + lag < n) p.push_back(a[size_t(y * n + x)]), q.push_back(a[size_t(y * n + x + lag)]);
            if (y + lag < n) p.push_back(a[size_t(y * n + x)]), q.push_back(a[size_t((y + lag) * n + x)]);
        }
    return correlation(p, q);
}

double mean(const std::vector<double>& a) {
    double s = 0;
    for (double v : a) s += v;
    return s / double(a.size());
}

}  // namespace

// Issue 38 item 3: flakes are surface features of their size. With flake_size the specular image of a close-up plate
// is made of patches about the flake's width (pixels 2 and 3 apart still correlate), where C20's counting at the same
// density gives one-pixel grain; the pattern belongs to the surface, so two seeds differ less than the counted glints'
// two seeds do (what is left is the sampling of the environment through the flakes' narrow lobes and the flakes'
// edges). The energy is GlintFlakes.SurfaceMeanOfTheFlakesIsTheConvergedLobe's claim: one 96 x 96 plate holds about
// 300 flakes, whose mean specular spreads by 12 % from one plate to the next under this environment (docs/validation/
// glint.md), too wide for a test of the mean.
TEST(GlintRender, FlakesArePatchesOfTheirSizeThatStayPutAcrossSeeds) {
    const auto flakesA = flakePlate(true, 1), flakesB = flakePlate(true, 2);
    const auto countedA = flakePlate(false, 1), countedB = flakePlate(false, 2);
    const double cf = autocorrelation(flakesA, 2), cc = autocorrelation(countedA, 2);
    const double cf3 = autocorrelation(flakesA, 3), cc3 = autocorrelation(countedA, 3);
    const double mf = 0.5 * (mean(flakesA) + mean(flakesB)), mc = 0.5 * (mean(countedA) + mean(countedB));
    const double sf = rmse(flakesA, flakesB) / mf, sc = rmse(countedA, countedB) / mc;
    std::printf("flake plate: autocorrelation at 2 and 3 px %.3f, %.3f with flakes, %.3f, %.3f counted; seed-to-seed "
                "RMSE / mean %.3f with flakes, %.3f counted (ratio %.3f); mean specular %.4f with flakes, %.4f counted\n",
                cf, cf3, cc, cc3, sf, sc, sf / sc, mf, mc);
    EXPECT_GT(cf, 0.55);
    EXPECT_GT(cf3, 0.3);
    EXPECT_LT(std::abs(cc), 0.1);
    EXPECT_LT(sf, 0.8 * sc);
}
