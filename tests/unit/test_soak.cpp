// Soak (issue 16 item 6): 1,000 consecutive renders of small random valid scenes through the public API in one
// process. Every scene must load and render; resident memory after the last render must not exceed the memory after
// the warm-up (first 100 renders: caches, the texture system, TBB's pools) by more than a small slack. Under the
// sanitizer job (ASan's leak checker) the same test proves that nothing leaks.
#include "specula/specula.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstdlib>
#include <fstream>
#include <random>
#include <unistd.h>

namespace sp = specula::api;
using nlohmann::json;

namespace {

double residentMiB() {
    std::ifstream in("/proc/self/statm");
    long pages = 0, resident = 0;
    in >> pages >> resident;
    return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// A random valid scene: 1-4 shapes of every built-in type, 1-3 graph materials from the main BSDF families, a point
// or quad light and sometimes a constant environment; 16x12 pixels, 1-4 spp.
std::string randomScene(std::mt19937& rng) {
    auto u = [&](float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); };
    auto pick = [&](int n) { return int(std::uniform_int_distribution<int>(0, n - 1)(rng)); };
    json materials = json::object();
    const int nMat = 1 + pick(3);
    for (int m = 0; m < nMat; ++m) {
        json node;
        switch (pick(5)) {
            case 0: node = {{"type", "bsdf.diffuse"}, {"inputs", {{"color", {u(0, 1), u(0, 1), u(0, 1)}}}}}; break;
            case 1: node = {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", u(0.05f, 1.f)}, {"anisotropy", u(0, 1)}}}}; break;
            case 2: node = {{"type", "bsdf.ggx_filtered"}, {"inputs", {{"alpha", {u(0.05f, 0.8f), u(0.05f, 0.8f)}}}}}; break;
            case 3: node = {{"type", "bsdf.glint"}, {"inputs", {{"sigma_x", u(0.1f, 0.5f)}, {"sigma_y", u(0.1f, 0.5f)}}}}; break;
            default: node = {{"type", "bsdf.emission"}, {"inputs", {{"strength", u(0.1f, 4.f)}}}}; break;
        }
        materials["m" + std::to_string(m)] = {{"nodes", {{"b", node}}}, {"output", "@b.bsdf"}};
    }
    static const char* kShapes[] = {"sphere", "quad", "disk", "cylinder", "torus"};
    json shapes = json::array();
    const int nShapes = 1 + pick(4);
    for (int s = 0; s < nShapes; ++s) {
        json shape = {{"type", kShapes[pick(5)]}, {"material", "m" + std::to_string(pick(nMat))},
                      {"transform", {{"translate", {u(-1, 1), u(-1, 1), u(0, 1)}}, {"rotate", {u(-90, 90), u(-90, 90), 0}}}}};
        shapes.push_back(shape);
    }
    json lights = json::array();
    if (pick(2))
        lights.push_back({{"type", "point"}, {"position", {u(-3, 3), u(-3, 3), u(2, 4)}}, {"power", u(50, 500)}});
    else
        lights.push_back({{"type", "quad"}, {"position", {u(-2, 2), u(-3, -1), u(2, 4)}}, {"look_at", {0, 0, 0.5}},
                          {"size", {u(0.5f, 2), u(0.5f, 2)}}, {"power", u(50, 500)}});
    if (pick(2)) lights.push_back({{"type", "environment"}, {"strength", u(0.1f, 1.f)}});
    json scene = {{"render", {{"width", 16}, {"height", 12}, {"spp", 1 + pick(4)}, {"seed", pick(1000)}}},
                  {"camera", {{"position", {u(-1, 1), -4, u(0.5f, 2)}}, {"look_at", {0, 0, 0.5}}}},
                  {"materials", materials}, {"shapes", shapes}, {"lights", lights}};
    return scene.dump();
}

}  // namespace

TEST(Soak, ThousandRandomScenesRenderWithFlatMemory) {
    std::mt19937 rng(20261203);
    double warm = 0;
    const double first = residentMiB();
    for (int i = 0; i < 1000; ++i) {
        const std::string text = randomScene(rng);
        sp::RenderResult r;
        try {
            r = sp::Scene::fromString(text).render();
        } catch (const std::exception& e) {
            FAIL() << "scene " << i << " did not render: " << e.what() << "\n" << text;
        }
        ASSERT_EQ(r.width(), 16);
        sp::AovView b = r.aov("beauty");
        for (size_t k = 0; k < size_t(b.width) * b.height * 3; ++k) ASSERT_TRUE(std::isfinite(b.pixels[k])) << i;
        if (i == 99) warm = residentMiB();
        if (std::getenv("SPECULA_SOAK_TRACE") && i % 100 == 99) std::printf("soak: %d renders, %.1f MiB\n", i + 1, residentMiB());
        if (std::getenv("SPECULA_SOAK_TRACE") && i % 100 == 99) std::printf("soak: %d renders, %.1f MiB\n", i + 1, residentMiB());
    }
    const double last = residentMiB();
    std::printf("soak: resident memory %.1f MiB before, %.1f MiB after 100 renders, %.1f MiB after 1000\n", first, warm, last);
    ::testing::Test::RecordProperty("rss_first_mib", std::to_string(first));
    ::testing::Test::RecordProperty("rss_warm_mib", std::to_string(warm));
    ::testing::Test::RecordProperty("rss_last_mib", std::to_string(last));
#ifdef SPECULA_SANITIZED
    // ASan holds freed memory in its quarantine (256 MiB) and caches: resident memory says nothing there; LeakSanitizer
    // checks for leaks when the process ends.
    (void)first;
#else
    EXPECT_LT(last - warm, 16.0) << "resident memory grew from " << warm << " MiB to " << last << " MiB over 900 renders";
#endif
}
