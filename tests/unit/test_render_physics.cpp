// Renderer truths: white furnace, GGX normalisation/energy against independent Monte Carlo, ray
// differentials against finite differences of real neighbouring-pixel rays, thread-count determinism.
#include "core/render/accel.h"
#include "core/render/camera.h"
#include "core/render/lobes/ggx.h"
#include "core/render/lobes/lambert.h"
#include "core/render/renderer.h"
#include "core/render/sampler.h"
#include "core/render/sampling.h"
#include "core/scene/scene_loader.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>

using namespace specula;

namespace {

Scene sceneFrom(const std::string& json) { return loadSceneFromString(json, test::sourcePath("examples")); }

using test::Rng;

Vec3 dirFromTheta(float thetaDeg, float phiDeg = 0.f) {
    float t = glm::radians(thetaDeg), p = glm::radians(phiDeg);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

}  // namespace

TEST(WhiteFurnace, DiffuseSphereInConstantEnvironmentReturnsEnvironment) {
    for (const char* integrator : {"path", "direct"}) {
        Scene s = sceneFrom(std::string(R"({
            "render": {"width": 48, "height": 48, "spp": 64, "integrator": ")") + integrator + R"("},
            "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "fov": 30},
            "materials": {"white": {"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": 1.0}}}, "output": "@d.bsdf"}},
            "shapes": [{"type": "sphere", "radius": 1, "material": "white"}],
            "lights": [{"type": "environment", "color": [0.7, 0.7, 0.7]}]})");
        RenderOutput r = renderScene(s);
        const AovBuffer* beauty = r.images.find("beauty");
        const AovBuffer* albedo = r.images.find("albedo");
        ASSERT_TRUE(beauty && albedo);
        double sum = 0;
        int n = 0;
        for (size_t i = 0; i < beauty->pixels.size() / 3; ++i) {
            if (albedo->pixels[i * 3] < 0.999f) continue;  // sphere pixels only (fully covered)
            sum += beauty->pixels[i * 3 + 1];
            ++n;
        }
        ASSERT_GT(n, 300);
        EXPECT_NEAR(sum / n / 0.7, 1.0, 0.01) << integrator;
        EXPECT_EQ(r.stats.invalidSamples, 0u);
    }
}

TEST(Ggx, NdfIsNormalisedOverProjectedArea) {
    // ∫ D(h) cos θh dωh = 1 (Walter et al. 2007, Eq. 4), checked by stratified quadrature.
    for (float ax : {0.05f, 0.2f, 0.6f}) {
        for (float ay : {ax, 2.f * ax}) {
            double sum = 0;
            const int N = 1500;
            for (int i = 0; i < N; ++i) {
                // substitute cos θ = 1 - x² ... use a warp concentrated near the pole for small α
                for (int j = 0; j < 256; ++j) {
                    double u = (i + 0.5) / N, v = (j + 0.5) / 256;
                    double tanT = std::tan(u * 0.5 * M_PI * 0.999999);
                    double theta = std::atan(tanT);
                    double phi = 2 * M_PI * v;
                    double dtheta = 0.5 * M_PI * 0.999999 / N;
                    Vec3 h = dirFromTheta(float(glm::degrees(theta)), float(glm::degrees(phi)));
                    sum += double(ggx::ndf(h, ax, ay)) * std::cos(theta) * std::sin(theta) * dtheta * (2 * M_PI / 256);
                }
            }
            EXPECT_NEAR(sum, 1.0, 0.02) << "ax " << ax << " ay " << ay;
        }
    }
}

TEST(Ggx, EnergyAtMostOneAndMatchesIndependentMonteCarlo) {
    Rng rng{42};
    for (float alpha : {0.02f, 0.1f, 0.3f, 0.7f}) {
        for (float theta : {0.f, 30.f, 60.f, 80.f}) {
            GgxLobe lobe(alpha, alpha * 1.5f, Fresnel::one());
            Vec3 wo = dirFromTheta(theta, 20.f);
            // (a) importance sampling through the lobe's own sample/pdf
            const int N = 200000;
            double isEst = 0;
            for (int i = 0; i < N; ++i) {
                Vec3 wi;
                if (!lobe.sample(wo, rng.next2(), wi)) continue;
                float p = lobe.pdf(wo, wi);
                if (p > 0.f) isEst += luminance(lobe.eval(wo, wi)) / p;
            }
            isEst /= N;
            // (b) independent estimate: cosine-weighted hemisphere sampling (no knowledge of the lobe)
            double cosEst = 0;
            for (int i = 0; i < N; ++i) {
                Vec3 wi = sampleCosineHemisphere(rng.next2());
                cosEst += luminance(lobe.eval(wo, wi)) / (wi.z * kInvPi);
            }
            cosEst /= N;
            EXPECT_LE(isEst, 1.0 + 1e-3) << "alpha " << alpha << " theta " << theta;
            if (alpha >= 0.1f) {  // the cosine estimator is too noisy for near-specular lobes
                EXPECT_NEAR(isEst, cosEst, 0.02 * std::max(cosEst, 0.1)) << "alpha " << alpha << " theta " << theta;
            }
            // Single scattering loses little energy on smooth surfaces: measured 0.958 at the worst case
            // here (αx = 0.1, αy = 0.15, θ = 60°), 0.980 at normal incidence.
            if (alpha <= 0.1f && theta <= 60.f) EXPECT_GT(isEst, 0.95);
            if (alpha <= 0.1f && theta == 0.f) EXPECT_GT(isEst, 0.975);
        }
    }
}

