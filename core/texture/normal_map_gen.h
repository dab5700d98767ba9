// Procedural tangent-space normal maps (bumps, brushed, scratches, flakes, stone) for examples, tests and
// validation: deterministic (own integer hash, no libm transcendental in the generator), tileable, written via OIIO.
#pragma once

#include "core/math/math.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace specula {

struct NormalMapError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

enum class NormalMapKind { Bumps, Brushed, Scratches, Flakes, Stone };

// "bumps", "brushed", "scratches", "flakes", "stone" <-> kind. parse throws NormalMapError on unknown names.
const char* normalMapKindName(NormalMapKind k);
NormalMapKind parseNormalMapKind(const std::string& name);
const std::vector<NormalMapKind>& allNormalMapKinds();

// A square tangent-space normal map. Texel (x, y) is stored at normals[y * size + x] with row y = 0 the TOP row
// of the image (file order); u = (x + 0.5)/size, v = 1 - (y + 0.5)/size (v = 0 is the bottom, OpenGL convention).
// Normals are unit, z > 0, OpenGL convention (+y = +v). The map tiles seamlessly (periodic in u and v).
struct NormalMap {
    int size = 0;
    std::vector<Vec3> normals;
    const Vec3& at(int x, int y) const { return normals[size_t(y) * size_t(size) + size_t(x)]; }
};

// Generates a map. size in [8, 8192]; any seed. Per kind (slopes x~ = -nx/nz, y~ = -ny/nz, RMS per axis):
//  bumps     smooth isotropic fractal gradient noise (4 octaves), RMS slope 0.25 per axis;
//  brushed   fine grooves along the direction (2, 1)/sqrt(5) (26.6 deg from +u) plus faint isotropic noise:
//            principal RMS slopes ~0.2 across / ~0.03 along, so the slope covariance is strongly anisotropic
//            and correlated (rho ~ -0.6 in the (u, v) axes);
//  scratches a flat surface with thin (~2 texel) V-grooves of random direction and length; most texels flat;
//  flakes    jittered-grid Voronoi cells (~8 texels) with one random iid tilt each (RMS ~0.35 per axis, ~25 deg);
//  stone     Voronoi cobbles (bevelled domes, mortar grooves) with two octaves of surface noise, RMS ~0.3.
NormalMap generateNormalMap(NormalMapKind kind, int size, uint64_t seed);

// The brushed map with its grooves along 'angleDegrees' from +u (counter-clockwise towards +v). A seamless tile
// needs an integer direction (A, B): the nearest one with |A|, B <= 8 is used, and its angle is returned in
// *usedAngleDegrees (within 3.6 degrees of the request; 26.565 is (2, 1), the default brushed map exactly).
NormalMap generateBrushedNormalMap(int size, uint64_t seed, double angleDegrees, double* usedAngleDegrees = nullptr);

// 'generate:<kind>:<size>:<seed>' names a generated map wherever a normal-map file is expected (texture.image with
// colorspace raw, texture.lean, bsdf.ltc_normal_map, bsdf.glint_pndf), so scenes can use large maps without shipping
// multi-megabyte files. Inline: both libspecula and the image-I/O module parse it. maxSide is the host's or scene's
// cap on texture sides (SceneLimits::maxTextureSide): a generated map is a texture like a file and obeys it.
inline bool isGeneratedNormalMapName(const std::string& name) { return name.rfind("generate:", 0) == 0; }
inline NormalMap generateNormalMapFromName(const std::string& name, int maxSide = 8192) {
    const std::string rest = name.substr(9);
    const size_t a = rest.find(':'), b = a == std::string::npos ? a : rest.find(':', a + 1);
    if (!isGeneratedNormalMapName(name) || b == std::string::npos)
        throw NormalMapError("'" + name + "': expected generate:<kind>:<size>:<seed>");
    int size = 0;
    unsigned long long seed = 0;
    try {
        size_t used = 0;
        const std::string sizeText = rest.substr(a + 1, b - a - 1), seedText = rest.substr(b + 1);
        size = std::stoi(sizeText, &used);
        if (used != sizeText.size()) throw std::invalid_argument("size");
        seed = std::stoull(seedText, &used);
        if (used != seedText.size()) throw std::invalid_argument("seed");
    } catch (const std::logic_error&) {
        throw NormalMapError("'" + name + "': expected generate:<kind>:<size>:<seed> with integer size and seed");
    }
    if (size < 8 || size > 8192) throw NormalMapError("'" + name + "': size must be in [8, 8192]");
    if (size > maxSide)
        throw NormalMapError("'" + name + "': size " + std::to_string(size) + " exceeds the texture side limit of " +
                             std::to_string(maxSide) + " (limits.texture_side)");
    return generateNormalMap(parseNormalMapKind(rest.substr(0, a)), size, seed);
}
// The map as an RGB float image, colour = (n + 1)/2, rows top to bottom (what a file of it holds).
inline std::vector<float> encodeNormalMapRgb(const NormalMap& m) {
    std::vector<float> px(size_t(m.size) * size_t(m.size) * 3);
    for (size_t i = 0; i < m.normals.size(); ++i)
        for (int c = 0; c < 3; ++c) px[i * 3 + size_t(c)] = 0.5f * (m.normals[i][c] + 1.f);
    return px;
}

// The inverse for one pixel of an encoded map ('channels' >= 2 floats, colour = (n + 1)/2): the tangent-space normal,
// not normalised; two-channel maps get nz = sqrt(1 - nx² - ny²), and 'directx' flips green (DirectX maps: +Y down).
// LeanPyramid::fromEncodedPixels and NormalMapLtcPrefilter::normalsFromEncodedPixels decode with it.
inline Vec3 decodeNormalPixel(const float* p, int channels, bool directx) {
    Vec3 n(2.f * p[0] - 1.f, 2.f * p[1] - 1.f, 0.f);
    n.z = channels >= 3 ? 2.f * p[2] - 1.f : std::sqrt(std::max(0.f, 1.f - n.x * n.x - n.y * n.y));
    if (directx) n.y = -n.y;
    return n;
}

// Writes 'map' encoded as colour = (n + 1)/2 (the convention texture.normal_map decodes), chosen by extension:
// .png -> 16-bit RGB PNG, .exr -> 32-bit float RGB EXR (also .tif/.tiff -> 16-bit). Throws NormalMapError.
void writeNormalMap(const NormalMap& map, const std::string& path);

// FNV-1a 64 over the normals quantised to 16 bits per channel exactly as the PNG stores them (the golden-hash
// determinism tests use it; quantisation keeps it robust to last-bit float differences).
uint64_t normalMapHash(const NormalMap& map);

// Slope statistics of a map (texel average): mean slope, covariance, RMS slopes, correlation.
struct SlopeStats {
    double meanX = 0, meanY = 0;
    double varX = 0, varY = 0, covXY = 0;
    double sigmaX() const;
    double sigmaY() const;
    double rho() const;
    // Principal RMS slopes (sqrt of the covariance eigenvalues), major >= minor.
    double sigmaMajor() const;
    double sigmaMinor() const;
};
SlopeStats slopeStats(const NormalMap& map);

}  // namespace specula
