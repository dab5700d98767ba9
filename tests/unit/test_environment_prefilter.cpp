// The split-sum environment of the raster integrator and the GPU preview (core/render/environment_prefilter.h):
// closed forms (constant maps, the irradiance of a linear environment), the convolution against independent Monte
// Carlo, GL's bilinear conventions, thread-count determinism, and the closure's split sum in a white furnace.
#include "core/ltc/ltc.h"
#include "core/ltc/ltc_tables.h"
#include "core/render/bsdf.h"
#include "core/render/environment_prefilter.h"
#include "core/render/lobes/ggx.h"
#include "core/render/lobes/lambert.h"
#include "core/render/sampler.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cstring>
#include <functional>

using namespace specula;

namespace {

// A lat-long map of width × height whose texel (x, y) holds f(direction at its centre), as a raster light.
struct TestMap {
    std::vector<float> rgb;
    RasterLight light;
    TestMap(int width, int height, float rotation, const std::function<Color3(const Vec3&)>& f) {
        rgb.resize(size_t(width) * height * 3);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                // EnvironmentLight::uvToDir without the turn (the map is defined in its own frame)
                float a = (0.5f - (x + 0.5f) / width) * 2.f * kPi, theta = (y + 0.5f) / height * kPi;
                Color3 c = f(Vec3(-std::cos(a) * std::sin(theta), std::sin(a) * std::sin(theta), std::cos(theta)));
                for (int k = 0; k < 3; ++k) rgb[(size_t(y) * width + x) * 3 + size_t(k)] = c[k];
            }
        light.kind = RasterLight::Kind::Environment;
        light.hasMap = true;
        light.map = rgb.data();
        light.mapWidth = width;
        light.mapHeight = height;
        light.mapRotation = rotation;
        light.mapScale = Color3(1.f);
    }
};

Vec3 unturn(const Vec3& d, float rotation) {  // world direction -> the map's own frame
    float c = std::cos(rotation), s = std::sin(rotation);
    return {c * d.x + s * d.y, -s * d.x + c * d.y, d.z};
}

uint64_t mixBits(uint64_t x) {
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33;
    return x;
}
float uniform(uint64_t& s) { return float(mixBits(++s) >> 40) * (1.f / 16777216.f); }

}  // namespace

TEST(EnvironmentPrefilter, ConstantEnvironmentsGiveTheConstantAtEveryRoughness) {
    RasterLight constant;
    constant.kind = RasterLight::Kind::Environment;
    constant.value = Color3(0.3f, 0.6f, 0.9f);
    PrefilteredEnvironment c = prefilterEnvironment(constant);
    EXPECT_FALSE(c.hasMap);
    EXPECT_EQ(c.lookup(Vec3(0, 0, 1), 0.4f), constant.value);
    EXPECT_EQ(c.lookup(Vec3(1, 0, 0), -1.f), constant.value);

    TestMap m(200, 100, 0.7f, [](const Vec3&) { return Color3(2.f, 1.f, 0.5f); });
    PrefilteredEnvironment p = prefilterEnvironment(m.light);
    ASSERT_TRUE(p.hasMap);
    ASSERT_EQ(p.levels.size(), size_t(kEnvironmentLevels));
    EXPECT_EQ(p.levels[0].width, 128);  // 200 rounded down to a power of two
    EXPECT_EQ(p.levels[0].height, 64);
    EXPECT_EQ(p.levels[5].width, 4);
    EXPECT_EQ(p.levels[5].height, 2);
    uint64_t s = 1;
    for (int i = 0; i < 200; ++i) {
        Vec3 d = glm::normalize(Vec3(uniform(s), uniform(s), uniform(s)) - 0.5f);
        for (float alpha : {-1.f, 0.f, 0.13f, 0.5f, 0.99f, 1.f}) {
            Color3 v = p.lookup(d, alpha);
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(v[k], m.rgb[size_t(k)], 2e-6f * m.rgb[size_t(k)]) << alpha;
        }
    }
}

