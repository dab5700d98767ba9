// Shared pieces of the libFuzzer targets (fuzz_common.h).
#include "fuzz/fuzz_common.h"

#include "core/render/renderer.h"
#include "core/util/error.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace specula::fuzz {

const std::string& scratchDir() {
    static const std::string dir = [] {
        const char* tmp = std::getenv("TMPDIR");
        std::string d = std::string(tmp && *tmp ? tmp : "/tmp") + "/specula-fuzz-" + std::to_string(::getpid());
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}

void clearScratch() {
    std::error_code ec;
    for (auto& e : std::filesystem::directory_iterator(scratchDir(), ec)) std::filesystem::remove_all(e.path(), ec);
}

void loadAndRenderTiny(const std::function<Scene(const SceneOverrides&)>& load) {
    SceneOverrides ov;
    ov.width = 16;
    ov.height = 12;
    ov.spp = 1;
    ov.limits.maxTextureSide = kFuzzTextureSide;
    try {
        Scene scene = load(ov);
        RenderOptions ro;
        ro.threads = 1;
        (void)renderScene(scene, ro);
    } catch (const Error&) {
    }
}

std::string writeScratch(const std::string& name, const uint8_t* data, size_t size) {
    std::string path = scratchDir() + "/" + name;
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), std::streamsize(size));
    return path;
}

bool parseJson(const uint8_t* data, size_t size, nlohmann::json& out) {
    try {
        out = nlohmann::json::parse(data, data + size);
        return true;
    } catch (const nlohmann::json::exception&) {
        // parse_error and also out_of_range (406: a number such as 1e777777 that overflows a double); the product's
        // loaders catch the base class too (scene_loader.cpp parseJson).
        return false;
    }
}

ShadingPoint fuzzShadingPoint() {
    ShadingPoint sp;
    sp.p = Vec3(0.3f, -0.2f, 0.93f);
    sp.n = sp.ng = glm::normalize(sp.p);
    sp.tangent = Vec4(glm::normalize(glm::cross(Vec3(0, 0, 1), sp.n)), 1.f);
    sp.frame = Frame::fromNormalTangent(sp.n, Vec3(sp.tangent));
    sp.uv = Vec2(0.37f, 0.61f);
    sp.wo = glm::normalize(Vec3(0.1f, -0.4f, 1.f));
    sp.dpdu = Vec3(sp.tangent);
    sp.dpdv = glm::cross(sp.n, Vec3(sp.tangent));
    sp.hasDifferentials = true;
    sp.dpdx = Vec3(0.004f, 0.f, 0.001f);
    sp.dpdy = Vec3(0.f, 0.004f, -0.001f);
    sp.duvdx = Vec2(0.002f, 0.f);
    sp.duvdy = Vec2(0.f, 0.002f);
    sp.dndx = Vec3(0.01f, 0.002f, 0.f);
    sp.dndy = Vec3(-0.001f, 0.012f, 0.f);
    sp.dwodx = Vec3(0.002f, 0.0005f, -0.0003f);
    sp.dwody = Vec3(-0.0004f, 0.0021f, 0.0001f);
    return sp;
}

}  // namespace specula::fuzz
