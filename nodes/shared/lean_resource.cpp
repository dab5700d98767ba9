// leanMomentImage and the process-wide LEAN pyramid cache.
#include "nodes/shared/lean_resource.h"

#include <map>
#include <mutex>

namespace specula::nodes {

graph::ResourceImage leanMomentImage(const LeanPyramid& P) {
    graph::ResourceImage r;
    for (int l = 0; l < P.glslLevels(); ++l) {
        graph::ResourceImage::Level lv;
        P.glslLevelSize(l, lv.width, lv.height);
        lv.rgba = P.glslPackedLevel(l);
        r.levels.push_back(std::move(lv));
    }
    r.minFilter = "nearest_mipmap_nearest";
    r.magFilter = "nearest";
    r.wrapS = r.wrapT = "clamp_to_edge";
    return r;
}

std::shared_ptr<const LeanPyramid> sharedLeanPyramid(const std::vector<float>& px, int w, int h, int c) {
    uint64_t hash = 0xcbf29ce484222325ULL;  // FNV-1a 64
    auto mixIn = [&](const void* p, size_t n) {
        const unsigned char* b = static_cast<const unsigned char*>(p);
        for (size_t i = 0; i < n; ++i) hash = (hash ^ b[i]) * 0x100000001b3ULL;
    };
    int dims[3] = {w, h, c};
    mixIn(dims, sizeof dims);
    mixIn(px.data(), px.size() * sizeof(float));
    static std::mutex mutex;
    static std::map<uint64_t, std::weak_ptr<const LeanPyramid>> cache;
    std::lock_guard<std::mutex> lock(mutex);
    if (auto p = cache[hash].lock()) return p;
    auto p = std::make_shared<const LeanPyramid>(LeanPyramid::fromEncodedPixels(px.data(), w, h, c, false));
    cache[hash] = p;
    return p;
}

}  // namespace specula::nodes
