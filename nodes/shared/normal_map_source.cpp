// loadNormalMapSource: files through the texture store ("raw": normal maps are data), generated maps in memory.
#include "nodes/shared/normal_map_source.h"

#include "core/graph/graph_material.h"
#include "core/texture/normal_map_gen.h"
#include "core/texture/texture_store.h"
#include "core/util/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace specula::nodes {
namespace {

// A generated map encoded as an RGB float image in file row order, without a texture store (codegen-only loads).
void generate(const std::string& name, int maxSide, NormalMapSource& out) {
    const NormalMap m = generateNormalMapFromName(name, maxSide);
    out.width = out.height = m.size;
    out.channels = 3;
    out.encoded = encodeNormalMapRgb(m);
}

}  // namespace

std::string resolveTexturePath(const graph::PrepareContext& pc, const std::string& file) {
    if (isGeneratedNormalMapName(file) || !pc.load || pc.load->baseDir.empty()) return file;
    std::filesystem::path p(file);
    return p.is_relative() ? (std::filesystem::path(pc.load->baseDir) / p).string() : file;
}

void throwTextureLoadError(const std::string& pointer, const std::string& path, const std::string& message,
                           const std::exception& cause) {
    std::error_code ec;
    const bool exists = !isGeneratedNormalMapName(path) && std::filesystem::exists(path, ec);
    if (!exists || dynamic_cast<const TextureInputError*>(&cause)) throw InputError(pointer, message);
    throw Error(ErrorCode::Io, pointer, message);
}

NormalMapSource loadNormalMapSource(const graph::PrepareContext& pc, const std::string& port, const char* node,
                                    bool directx, const NormalMapChecks& checks) {
    const std::string& file = pc.str(port);
    const std::string& pointer = pc.pointer(port);
    NormalMapSource src;
    src.name = file;
    const std::string what = std::string(node) + ": normal map '" + file + "'";
    try {
        if (isGeneratedNormalMapName(file)) {
            generate(file, pc.load && pc.load->textures ? pc.load->textures->maxSide() : 8192, src);
        } else {
            if (!pc.load || !pc.load->textures)
                throw InputError(pointer, std::string(node) + " needs a texture store (none was given to the graph loader)");
            TextureStore& store = *pc.load->textures;
            const TextureHandle h = store.load(resolveTexturePath(pc, file), "raw");
            src.width = store.width(h);
            src.height = store.height(h);
            src.channels = store.channels(h);
            src.encoded = store.pixels(h);
        }
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throwTextureLoadError(pointer, resolveTexturePath(pc, file), what + ": cannot load: " + e.what(), e);
    }
    if (src.channels < 2 || src.channels > 4)
        throw InputError(pointer, what + " has " + std::to_string(src.channels) +
                                      " channel(s); a tangent-space normal map has 2 (RG, z reconstructed), 3 or 4");
    const int w = src.width, h = src.height, nc = src.channels;
    src.normals.resize(size_t(w) * h);
    size_t bad = 0, firstBad = size_t(-1);
    float firstLength = 0.f;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float* px = &src.encoded[(size_t(h - 1 - y) * w + x) * nc];  // row 0 of the result = bottom row
            Vec3 n(2.f * px[0] - 1.f, 2.f * px[1] - 1.f, 0.f);
            const float xy2 = n.x * n.x + n.y * n.y;
            n.z = nc >= 3 ? 2.f * px[2] - 1.f : std::sqrt(std::max(0.f, 1.f - xy2));
            if (directx) n.y = -n.y;
            // Two channels: z is reconstructed, so only |(x, y)| > 1 makes the vector non-unit.
            const float len = nc >= 3 ? glm::length(n) : std::max(1.f, std::sqrt(xy2));
            if (checks.requireUnitLength && !(std::abs(len - 1.f) <= checks.lengthTolerance)) {
                if (bad++ == 0) firstBad = size_t(h - 1 - y) * w + x, firstLength = len;
            }
            if (checks.normalise && len > 0.f && std::isfinite(len)) n /= glm::length(n);
            src.normals[size_t(y) * w + x] = n;
        }
    if (checks.requireUnitLength && double(bad) > double(checks.maxBadFraction) * double(w) * h) {
        char msg[256];
        std::snprintf(msg, sizeof msg,
                      " is not a tangent-space normal map: %.1f%% of its texels decode to vectors whose length is off "
                      "1 by more than %.2g (first: pixel (%zu, %zu), length %.3g); expected colour = (n + 1)/2",
                      100.0 * double(bad) / (double(w) * h), double(checks.lengthTolerance), firstBad % size_t(w),
                      firstBad / size_t(w), double(firstLength));
        throw InputError(pointer, what + msg);
    }
    return src;
}

}  // namespace specula::nodes