TEST(Ggx, SamplingPdfIntegratesToOne) {
    Rng rng{7};
    for (float alpha : {0.15f, 0.5f}) {
        GgxLobe lobe(alpha, alpha, Fresnel::one());
        Vec3 wo = dirFromTheta(40.f);
        // ∫ pdf dω over the upper hemisphere = P(sample above horizon) ≤ 1, estimated uniformly.
        double sum = 0;
        const int N = 400000;
        for (int i = 0; i < N; ++i) {
            Vec3 wi = sampleUniformSphere(rng.next2());
            if (wi.z > 0.f) sum += lobe.pdf(wo, wi) * 4.0 * M_PI;
        }
        sum /= N;
        int valid = 0;
        for (int i = 0; i < 20000; ++i) {
            Vec3 wi;
            valid += lobe.sample(wo, rng.next2(), wi) ? 1 : 0;
        }
        EXPECT_NEAR(sum, valid / 20000.0, 0.02) << alpha;
    }
}

TEST(Ggx, ReciprocityAndFresnelLimits) {
    GgxLobe lobe(0.2f, 0.35f, Fresnel::schlick(Color3(0.04f)));
    Rng rng{3};
    for (int i = 0; i < 200; ++i) {
        Vec3 a = sampleCosineHemisphere(rng.next2()), b = sampleCosineHemisphere(rng.next2());
        // f(a,b) = f(b,a): compare f·cos / cos.
        Color3 fab = lobe.eval(a, b) / b.z, fba = lobe.eval(b, a) / a.z;
        EXPECT_NEAR(fab.x, fba.x, 1e-4f * std::max(1.f, fab.x));
    }
    EXPECT_NEAR(fresnelDielectric(1.f, 1.5f), 0.04f, 1e-5f);
    EXPECT_NEAR(fresnelConductor(1.f, 1.5f, 0.f), 0.04f, 1e-5f);  // k = 0 conductor = dielectric
    EXPECT_NEAR(fresnelConductor(0.f, 0.2f, 3.9f), 1.f, 1e-4f);
}

namespace {

struct DiffCheck {
    double worstP = 0, worstUv = 0, worstN = 0;
    int checked = 0;
};

// Compares the hit differentials at pixel (x, y) with central differences of the real rays through
// the neighbouring pixels (x±1, y) and (x, y±1).
DiffCheck checkDifferentials(const Scene& scene, bool checkNormals) {
    Accel accel(scene);
    PerspectiveCamera cam(scene.camera, scene.render.width, scene.render.height);
    DiffCheck dc;
    for (int y = 8; y < scene.render.height - 8; y += 11) {
        for (int x = 8; x < scene.render.width - 8; x += 11) {
            auto hitAt = [&](float px, float py, ShadingPoint& sp, Hit& h) {
                RayDifferential r = cam.generateRay(px, py, Vec2(0.5f));
                if (!accel.intersect(r, h)) return false;
                sp = accel.shadingPoint(r, h);
                return true;
            };
            ShadingPoint c, xp, xm, yp, ym;
            Hit hc, h1, h2, h3, h4;
            float cx = x + 0.5f, cy = y + 0.5f;
            if (!hitAt(cx, cy, c, hc) || !hitAt(cx + 1, cy, xp, h1) || !hitAt(cx - 1, cy, xm, h2) ||
                !hitAt(cx, cy + 1, yp, h3) || !hitAt(cx, cy - 1, ym, h4))
                continue;
            if (h1.shape != hc.shape || h2.shape != hc.shape || h3.shape != hc.shape || h4.shape != hc.shape) continue;
            if (glm::dot(c.n, c.wo) < 0.3f) continue;  // avoid silhouettes, where the neighbour rays miss the tangent plane
            // Skip the u seam of parametric surfaces (uv wraps from 1 to 0).
            if (std::abs(xp.uv.x - xm.uv.x) > 0.5f || std::abs(yp.uv.x - ym.uv.x) > 0.5f) continue;
            auto rel = [](const Vec3& fd, const Vec3& an) {
                return double(glm::length(fd - an)) / std::max(double(glm::length(fd)), 1e-7);
            };
            auto rel2 = [](const Vec2& fd, const Vec2& an) {
                return double(glm::length(fd - an)) / std::max(double(glm::length(fd)), 1e-7);
            };
            Vec3 fdx = 0.5f * (xp.p - xm.p), fdy = 0.5f * (yp.p - ym.p);
            dc.worstP = std::max({dc.worstP, rel(fdx, c.dpdx), rel(fdy, c.dpdy)});
            dc.worstUv = std::max({dc.worstUv, rel2(0.5f * (xp.uv - xm.uv), c.duvdx), rel2(0.5f * (yp.uv - ym.uv), c.duvdy)});
            if (checkNormals) {
                Vec3 fnx = 0.5f * (xp.n - xm.n), fny = 0.5f * (yp.n - ym.n);
                dc.worstN = std::max({dc.worstN, rel(fnx, c.dndx), rel(fny, c.dndy)});
            }
            ++dc.checked;
        }
    }
    return dc;
}

// Every AOV of two renders, the same bits.
void expectSameBits(const ImageSet& a, const ImageSet& b) {
    ASSERT_EQ(a.aovs.size(), b.aovs.size());
    for (size_t i = 0; i < a.aovs.size(); ++i) {
        const auto& pa = a.aovs[i].pixels;
        const auto& pb = b.aovs[i].pixels;
        ASSERT_EQ(pa.size(), pb.size());
        EXPECT_EQ(std::memcmp(pa.data(), pb.data(), pa.size() * sizeof(float)), 0) << a.aovs[i].name;
    }
}

std::string diffScene(const std::string& shape) {
    // 512² keeps one-pixel steps small against the torus' minor radius, so that central differences
    // (second-order accurate) are a fair reference for the analytic differentials.
    return R"({"render": {"width": 512, "height": 512},
        "camera": {"position": [0.3, -4, 2.2], "look_at": [0, 0, 0.4], "fov": 40},
        "materials": {"m": {"nodes": {"d": {"type": "bsdf.diffuse"}}, "output": "@d.bsdf"}},
        "shapes": [)" + shape + R"(]})";
}

}  // namespace

