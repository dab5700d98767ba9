// LEAN mapping (Olano & Baker 2010): MIP pyramids of the slope moments (x~, y~, x~^2, y~^2, x~y~) of a
// tangent-space normal map, exact box reduction, footprint-filtered lookups and the slope mean/covariance.
#pragma once

#include "core/math/math.h"

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace specula {

struct NormalMap;

struct LeanError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Slope moments of a texel or of a filtered footprint. Slopes follow glint-brdf.md §1: x~ = -nx/nz, y~ = -ny/nz
// (so a microfacet with slope (x~, y~) has normal ∝ (-x~, -y~, 1)). All five average linearly, which is the point
// of LEAN mapping (Olano & Baker 2010: store the first and second slope moments, filter them with ordinary
// linear/MIP filtering, recover the covariance only after filtering).
struct LeanMoments {
    float x = 0, y = 0;           // E[x~], E[y~]
    float xx = 0, yy = 0, xy = 0;  // E[x~^2], E[y~^2], E[x~ y~]

    LeanMoments& operator+=(const LeanMoments& o) {
        x += o.x, y += o.y, xx += o.xx, yy += o.yy, xy += o.xy;
        return *this;
    }
    LeanMoments operator*(float s) const { return {x * s, y * s, xx * s, yy * s, xy * s}; }
};

// Gaussian slope statistics derived from moments (Olano & Baker 2010; Chermain et al. 2021, §5.1, Eq. 16):
// Σ = [[E[x²] − E[x]², E[xy] − E[x]E[y]], [·, E[y²] − E[y]²]], projected to PSD (variances ≥ 0, |cov| ≤ σxσy),
// σx = sqrt Σxx, σy = sqrt Σyy, ρ = Σxy / (σx σy) (0 when either σ is 0).
struct LeanStats {
    Vec2 mean{0.f};                       // mean slope
    float varX = 0, varY = 0, covXY = 0;  // slope covariance Σ
    float sigmaX = 0, sigmaY = 0, rho = 0;
    // Mean normal in tangent space: normalize(-E[x~], -E[y~], 1).
    Vec3 meanNormal() const;
};

// 'strength' scales slopes (mean × s, Σ × s²: the same tilt scaling as texture.normal_map's strength, exactly in
// slope space); 'flipY' negates y~ (left-handed tangent frames: mean.y and Σxy change sign); 'dropCorrelation'
// zeroes Σxy and ρ ("LEAN without ρ" of the validation).
LeanStats leanStats(const LeanMoments& m, float strength = 1.f, bool flipY = false, bool dropCorrelation = false);

// Moments of one tangent-space normal (any length; only the direction matters). nz is clamped to keep
// |slope| <= kLeanMaxSlope (normals at or below the horizon map to the steepest representable slope).
constexpr float kLeanMaxSlope = 16.f;
LeanMoments leanTexelMoments(Vec3 n);

enum class LeanFilter : uint8_t {
    None,         // bilinear on level 0 (footprint ignored): the full-resolution reference
    Trilinear,    // isotropic: λ = log2(max(|J1|, |J2|)) (texels), linear between levels floor(λ), floor(λ)+1
    Anisotropic,  // EXT_texture_filter_anisotropic: N = min(ceil(Pmax/Pmin - slack), maxAniso) trilinear probes along the
                  // major axis at λ = log2(Pmax/N), equally weighted
};
enum class LeanWrap : uint8_t { Repeat, Clamp };

// One MIP level, stored as the GLSL samplers hold it: 'rgba' = (x~, y~, x~², y~²) and 'r' = x~y~, rows bottom-up
// (texel (x, y) covers u ∈ [x/w, (x+1)/w), v ∈ [y/h, (y+1)/h); v = 0 is the bottom row, OpenGL convention).
struct LeanLevel {
    int width = 0, height = 0;
    std::vector<float> rgba;  // 4 floats per texel
    std::vector<float> r;     // 1 float per texel
};

class LeanPyramid {
public:
    LeanPyramid() = default;

    // From normal-map pixels as TextureStore::pixels() gives them: 'channels' floats per pixel, rows top to bottom,
    // colour = (n + 1)/2 ("raw" data). 'directx' flips green (DirectX maps: +Y = down). Two-channel maps get
    // nz = sqrt(1 - nx² - ny²). Throws LeanError on empty input or fewer than 2 channels.
    static LeanPyramid fromEncodedPixels(const float* pixels, int width, int height, int channels, bool directx);
    // From a generated map (already unit normals, OpenGL convention).
    static LeanPyramid fromNormalMap(const NormalMap& map);

    int levels() const { return int(levels_.size()); }
    const LeanLevel& level(int l) const { return levels_[size_t(l)]; }
    int width() const { return levels_.empty() ? 0 : levels_[0].width; }
    int height() const { return levels_.empty() ? 0 : levels_[0].height; }
    // Texel (x, y) of level l, y = 0 the bottom row.
    LeanMoments texel(int l, int x, int y) const;

    // Bilinear lookup on level l (GL_LINEAR: texel centres at (i + 1/2)/w).
    LeanMoments bilinear(int l, Vec2 uv, LeanWrap wrap = LeanWrap::Repeat) const;
    // Trilinear lookup at a fractional level λ (GL_LINEAR_MIPMAP_LINEAR, λ clamped to [0, levels-1]).
    LeanMoments trilinear(float lambda, Vec2 uv, LeanWrap wrap = LeanWrap::Repeat) const;
    // Footprint-filtered lookup: duvdx, duvdy are the UV changes per pixel step (ray differentials).
    LeanMoments lookup(Vec2 uv, Vec2 duvdx, Vec2 duvdy, LeanFilter filter, LeanWrap wrap = LeanWrap::Repeat,
                       int maxAniso = 16) const;

    // Bytes held by all levels (5 floats per texel); baseBytes() is level 0 alone.
    size_t memoryBytes() const;
    size_t baseBytes() const;

    // GLSL upload of texture.lean (nodes/texture/lean/lean.glsl): ONE mipmapped, GL-complete RGBA32F sampler2D of
    // width w0 and height P0 = 2 max(w0, h0) with glslLevels() = levels() + 1 levels (GL sizes max(1, w0 >> l) x
    // max(1, P0 >> l); the last level is padding). Level l < levels() interleaves rows: row 2j = (x~, y~, x~², y~²)
    // and row 2j+1 = (x~y~, h_l, levels(), 0) of moment row j (bottom-up); the remaining rows are zero. The shader
    // reads it with texelFetch and filters exactly as lookup() does, so CPU and GLSL agree (tests/glsl parity).
    // Host: glTexImage2D per level with glslPackedLevel(l), GL_TEXTURE_MAX_LEVEL = glslLevels() - 1.
    int glslLevels() const { return levels() + 1; }
    void glslLevelSize(int l, int& width, int& height) const;
    std::vector<float> glslPackedLevel(int l) const;

private:
    std::vector<LeanLevel> levels_;
    void build(std::vector<LeanMoments> base, int width, int height);  // base rows bottom-up
};

// Reduction used between levels: level l+1 has max(1, floor(w/2)) x max(1, floor(h/2)) texels and each of them
// is the exact box average of the level-l area it covers (fractional overlaps for odd sizes), so every level has
// the same mean as level 0 and the coarsest 1x1 texel is the image mean of each moment.
int leanLevelSize(int size0, int level);

}  // namespace specula
