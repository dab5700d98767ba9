// libFuzzer target: a glTF file imported as a scene (core/scene/gltf_scene.h, issue 35) with its external files, then
// loaded and rendered tiny (16x12, 1 spp, one thread), as `specula render model.gltf` would.
//
// Input: the first byte's bit 0 picks .gltf (0) or .glb (1); the rest is split at kSeparator into up to three files in
// an empty scratch folder: the scene ("scene.gltf" / "scene.glb"), "buffer.bin" and "image.png", the names the seeds
// (fuzz/make_corpus.py) use in their buffer and image URIs. Only specula::Error may leave; anything else or a crash is a
// finding.
#include "core/render/renderer.h"
#include "core/scene/scene_loader.h"
#include "core/util/cache_dir.h"
#include "core/util/error.h"
#include "fuzz/fuzz_common.h"

#include <cstdlib>
#include <filesystem>
#include <string_view>

using namespace specula;

namespace {

constexpr std::string_view kSeparator = "\n--8<--\n";

// The texture cache folder whose "gltf-images" this target empties after each input: fuzz/run.sh's
// $SPECULA_CACHE_DIR, or one of this process's own (never the user's ~/.cache).
bool ownCacheFolder() {
    const char* set = std::getenv("SPECULA_CACHE_DIR");
    if (!set || !*set) ::setenv("SPECULA_CACHE_DIR", (fuzz::scratchDir() + "-cache").c_str(), 1);
    return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const bool cacheReady = ownCacheFolder();
    (void)cacheReady;
    if (size < 1) return 0;
    fuzz::clearScratch();
    const bool binary = data[0] & 1;
    const std::string_view input(reinterpret_cast<const char*>(data + 1), size - 1);
    const char* names[] = {binary ? "scene.glb" : "scene.gltf", "buffer.bin", "image.png"};
    std::string scenePath;
    size_t begin = 0;
    for (int part = 0; part < 3 && begin <= input.size(); ++part) {
        size_t end = part < 2 ? input.find(kSeparator, begin) : std::string_view::npos;
        if (end == std::string_view::npos) end = input.size();
        const std::string path = fuzz::writeScratch(names[part], data + 1 + begin, end - begin);
        if (part == 0) scenePath = path;
        begin = end + kSeparator.size();
    }
    fuzz::loadAndRenderTiny([&](const SceneOverrides& ov) { return loadScene(scenePath, ov); });
    // Embedded images are written to the texture cache, named by content: every mutant would add one.
    std::error_code ec;
    std::filesystem::remove_all(cacheFolder("gltf-images"), ec);
    return 0;
}