// Embree chooses SSE, AVX2 or AVX-512 kernels by the CPU at run time and their t, u, v differ in the last bits;
// Accel recomputes them from the hit triangle, so a hit is the same bits on every machine (and images are too).
// Pinning Embree's ISA on one machine stands in for running on machines of different ISAs.
TEST(AccelDeterminism, HitsAreTheSameBitsForEveryEmbreeIsa) {
    Scene s = sceneFrom(R"({"camera": {"position": [0.3, -4, 2.2], "look_at": [0, 0, 0.4], "fov": 40},
        "materials": {"m": {"nodes": {"d": {"type": "bsdf.diffuse"}}, "output": "@d.bsdf"}},
        "shapes": [{"type": "sphere", "radius": 1.2, "transform": {"translate": [0, 0, 0.4]}, "material": "m"},
                   {"type": "torus", "major_radius": 1.5, "minor_radius": 0.3, "material": "m"},
                   {"type": "quad", "size": [8, 8], "transform": {"translate": [0, 0, -1]}, "material": "m"}]})");
    std::vector<std::vector<Hit>> hits;
    std::vector<Ray> rays;
    Rng rng{7};
    for (int i = 0; i < 40000; ++i) {
        Ray r;
        r.o = Vec3(rng.next() * 8.f - 4.f, rng.next() * 8.f - 4.f, rng.next() * 6.f - 1.f) * 1.5f;
        r.d = glm::normalize(Vec3(0.f, 0.f, 0.4f) + Vec3(rng.next(), rng.next(), rng.next()) - 0.5f - r.o);
        rays.push_back(r);
    }
    for (const char* config : {"threads=1,max_isa=sse4.2", "threads=1,max_isa=avx2", "threads=0"}) {
        Accel accel(s, config);
        hits.emplace_back(rays.size());
        for (size_t i = 0; i < rays.size(); ++i)
            if (!accel.intersect(rays[i], hits.back()[i])) hits.back()[i].shape = ~0u;
    }
    size_t compared = 0, differing = 0;
    for (size_t k = 1; k < hits.size(); ++k)
        for (size_t i = 0; i < rays.size(); ++i) {
            const Hit &a = hits[0][i], &b = hits[k][i];
            if (a.shape == ~0u || a.shape != b.shape || a.prim != b.prim) continue;  // a tie on an edge: another triangle
            ++compared;
            differing += std::memcmp(&a.t, &b.t, sizeof(float)) || std::memcmp(&a.b1, &b.b1, sizeof(float)) ||
                         std::memcmp(&a.b2, &b.b2, sizeof(float));
        }
    EXPECT_GT(compared, 40000u);
    EXPECT_EQ(differing, 0u) << "of " << compared << " hits";
}

TEST(RayDifferentials, MatchFiniteDifferencesOnSphere) {
    Scene s = sceneFrom(diffScene(R"({"type": "sphere", "radius": 1.2, "transform": {"translate": [0, 0, 0.4]}, "material": "m"})"));
    DiffCheck dc = checkDifferentials(s, true);
    EXPECT_GT(dc.checked, 100);
    EXPECT_LT(dc.worstP, 0.02);
    EXPECT_LT(dc.worstUv, 0.02);
    EXPECT_LT(dc.worstN, 0.02);
}

TEST(RayDifferentials, MatchFiniteDifferencesOnPlane) {
    Scene s = sceneFrom(diffScene(R"({"type": "quad", "size": [6, 6], "transform": {"rotate": [10, 0, 20]}, "material": "m"})"));
    DiffCheck dc = checkDifferentials(s, false);
    EXPECT_GT(dc.checked, 200);
    EXPECT_LT(dc.worstP, 0.02);
    EXPECT_LT(dc.worstUv, 0.02);
}

TEST(RayDifferentials, MatchFiniteDifferencesOnTorus) {
    Scene s = sceneFrom(diffScene(
        R"({"type": "torus", "major_radius": 1.3, "minor_radius": 0.5, "transform": {"translate": [0, 0, 0.4], "rotate": [50, 0, 0]}, "material": "m"})"));
    DiffCheck dc = checkDifferentials(s, true);
    EXPECT_GT(dc.checked, 50);
    EXPECT_LT(dc.worstP, 0.02);
    EXPECT_LT(dc.worstUv, 0.02);
    EXPECT_LT(dc.worstN, 0.02);
}