// E(n)/π of L(l) = a + b·l is a + (2/3) b·n: ∫_{n·l>0} (b·l)(n·l) dl = (2π/3) b·n.
TEST(EnvironmentPrefilter, IrradianceOfALinearEnvironmentIsItsClosedForm) {
    const Vec3 b(0.3f, -0.2f, 0.4f);
    const float rotation = 1.1f;
    TestMap m(256, 128, rotation, [&](const Vec3& d) { return Color3(1.f + glm::dot(b, d)); });
    PrefilteredEnvironment p = prefilterEnvironment(m.light);
    double worst = 0;
    for (int y = 0; y < p.irradiance.height; ++y)
        for (int x = 0; x < p.irradiance.width; ++x) {
            // at texel centres, where the bilinear read is the texel itself
            Vec2 uv((x + 0.5f) / p.irradiance.width, (y + 0.5f) / p.irradiance.height);
            float a = (0.5f - uv.x) * 2.f * kPi, theta = uv.y * kPi;
            Vec3 own(-std::cos(a) * std::sin(theta), std::sin(a) * std::sin(theta), std::cos(theta));
            Vec3 world(std::cos(rotation) * own.x - std::sin(rotation) * own.y,
                       std::sin(rotation) * own.x + std::cos(rotation) * own.y, own.z);
            float got = p.lookup(world, -1.f).x;
            float want = 1.f + 2.f / 3.f * glm::dot(b, own);
            worst = std::max(worst, double(std::abs(got - want)));
        }
    // the 128×64 source's quadrature of a smooth integrand
    EXPECT_LT(worst, 2e-3);
}

// At α = 1 the GGX reflected lobe for N = V = R is uniform over the sphere of l (D constant), so the top level is the
// cosine-weighted mean about R, as the irradiance map: for a quadratic environment its closed form from the cosine
// lobe's moments, E[l] = (2/3) n and E[l lᵀ] = (I + n nᵀ)/4.
TEST(EnvironmentPrefilter, RoughestLevelIsTheCosineMeanInClosedForm) {
    auto f = [](const Vec3& d) { return Color3(1.f + 0.8f * d.x * d.x + 0.5f * d.z, 0.5f, 0.2f + d.z * d.z); };
    const float rotation = -0.4f;
    TestMap m(512, 256, rotation, f);
    PrefilteredEnvironment p = prefilterEnvironment(m.light);
    const EnvironmentImage& img = p.levels.back();
    double worst = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            Vec2 uv((x + 0.5f) / img.width, (y + 0.5f) / img.height);
            float a = (0.5f - uv.x) * 2.f * kPi, theta = uv.y * kPi;
            Vec3 n(-std::cos(a) * std::sin(theta), std::sin(a) * std::sin(theta), std::cos(theta));  // map frame
            Vec3 world(std::cos(rotation) * n.x - std::sin(rotation) * n.y,
                       std::sin(rotation) * n.x + std::cos(rotation) * n.y, n.z);
            Color3 got = p.lookup(world, 1.f);
            double want0 = 1.0 + 0.8 * (0.25 + 0.25 * n.x * n.x) + 0.5 * (2.0 / 3.0) * n.z;
            double want2 = 0.2 + 0.25 + 0.25 * n.z * n.z;
            worst = std::max({worst, std::abs(got.x - want0) / want0, std::abs(got.z - want2) / want2});
        }
    EXPECT_LT(worst, 3e-3);
}

// GL_LINEAR with GL_REPEAT in u and GL_CLAMP_TO_EDGE in v: texel centres read the texel, u wraps across the seam.
TEST(EnvironmentPrefilter, BilinearReadFollowsGlConventions) {
    EnvironmentImage img{4, 2, {}};
    for (int i = 0; i < 8; ++i)
        for (int c = 0; c < 3; ++c) img.rgb.push_back(float(i) + 0.1f * c);
    EXPECT_FLOAT_EQ(sampleBilinear(img, {0.375f, 0.25f}).x, 1.f);
    EXPECT_FLOAT_EQ(sampleBilinear(img, {0.625f, 0.75f}).x, 6.f);
    EXPECT_FLOAT_EQ(sampleBilinear(img, {0.f, 0.25f}).x, 0.5f * (3.f + 0.f));  // halfway between texel 3 and texel 0
    EXPECT_FLOAT_EQ(sampleBilinear(img, {1.f, 0.25f}).x, 1.5f);
    EXPECT_FLOAT_EQ(sampleBilinear(img, {0.125f, 0.f}).x, 0.f);  // v clamps to the top row
    EXPECT_FLOAT_EQ(sampleBilinear(img, {0.125f, 0.5f}).x, 2.f);  // between rows 0 and 1: (0 + 4)/2
    // the direction convention is EnvironmentLight's: +z is v = 0, u = 0.5 looks along −x (before the turn)
    EXPECT_NEAR(environmentUv(Vec3(0, 0, 1), 0.f).y, 0.f, 1e-6f);
    EXPECT_NEAR(environmentUv(Vec3(-1, 0, 0), 0.f).x, 0.5f, 1e-6f);
    EXPECT_NEAR(environmentUv(unturn(Vec3(-1, 0, 0), -0.3f), 0.3f).x, 0.5f, 1e-6f);
}

