// The OpenImageIO module (libspecula_io.so): every function of core/io/image_io.h,
// core/texture/texture_store.h and core/texture/normal_map_gen.h is defined twice: for real in the module
// (built from those .cpp files unchanged, linked with OpenImageIO) and as a forwarding stub in libspecula
// (core/io_module/io_module.cpp). The first call of a stub dlopens the module next to libspecula (thread-safe,
// once) and fetches this table; programs that never touch an image never load OpenImageIO (start-up time,
// issue 9 item 8). Internal to libspecula: not part of the public API.
#pragma once

#include "core/io/image_io.h"
#include "core/texture/normal_map_gen.h"
#include "core/texture/texture_store.h"

#include <memory>
#include <string>

namespace specula::io_module {

constexpr int kAbiVersion = 2;

struct Table {
    int abiVersion = kAbiVersion;
    // core/io/image_io.h
    const AovBuffer* (*imageSetFind)(const ImageSet&, const std::string&);
    void (*writeExr)(const std::string&, const ImageSet&, const ColorConfig&);
    void (*writePng)(const std::string&, const ImageSet&, const ColorConfig&, const std::string&, float);
    ImageSet (*readImageSet)(const std::string&, int64_t);
    CompareResult (*compareImages)(const std::string&, const std::string&, const std::string&, const std::string&);
    void (*writeFileAtomic)(const std::string&, const std::string&);
    std::string (*createTempFileNear)(const std::string&);
    void (*commitTempFile)(const std::string&, const std::string&);
    void (*writeImage8)(const std::string&, int, int, int, const float*, const std::string&);
    bool (*drawText)(float*, int, int, int, int, const std::string&, int, const Vec3&, int, bool);
    // core/texture/texture_store.h (on the module's own TextureStore objects)
    TextureStore* (*textureCreate)(std::shared_ptr<const ColorConfig>, int maxSide);
    void (*textureDestroy)(TextureStore*);
    TextureHandle (*textureLoad)(TextureStore*, const std::string&, const std::string&);
    int (*textureWidth)(const TextureStore*, TextureHandle);
    int (*textureHeight)(const TextureStore*, TextureHandle);
    int (*textureChannels)(const TextureStore*, TextureHandle);
    void (*textureSample)(const TextureStore*, TextureHandle, Vec2, Vec2, Vec2, float*, int, TextureWrap);
    Color3 (*textureSampleRgb)(const TextureStore*, TextureHandle, Vec2, Vec2, Vec2, TextureWrap);
    const std::vector<float>& (*texturePixels)(const TextureStore*, TextureHandle);
    // core/texture/normal_map_gen.h
    const char* (*normalMapKindName)(NormalMapKind);
    NormalMapKind (*parseNormalMapKind)(const std::string&);
    const std::vector<NormalMapKind>& (*allNormalMapKinds)();
    NormalMap (*generateNormalMap)(NormalMapKind, int, uint64_t);
    NormalMap (*generateBrushedNormalMap)(int, uint64_t, double, double*);
    void (*writeNormalMap)(const NormalMap&, const std::string&);
    uint64_t (*normalMapHash)(const NormalMap&);
    SlopeStats (*slopeStats)(const NormalMap&);
    double (*slopeStat)(const SlopeStats&, int which);  // 0 sigmaX, 1 sigmaY, 2 rho, 3 sigmaMajor, 4 sigmaMinor
};

// The table, loading the module on first use (throws IoError if it cannot be loaded).
const Table& table();
// Whether the module has been loaded in this process (for tests and the start-up report).
bool loaded();

}  // namespace specula::io_module

extern "C" const specula::io_module::Table* specula_io_module_table();