TEST(Determinism, OneAndTwoThreadsAreBitIdentical) {
    Scene s = loadScene(test::sourcePath("examples/demo.json"));
    s.render.width = 96;
    s.render.height = 54;
    s.render.spp = 4;
    s.render.tile = 16;
    RenderOptions one, two;
    one.threads = 1;
    two.threads = 2;
    RenderOutput a = renderScene(s, one);
    RenderOutput b = renderScene(s, two);
    expectSameBits(a.images, b.images);
    // A different seed changes the image (the seed is really used).
    s.render.seed = 12345;
    RenderOutput c = renderScene(s, one);
    EXPECT_NE(std::memcmp(a.images.aovs[0].pixels.data(), c.images.aovs[0].pixels.data(),
                          a.images.aovs[0].pixels.size() * sizeof(float)), 0);
}

// Issue 37: the batched camera stage (rows of camera rays traced as one Embree stream, hits shaded per material in one
// interpreter pass) computes what the pixel-by-pixel loop computes, bit for bit, for any thread count and tile size.
TEST(Determinism, BatchedCameraStageGivesTheSameBitsAsPixelByPixel) {
    std::vector<Scene> scenes;
    for (const char* path : {"examples/demo.json", "examples/anchor-sphere.json", "examples/cornell.json",
                             "examples/glass.json", "examples/metals.json", "examples/glint/env_sphere.json"})
        scenes.push_back(loadScene(test::sourcePath(path)));
    // A light the camera does not see in front of an emissive mesh and a GGX floor: the stream's first hit is the
    // invisible light, so the ray is traced on beyond it, and the emissive material's emission comes from the batch.
    scenes.push_back(sceneFrom(R"({"version": 1,
      "render": {"width": 40, "height": 30, "spp": 2, "integrator": "path", "max_depth": 3},
      "camera": {"position": [0, -4, 1], "look_at": [0, 0, 0.5], "fov": 50},
      "materials": {
        "metal": {"nodes": {"s": {"type": "bsdf.ggx", "inputs": {"roughness": 0.3}}}, "output": "@s.bsdf"},
        "glow": {"nodes": {"e": {"type": "bsdf.emission", "inputs": {"color": [2, 1, 0.5]}}}, "output": "@e.bsdf"}
      },
      "shapes": [
        {"type": "quad", "size": [4, 4], "material": "metal"},
        {"type": "sphere", "radius": 0.4, "transform": {"translate": [0.6, 0, 0.5]}, "material": "glow"}
      ],
      "lights": [
        {"type": "quad", "position": [0, -2, 0.8], "size": [1.5, 1.5], "look_at": [0, 0, 0.8], "radiance": 3,
         "visible": false, "two_sided": true}
      ]})"));
    for (size_t i = 0; i < scenes.size(); ++i) {
        SCOPED_TRACE("scene " + std::to_string(i));
        Scene& s = scenes[i];
        s.render.width = std::min(s.render.width, 72);
        s.render.height = std::min(s.render.height, 40);
        s.render.spp = std::min(s.render.spp, 3);
        s.render.tile = 16;
        RenderOptions scalar, batched, batchedTwo;
        scalar.batchedCameraHits = false;
        scalar.threads = batched.threads = 1;
        batchedTwo.threads = 2;
        RenderOutput a = renderScene(s, scalar);
        RenderOutput b = renderScene(s, batched);
        EXPECT_EQ(a.stats.batchedSamples, 0u);
        EXPECT_EQ(b.stats.batchedSamples, b.stats.samples);
        EXPECT_GT(b.stats.samples, 0u);
        expectSameBits(a.images, b.images);
        s.render.tile = 7;  // rows shorter than a stream chunk, tiles cut at the image's edge
        RenderOutput c = renderScene(s, batchedTwo);
        expectSameBits(a.images, c.images);
    }
}

TEST(Film, DiffuseAndSpecularAovsSumToBeauty) {
    Scene s = loadScene(test::sourcePath("examples/cornell.json"));
    s.render.width = 40;
    s.render.height = 40;
    s.render.spp = 8;
    RenderOutput r = renderScene(s);
    const auto* b = r.images.find("beauty");
    const auto* d = r.images.find("diffuse");
    const auto* sp = r.images.find("specular");
    // Only pixels that see the light itself carry emission; everywhere else beauty = diffuse + specular.
    int ok = 0;
    for (size_t i = 0; i < b->pixels.size(); ++i)
        ok += std::abs(b->pixels[i] - d->pixels[i] - sp->pixels[i]) <= 1e-4f * std::max(1.f, b->pixels[i]);
    EXPECT_GT(ok, int(b->pixels.size() * 0.97));
}