TEST(EnvironmentPrefilter, SameBitsForAnyThreadCount) {
    TestMap m(256, 128, 0.2f, [](const Vec3& d) { return Color3(std::exp(4.f * d.x), 1.f + d.y, d.z * d.z); });
    PrefilteredEnvironment many = prefilterEnvironment(m.light), one;
    tbb::task_arena(1).execute([&] { one = prefilterEnvironment(m.light); });
    ASSERT_EQ(many.levels.size(), one.levels.size());
    for (size_t k = 0; k < many.levels.size(); ++k)
        EXPECT_EQ(0, std::memcmp(many.levels[k].rgb.data(), one.levels[k].rgb.data(), many.levels[k].rgb.size() * 4)) << k;
    EXPECT_EQ(0, std::memcmp(many.irradiance.rgb.data(), one.irradiance.rgb.data(), many.irradiance.rgb.size() * 4));
}

// The LTC lookup of a GGX lobe seen head-on: the mirror direction and (the LTC's peak density being that of the GGX
// reflected lobe) about the lobe's own α; at a grazing view the lookup turns to the other side of the normal.
TEST(EnvironmentPrefilter, GgxLtcLookupIsTheMirrorDirectionAndItsRoughness) {
    const ltc::LtcTables& t = ltc::builtinTables();
    for (float alpha : {0.05f, 0.2f, 0.5f}) {
        Vec3 dir;
        float a;
        ltc::environmentLookup(ltc::ggxIsotropic(t, alpha, Vec3(0, 0, 1)), dir, a);
        EXPECT_NEAR(dir.z, 1.f, 1e-3f) << alpha;
        EXPECT_NEAR(a, alpha, 0.2f * alpha) << alpha;  // measured 0.0496, 0.193, 0.419
        Vec3 wo = glm::normalize(Vec3(0.8f, 0.f, 0.6f));
        Vec3 dirG;
        float aG;
        ltc::environmentLookup(ltc::ggxIsotropic(t, alpha, wo), dirG, aG);
        EXPECT_LT(dirG.x, 0.f) << alpha;  // reflected to the other side of the normal
        EXPECT_GT(aG, 0.f) << alpha;
    }
}

// White furnace: in a constant environment the split sum is each lobe's hemisphere integral times the constant.
TEST(EnvironmentPrefilter, ClosureSplitSumInAConstantEnvironmentIsTheHemisphereIntegral) {
    LambertLobe diffuse(Color3(0.5f, 0.4f, 0.3f));
    GgxLobe specular(0.3f, 0.2f, Fresnel::schlick(Color3(0.04f)));
    Closure c;
    c.add(Color3(0.8f), &diffuse, Frame::fromNormal(Vec3(0, 0, 1)));
    c.add(Color3(1.f), &specular, Frame::fromNormal(glm::normalize(Vec3(0.1f, 0, 1))));
    RasterLight constant;
    constant.kind = RasterLight::Kind::Environment;
    constant.value = Color3(1.5f);
    PrefilteredEnvironment env = prefilterEnvironment(constant);
    BsdfQuery q;
    q.wo = glm::normalize(Vec3(0.3f, 0.2f, 1.f));
    const float eps = 0.01f;
    Vec3 hemi[4] = {glm::normalize(Vec3(1, 0, eps)), glm::normalize(Vec3(0, 1, eps)), glm::normalize(Vec3(-1, 0, eps)),
                    glm::normalize(Vec3(0, -1, eps))};
    BsdfEval split, integral;
    EXPECT_EQ(c.integrateEnvironment(q, hemi, 4, [&](const Vec3& d, float a) { return env.lookup(d, a); }, split),
              c.allLobes());
    c.integratePolygon(q, hemi, 4, integral);
    for (int k = 0; k < 3; ++k) {
        EXPECT_FLOAT_EQ(split.diffuse[k], integral.diffuse[k] * 1.5f);
        EXPECT_FLOAT_EQ(split.specular[k], integral.specular[k] * 1.5f);
    }
    EXPECT_GT(integral.diffuse.x, 0.3f);  // ≈ 0.8·0.5 less the lifted hemisphere's small gap
}
