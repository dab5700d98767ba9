// Image textures for shading: files are read with OpenImageIO, converted from their declared
// colorspace to the working space once, MIP-mapped, and sampled through OIIO's TextureSystem with
// the ray-differential footprint (trilinear/anisotropic), so filtering is identical for every node.
#pragma once

#include "core/math/math.h"

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace specula {

class ColorConfig;

struct TextureError : std::runtime_error {
    using std::runtime_error::runtime_error;
};
// A texture the scene asks for wrongly (beyond the documented limits of size, file size and memory; an unknown colour
// space): bad input, not I/O.
struct TextureInputError : TextureError {
    using TextureError::TextureError;
};
// The declared colorspace is not a name, alias or role of the config: the fault is the colorspace, not the file.
struct TextureColorspaceError : TextureInputError {
    using TextureInputError::TextureInputError;
};

enum class TextureWrap { Repeat, Clamp, Mirror, Black };

struct TextureHandle {
    int index = -1;
    bool valid() const { return index >= 0; }
};

class TextureStore {
public:
    // maxSide: the largest texture side accepted (a host's cap, SceneLimits::maxTextureSide), at most 65536.
    explicit TextureStore(std::shared_ptr<const ColorConfig> color, int maxSide = 65536);
    ~TextureStore();
    TextureStore(const TextureStore&) = delete;
    TextureStore& operator=(const TextureStore&) = delete;

    // Loads (or reuses) 'path' declared in 'colorspace' (any name/alias of the OCIO config, or "raw"
    // for data such as normal maps). Converted to linear working space, MIP-mapped in a cache
    // directory keyed by content+colorspace. Throws TextureError naming the path.
    TextureHandle load(const std::string& path, const std::string& colorspace);
    // The cap on texture sides given at construction (generated normal maps obey it too).
    int maxSide() const;

    int width(TextureHandle h) const;
    int height(TextureHandle h) const;
    int channels(TextureHandle h) const;

    // Filtered lookup at uv (v = 0 is the *bottom* row, OpenGL convention) with footprint
    // derivatives (duvdx, duvdy); zero derivatives give a bilinear lookup of the finest level.
    // Writes 'nchannels' floats (missing channels are filled with the last available / 1 for alpha).
    void sample(TextureHandle h, Vec2 uv, Vec2 duvdx, Vec2 duvdy, float* out, int nchannels,
                TextureWrap wrap = TextureWrap::Repeat) const;
    Color3 sampleRgb(TextureHandle h, Vec2 uv, Vec2 duvdx, Vec2 duvdy, TextureWrap wrap = TextureWrap::Repeat) const;

    // The full-resolution linear pixels (rows top to bottom), e.g. for uploading to GLSL samplers
    // or building derived pyramids (LEAN moments).
    const std::vector<float>& pixels(TextureHandle h) const;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace specula