TEST(Film, GaussianFilterOfAStepEdgeIsTheNormalCdf) {
    // An emitter covering x > 0 seen head-on: with the Gaussian pixel filter (σ² = 1/(2π)) a pixel whose
    // centre is d pixels from the edge integrates to Φ(d/σ).
    Scene s = sceneFrom(R"({
        "render": {"width": 16, "height": 4, "spp": 4096, "filter": "gaussian"},
        "camera": {"position": [0, -10, 0], "look_at": [0, 0, 0], "fov": 10},
        "materials": {"glow": {"nodes": {"e": {"type": "bsdf.emission", "inputs": {"color": 1.0}}}, "output": "@e.bsdf"}},
        "shapes": [{"type": "quad", "size": [4, 4], "transform": {"translate": [2, 0, 0], "rotate": [90, 0, 0]}, "material": "glow"}]})");
    RenderOutput r = renderScene(s);
    const auto* b = r.images.find("beauty");
    const double sigma = std::sqrt(1.0 / (2.0 * M_PI));
    for (int x = 4; x < 12; ++x) {
        double d = (x + 0.5) - 8.0;
        double expected = 0.5 * std::erfc(-d / (sigma * std::sqrt(2.0)));
        double v = 0;
        for (int y = 0; y < 4; ++y) v += b->pixels[(size_t(y) * 16 + x) * 3] / 4.0;
        EXPECT_NEAR(v, expected, 0.012) << "column " << x;
    }
}

TEST(EnvironmentLight, ImportanceSamplingIsConsistentAndFollowsBlenderOrientation) {
    // 32x16 lat-long map: dim everywhere, one bright column at u = 0.5 (Blender: the -x direction).
    const int W = 32, H = 16;
    std::vector<float> rgb(size_t(W) * H * 3, 0.1f);
    for (int y = 0; y < H; ++y)
        for (int c = 0; c < 3; ++c) rgb[(size_t(y) * W + W / 2) * 3 + c] = 20.f;
    EnvironmentLight env(rgb, W, H, 0.f, Color3(1.f));
    EXPECT_NEAR(env.radiance(Vec3(-1, 0, 0), true).x, 20.f, 1e-5f);
    EXPECT_NEAR(env.radiance(Vec3(1, 0, 0), true).x, 0.1f, 1e-5f);
    // Rotating the map by 90° about z moves the bright column to -y.
    EnvironmentLight rotated(rgb, W, H, 90.f, Color3(1.f));
    EXPECT_NEAR(rotated.radiance(Vec3(0, -1, 0), true).x, 20.f, 1e-5f);

    // sample() returns the density pdf() reports, and ∫L dω by importance sampling matches uniform sampling.
    Rng rng{11};
    double isEst = 0, uniEst = 0;
    const int N = 200000;
    int rejected = 0;  // only where sin θ = 0 (the poles): measure zero
    for (int i = 0; i < N; ++i) {
        LightSample s;
        if (!env.sample(Vec3(0.f), rng.next2(), s)) {
            ++rejected;
            continue;
        }
        EXPECT_NEAR(s.pdf, env.pdf(Vec3(0.f), s.wi, 0.f), 1e-3f * s.pdf);
        EXPECT_NEAR(s.L.x, env.radiance(s.wi, true).x, 1e-4f);
        isEst += s.L.x / s.pdf;
        Vec3 w = sampleUniformSphere(rng.next2());
        uniEst += env.radiance(w, true).x * 4.0 * M_PI;
    }
    isEst /= N;
    uniEst /= N;
    EXPECT_LT(rejected, N / 10000);
    // Closed form: the bright column covers 1/32 of the azimuth over the whole sphere.
    double exact = 4.0 * M_PI * (0.1 * 31.0 / 32.0 + 20.0 / 32.0);
    EXPECT_NEAR(isEst, exact, 0.005 * exact);
    EXPECT_NEAR(uniEst, exact, 0.03 * exact);
}

namespace {

// A Lambert lobe with the closed-form polygon integral (Lambert's formula for the projected solid
// angle, polygon entirely above the horizon): ∫_P cos θ dω = ½ |Σ_i Θ_i (v̂_i × v̂_{i+1})/|…| · z|.
class AnalyticLambertLobe final : public BsdfLobe {
public:
    explicit AnalyticLambertLobe(const Color3& albedo) : lambert_(albedo), albedo_(albedo) {}
    LobeKind kind() const override { return LobeKind::Diffuse; }
    using BsdfLobe::sample;
    LobeValue evalPdf(const LobeQuery& q) const override { return lambert_.evalPdf(q); }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override { return lambert_.sample(q, u, wi); }
    Color3 albedo(const Vec3& wo) const override { return albedo_; }
    const char* modelName() const override { return "analytic_lambert"; }
    bool integratePolygon(const LobeQuery&, const Vec3* v, int n, Color3& result) const override {
        double sum = 0;
        for (int i = 0; i < n; ++i) {
            glm::dvec3 a = glm::normalize(glm::dvec3(v[i])), b = glm::normalize(glm::dvec3(v[(i + 1) % n]));
            double theta = std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
            sum += theta * glm::normalize(glm::cross(a, b)).z;
        }
        result = albedo_ * float(0.5 * std::abs(sum) / M_PI);
        return true;
    }

private:
    LambertLobe lambert_;
    Color3 albedo_;
};

class AnalyticLambertMaterial final : public Material {
public:
    void build(const ShadingPoint& sp, ScratchArena& arena, Closure& out, Color3* emission) const override {
        out.add(Color3(1.f), arena.make<AnalyticLambertLobe>(Color3(0.5f)), sp.frame);
    }
};

// GGX without a closed form over polygons (GgxLobe has its LTC): forwards everything but integratePolygon.
class SampledOnlyGgxLobe final : public BsdfLobe {
public:
    SampledOnlyGgxLobe(float alpha, const Fresnel& f) : ggx_(alpha, alpha, f) {}
    LobeKind kind() const override { return LobeKind::Specular; }
    using BsdfLobe::sample;
    LobeValue evalPdf(const LobeQuery& q) const override { return ggx_.evalPdf(q); }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override { return ggx_.sample(q, u, wi); }
    Color3 albedo(const Vec3& wo) const override { return ggx_.albedo(wo); }
    const char* modelName() const override { return "sampled_only_ggx"; }

private:
    GgxLobe ggx_;
};

// Analytic Lambert plus a sampled GGX lobe (no closed form): integratePolygon handles only the diffuse lobe.
class AnalyticLambertPlusGgxMaterial final : public Material {
public:
    void build(const ShadingPoint& sp, ScratchArena& arena, Closure& out, Color3* emission) const override {
        out.add(Color3(1.f), arena.make<AnalyticLambertLobe>(Color3(0.5f)), sp.frame);
        out.add(Color3(1.f), arena.make<SampledOnlyGgxLobe>(0.3f, Fresnel::schlick(Color3(0.5f))), sp.frame);
    }
};
class LambertPlusGgxMaterial final : public Material {
public:
    void build(const ShadingPoint& sp, ScratchArena& arena, Closure& out, Color3* emission) const override {
        out.add(Color3(1.f), arena.make<LambertLobe>(Color3(0.5f)), sp.frame);
        out.add(Color3(1.f), arena.make<GgxLobe>(0.3f, 0.3f, Fresnel::schlick(Color3(0.5f))), sp.frame);
    }
};

}  // namespace

