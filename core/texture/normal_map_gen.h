// Procedural tangent-space normal maps (bumps, brushed, scratches, flakes, stone) for examples, tests and
// validation: deterministic (own integer hash, no libm transcendental in the generator), tileable, written via OIIO.
#pragma once

#include "core/math/math.h"

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