TEST(PolygonLightHook, AnalyticIntegrationMatchesSampledQuadLight) {
    // A diffuse floor under a downward-facing quad light: the hook's closed form and light/BSDF sampling
    // with MIS must give the same image (no occluders, so one-point visibility is exact).
    const char* json = R"({
        "render": {"width": 48, "height": 36, "spp": 256, "integrator": "direct"},
        "camera": {"position": [0, -3, 2.5], "look_at": [0, 0, 0], "fov": 50},
        "materials": {"m": {"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": 0.5}}}, "output": "@d.bsdf"}},
        "shapes": [{"type": "quad", "size": [6, 6], "material": "m"}],
        "lights": [{"type": "quad", "position": [0.3, 0.2, 1.2], "look_at": [0.3, 0.2, 0], "size": [1.0, 0.6], "power": 40}]})";
    Scene sampled = sceneFrom(json);
    sampled.render.areaLights = AreaLightMode::Sampled;  // bsdf.diffuse has a closed form too: sample it here
    Scene analytic = sceneFrom(json);
    analytic.materials[0] = std::make_shared<AnalyticLambertMaterial>();
    RenderOutput a = renderScene(sampled), b = renderScene(analytic);
    const auto& pa = a.images.find("beauty")->pixels;
    const auto& pb = b.images.find("beauty")->pixels;
    double sa = 0, sb = 0, maxRel = 0;
    for (size_t i = 0; i < pa.size(); ++i) {
        sa += pa[i];
        sb += pb[i];
        if (pb[i] > 0.05f) maxRel = std::max(maxRel, std::abs(double(pa[i]) - pb[i]) / pb[i]);
    }
    ASSERT_GT(sb, 0.0);
    EXPECT_NEAR(sa / sb, 1.0, 0.01);
    EXPECT_LT(maxRel, 0.15);  // 256-spp sampling noise per pixel against the noise-free closed form
    // The closed form is noise free: at pixel centres, two seeds (different light samples) give the same image.
    analytic.render.spp = 1;
    analytic.render.pixelCenter = true;
    RenderOutput b1 = renderScene(analytic);
    const auto& pb1 = b1.images.find("beauty")->pixels;
    analytic.render.seed = 99;
    RenderOutput c = renderScene(analytic);
    const auto& pc = c.images.find("beauty")->pixels;
    double maxDiff = 0;
    for (size_t i = 0; i < pb1.size(); ++i) {
        maxDiff = std::max(maxDiff, double(std::abs(pb1[i] - pc[i])));
    }
    EXPECT_LT(maxDiff, 1e-5);
}

TEST(PolygonLightHook, PartlyAnalyticClosureMatchesSampledQuadLight) {
    // Diffuse (closed form) + GGX (none) under a quad light: integratePolygon handles the diffuse lobe only; the GGX
    // lobe goes through sampled NEE with MIS and BSDF-sampled hits of the light count only the GGX lobe. The image must
    // equal the fully sampled one up to noise, split by AOV.
    const char* json = R"({
        "render": {"width": 40, "height": 30, "spp": 512, "integrator": "direct"},
        "camera": {"position": [0, -3, 2.5], "look_at": [0, 0, 0], "fov": 50},
        "materials": {"m": {"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": 0.5}}}, "output": "@d.bsdf"}},
        "shapes": [{"type": "quad", "size": [6, 6], "material": "m"}],
        "lights": [{"type": "quad", "position": [0.3, 0.9, 1.2], "look_at": [0.3, 0.2, 0], "size": [1.0, 0.6], "power": 40}]})";
    Scene sampled = sceneFrom(json);
    sampled.render.areaLights = AreaLightMode::Sampled;
    Scene mixed = sceneFrom(json);
    sampled.materials[0] = std::make_shared<LambertPlusGgxMaterial>();
    mixed.materials[0] = std::make_shared<AnalyticLambertPlusGgxMaterial>();
    RenderOutput a = renderScene(sampled), b = renderScene(mixed);
    for (const char* aov : {"diffuse", "specular"}) {
        const auto& pa = a.images.find(aov)->pixels;
        const auto& pb = b.images.find(aov)->pixels;
        double sa = 0, sb = 0;
        for (size_t i = 0; i < pa.size(); ++i) sa += pa[i], sb += pb[i];
        ASSERT_GT(sb, 0.0) << aov;
        EXPECT_NEAR(sa / sb, 1.0, 0.02) << aov;
    }
}

TEST(ClosureQueries, RenamingEveryNodeGivesABitIdenticalImage) {
    // Frames live in the closure, one per lobe, so node ids (which order the graph walk) cannot change the image or
    // the normal AOV: diffuse on the geometric normal, GGX on a tilted normal, mixed, renamed in reverse order.
    auto scene = [](const std::string& d, const std::string& g, const std::string& mix) {
        return R"({"render": {"width": 32, "height": 24, "spp": 4, "integrator": "path", "max_depth": 3},
            "camera": {"position": [0, -3, 2], "look_at": [0, 0, 0.4], "fov": 40},
            "materials": {"m": {"nodes": {
                ")" + d + R"(": {"type": "bsdf.diffuse", "inputs": {"color": [0.6, 0.4, 0.3]}},
                ")" + g + R"(": {"type": "bsdf.ggx", "inputs": {"roughness": 0.3, "normal": [0.3, 0.1, 1.0]}},
                ")" + mix + R"(": {"type": "closure.mix", "inputs": {"a": "@)" + d + R"(.bsdf", "b": "@)" + g + R"(.bsdf", "t": 0.6}}},
              "output": "@)" + mix + R"(.bsdf"}},
            "shapes": [{"type": "sphere", "radius": 0.5, "transform": {"translate": [0, 0, 0.5]}, "material": "m"},
                       {"type": "quad", "size": [4, 4], "material": "m"}],
            "lights": [{"type": "point", "position": [1, -2, 3], "power": 300}, {"type": "environment", "color": [0.2, 0.2, 0.25]}]})";
    };
    RenderOutput a = renderScene(sceneFrom(scene("a_diffuse", "b_ggx", "c_mix")));
    RenderOutput b = renderScene(sceneFrom(scene("z_diffuse", "y_ggx", "x_mix")));
    for (const char* aov : {"beauty", "normal", "albedo"}) {
        const auto& pa = a.images.find(aov)->pixels;
        const auto& pb = b.images.find(aov)->pixels;
        ASSERT_EQ(pa.size(), pb.size());
        size_t differing = 0;
        for (size_t i = 0; i < pa.size(); ++i) differing += pa[i] != pb[i];
        EXPECT_EQ(differing, 0u) << aov;
    }
    // The normal AOV is the dominant lobe's unit normal, averaged over the pixel's 4 samples (the sphere fills the centre pixel).
    const auto& img = *a.images.find("normal");
    size_t c = (size_t(12) * 32 + 16) * size_t(img.channels());
    EXPECT_NEAR(glm::length(Vec3(img.pixels[c], img.pixels[c + 1], img.pixels[c + 2])), 1.f, 5e-3f);
}

// Secondary vertices borrow the camera's footprint (pbrt-v4's Approximate_dp_dxy): for a point seen directly it
// equals the camera ray differentials' dp/dx exactly (same pinhole geometry), and it grows linearly with distance.
TEST(SecondaryDifferentials, CameraApproximationMatchesPrimaryRayDifferentials) {
    Scene s = sceneFrom(diffScene(R"({"type": "quad", "size": [6, 6], "transform": {"rotate": [10, 0, 20]}, "material": "m"})"));
    PerspectiveCamera cam(s.camera, s.render.width, s.render.height);
    Accel accel(s);
    int checked = 0;
    for (int y = 4; y < s.render.height; y += 9)
        for (int x = 3; x < s.render.width; x += 11) {
            RayDifferential r = cam.generateRay(x + 0.5f, y + 0.5f, Vec2(0.5f));
            Hit h;
            if (!accel.intersect(r, h)) continue;
            ShadingPoint sp = accel.shadingPoint(r, h);
            ASSERT_TRUE(sp.hasDifferentials);
            Vec3 dx, dy;
            cam.approximateDpDxy(sp.p, sp.n, 1.f, dx, dy);
            EXPECT_LT(glm::length(dx - sp.dpdx), 1e-3f * glm::length(sp.dpdx)) << x << "," << y;
            EXPECT_LT(glm::length(dy - sp.dpdy), 1e-3f * glm::length(sp.dpdy)) << x << "," << y;
            ++checked;
        }
    EXPECT_GT(checked, 10);
    // Facing the camera on its axis at distance r: |dp/dx| = r * (image-plane pixel size at distance 1) * scale.
    Vec3 f = cam.forward(), p = cam.position() + 7.f * f, dx, dy;
    cam.approximateDpDxy(p, -f, 0.5f, dx, dy);
    Vec3 p2 = cam.position() + 14.f * f, dx2, dy2;
    cam.approximateDpDxy(p2, -f, 0.5f, dx2, dy2);
    EXPECT_NEAR(glm::length(dx2) / glm::length(dx), 2.f, 1e-4f);
    EXPECT_NEAR(glm::dot(dx, f), 0.f, 1e-6f);
}

namespace {
// Records the footprint every shading point at depth >= 1 receives (diffuse, so the path continues).
class FootprintProbe final : public Material {
public:
    mutable std::atomic<int> secondary{0}, withFootprint{0};
    void build(const ShadingPoint& sp, ScratchArena& arena, Closure& out, Color3* emission) const override {
        if (sp.depth >= 1) {
            ++secondary;
            if (sp.hasDifferentials && glm::length(sp.duvdx) > 0.f && glm::length(sp.dpdx) > 0.f) ++withFootprint;
        }
        out.add(Color3(1.f), arena.make<LambertLobe>(Color3(0.8f)), sp.frame);
    }
};
}  // namespace

TEST(SecondaryDifferentials, PathVerticesAfterTheFirstGetAFootprint) {
    Scene s = sceneFrom(R"({"render": {"width": 24, "height": 16, "spp": 2, "integrator": "path", "max_depth": 3},
        "camera": {"position": [0, -3, 2], "look_at": [0, 0, 0.4], "fov": 40},
        "materials": {"m": {"nodes": {"d": {"type": "bsdf.diffuse"}}, "output": "@d.bsdf"}},
        "shapes": [{"type": "sphere", "radius": 0.5, "transform": {"translate": [0, 0, 0.5]}, "material": "m"},
                   {"type": "quad", "size": [4, 4], "material": "m"}],
        "lights": [{"type": "environment", "color": [0.5, 0.5, 0.5]}]})");
    auto probe = std::make_shared<FootprintProbe>();
    s.materials[0] = probe;
    renderScene(s);
    EXPECT_GT(probe->secondary.load(), 50);
    EXPECT_EQ(probe->withFootprint.load(), probe->secondary.load());
}

namespace {
// Forwards to another material but claims to read differentials (Material::needsDerivatives), and counts the shading
// points that arrive with them.
class DerivativeClaim final : public Material {
public:
    explicit DerivativeClaim(std::shared_ptr<Material> inner) : inner_(std::move(inner)) {}
    mutable std::atomic<int> shaded{0}, withDifferentials{0};
    void build(const ShadingPoint& sp, ScratchArena& arena, Closure& out, Color3* emission) const override {
        ++shaded;
        if (sp.hasDifferentials) ++withDifferentials;
        inner_->shade(sp, arena, out, emission);
    }
    bool needsDerivatives() const override { return true; }

private:
    std::shared_ptr<Material> inner_;
};
}  // namespace

// Materials that read no differentials get shading points without them (issue 15): the closure, and so the image, is
// the same bits as with them; a material that asks for them still gets them at every vertex.
TEST(SecondaryDifferentials, SkippedOnlyForMaterialsThatReadNone) {
    Scene s = loadScene(test::sourcePath("examples/anchor-sphere.json"));
    s.render.width = 64;
    s.render.height = 48;
    s.render.spp = 4;
    for (const auto& m : s.materials) EXPECT_FALSE(m->needsDerivatives()) << m->name();
    RenderOutput skipped = renderScene(s);
    std::vector<std::shared_ptr<DerivativeClaim>> claims;
    for (auto& m : s.materials) {
        claims.push_back(std::make_shared<DerivativeClaim>(m));
        m = claims.back();
    }
    RenderOutput built = renderScene(s);
    expectSameBits(skipped.images, built.images);
    int shaded = 0;
    for (const auto& c : claims) {
        shaded += c->shaded.load();
        EXPECT_EQ(c->withDifferentials.load(), c->shaded.load()) << c->name();
    }
    EXPECT_GT(shaded, 64 * 48 * 4 / 2);  // camera hits (a few rays miss) and their bounces

    // The shading point itself: the same geometry with and without derivatives, on an analytic sphere and a quad.
    Accel accel(s);
    PerspectiveCamera cam(s.camera, s.render.width, s.render.height);
    int compared = 0;
    for (int y = 0; y < s.render.height; y += 3)
        for (int x = 0; x < s.render.width; x += 3) {
            RayDifferential r = cam.generateRay(x + 0.5f, y + 0.5f, Vec2(0.5f));
            Hit h;
            if (!accel.intersect(r, h)) continue;
            ShadingPoint with = accel.shadingPoint(r, h, true), without = accel.shadingPoint(r, h, false);
            EXPECT_TRUE(with.hasDifferentials);
            EXPECT_FALSE(without.hasDifferentials);
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(with.p[c], without.p[c]);
                EXPECT_EQ(with.n[c], without.n[c]);
                EXPECT_EQ(with.ng[c], without.ng[c]);
                EXPECT_EQ(with.dpdu[c], without.dpdu[c]);
                EXPECT_EQ(with.frame.t[c], without.frame.t[c]);
                EXPECT_EQ(with.tangent[c], without.tangent[c]);
            }
            EXPECT_EQ(with.uv, without.uv);
            ++compared;
        }
    EXPECT_GT(compared, 100);
}
