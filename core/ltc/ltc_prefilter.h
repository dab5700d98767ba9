// LTC normal-map filtering after Nahmias 2022 (ltc-filtering.md §4, §5.3): per MIP texel and view, one LTC fitted
// (Student-t EM, §5.2) to the footprint's effective BRDF, specular and diffuse, with a content-hashed disk cache.
#pragma once

#include "core/ltc/ltc.h"

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace specula {
struct NormalMap;
}

namespace specula::ltc {

struct LtcTables;

struct PrefilterError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Everything the fitted tables depend on besides the normals (all of it enters the cache hash).
struct PrefilterSettings {
    float alpha = 0.1f;  // base GGX alpha of every texel (the material roughness squared)
    // View grids in the geometric tangent frame. θ_j = j/(nθ−1)·0.999·π/2 (thesis §3.4.1, linear in θ);
    // φ_k = 2πk/nφ: our variant of the thesis grid (which repeats φ = 0 as 2π): nφ distinct azimuths covering [0, 2π)
    // with wrap-around interpolation, so no azimuth is stored twice.
    int specTheta = 8, specPhi = 16;  // the thesis's 8 × 16
    int diffTheta = 2, diffPhi = 4;   // the thesis's 2 × 4
    int maxSamples = 256;             // weighted directions per fit (§5.3)
    int iterations = 30;              // t-EM iterations (§5.2 step 3)
};

// The two LTCs of a footprint, both in the geometric tangent frame (z = the unperturbed normal, x = +u, y = +v).
// spec: the GGX eBRDF (magnitude = ∫ f·cos with F = 1 over the footprint texels, fresnel its Schlick moment);
// diffuse: the Lambert eBRDF (magnitude = fraction of footprint texels facing the view).
struct LtcPair {
    Ltc spec, diffuse;
};

// Where a prefilter came from (tests and logs).
enum class CacheOutcome : uint8_t { Fitted, Loaded, FittedAfterInvalidCache, FittedNoCache };

// The prefiltered LTC pyramid of one square power-of-two tangent-space normal map (§5.3).
//
// Levels: level 0 is the map itself and is not stored: its LTCs come from the base table per texel at lookup time
// (ggxIsotropic in the texel frame with the texel rotation folded into inv(M); diffuse: the rotation to the texel
// normal). Levels l = 1..log2(size) (tile T = 2^l texels a side, down to 1 × 1) store one specular LTC per
// (texel, spec view) and one diffuse LTC per (texel, diffuse view), fitted in the view-aligned frame (view azimuth
// rotated to 0) from at most maxSamples weighted directions:
//   T² <= maxSamples: every tile texel, a stratified k×k grid of sample numbers each (k = ⌊√(maxSamples/T²)⌋), the
//   grids shifted per texel (Cranley-Patterson) by distinct cells of a T×T grid so the union over the tile is one
//   stratified (kT)² grid; T² > maxSamples: maxSamples texels, one per block of a fixed stride lattice (a hashed
//   position inside each block, the same for every tile), each with one cell of a stratified grid.
// Specular samples: GGX(α) visible normals in the texel frame (Heitz 2018), reflected, weighted by G2/G1 (texels
// facing away from the view weigh 0), rotated texel → geometric (the minimal rotation z → n, thesis R0) → view-aligned.
// Diffuse samples: cosine samples in the texel frame, weight 1 where the texel faces the view.
// The fit gives the shape (inv(M)); magnitude and Fresnel moment are the exact means over all footprint texels of
// the base table's per-texel values (diffuse: the fraction of texels facing the view), i.e. the albedo of the
// per-texel ground truth: the mean weight of 256 stratified samples is biased by up to ~1% at α ≈ 0.1.
// Storage: per LTC 11 half floats, inv(M) normalised to unit Frobenius norm (9), magnitude and Fresnel moment
// (22 bytes; the thesis stored 9 floats, no magnitude). 128² at the default grids: 5461 texels × 136 views × 22 B
// = 16.3 MB (thesis: 26.7 MB). Cost: one t-EM fit per (texel, view) with its samples, ~50 µs of CPU: 743k fits at
// 128², measured 19.3 s wall on 2 shared cores (bench_ltc_prefilter; the thesis: ~4 h on a GPU); 256² quadruples
// everything (65 MB, ~4× the time) and is allowed but not recommended. Temporary memory: 2 floats per stored texel
// and view plus one level-0 copy per view in flight.
// Deterministic: no random state (stratified grids, integer hashes), texels fitted independently in parallel (TBB),
// so the result does not depend on the thread count.
class NormalMapLtcPrefilter {
public:
    NormalMapLtcPrefilter() = default;

    // normals: size × size tangent-space normals (any length), texel (x, y) at [y·size + x] with y = 0 the BOTTOM
    // row (v = 0), OpenGL convention (+y = +v). size must be a power of two >= 1. Normals at or below the horizon are
    // clamped to nz >= max(|nx|, |ny|)/16 (as LEAN does). Throws PrefilterError.
    static NormalMapLtcPrefilter build(const std::vector<Vec3>& normals, int size, const PrefilterSettings& s);
    // From a generated map (rows top-down, see core/texture/normal_map_gen.h).
    static std::vector<Vec3> normalsOf(const NormalMap& map);
    // From pixels as TextureStore::pixels() returns them (rows top-down, colour = (n + 1)/2, 2 or more channels);
    // 'directx' flips green. Throws PrefilterError for a non-square or non-power-of-two image.
    static std::vector<Vec3> normalsFromEncodedPixels(const float* pixels, int width, int height, int channels,
                                                      bool directx);

    // The content hash that names the cache file: FNV-1a 64 of a format version, the settings, the base tables' hash
    // (builtinTables().hash(): the magnitudes come from them) and the clamped normals' bits.
    static uint64_t contentHash(const std::vector<Vec3>& normals, int size, const PrefilterSettings& s);
    // $SPECULA_CACHE_DIR/ltc, else $XDG_CACHE_HOME/specula/ltc, else ~/.cache/specula/ltc (the texture cache's bases).
    static std::string defaultCacheDir();
    static std::string cachePath(const std::string& dir, uint64_t hash);
    // Reads the cache file for (normals, s) from 'dir' if it is valid, else fits and writes it (atomically: temp file
    // + rename; a failure to write is not an error). dir = "" disables the cache.
    static std::shared_ptr<const NormalMapLtcPrefilter> loadOrBuild(const std::vector<Vec3>& normals, int size,
                                                                    const PrefilterSettings& s, const std::string& dir,
                                                                    CacheOutcome* outcome = nullptr);
    // Cache file I/O. read: false (and *this unchanged) unless the file's header matches exactly what (normals, s)
    // imply and the payload is complete and its checksum matches; never throws for a bad file.
    bool writeFile(const std::string& path) const;
    bool readFile(const std::string& path, const std::vector<Vec3>& normals, int size, const PrefilterSettings& s);

    // Runtime lookup (§5.3): uv (v = 0 bottom, repeat wrap), footprint duv/dx, duv/dy (the MIP level is
    // log2 of the longer footprint axis in texels), view woTangent (unit, geometric tangent frame). Trilinear over
    // texels and levels (level 0 = the per-texel base LTCs, so the 0-1 transition is a blend, not a switch), bilinear
    // over (θ, φ) of the stored views (magnitude and Fresnel in θ as ratios to the flat surface's), then rotated back
    // by the view azimuth. inv(M) entries are averaged with weights
    // filter weight × magnitude (a texel facing away contributes no shape), magnitude and Fresnel with the filter
    // weight. woTangent.z <= 0 gives magnitudes 0.
    LtcPair lookup(Vec2 uv, Vec2 duvdx, Vec2 duvdy, const Vec3& woTangent, const LtcTables& tables) const;
    // The same at an explicit fractional level in [0, levels()].
    LtcPair lookupLevel(float level, Vec2 uv, const Vec3& woTangent, const LtcTables& tables) const;
    // The stored LTCs of texel (x, y) of level l >= 1 (bilinear over views only), in the geometric frame.
    LtcPair texelLtc(int level, int x, int y, const Vec3& woTangent, const LtcTables& tables) const;
    // The base (level-0) LTCs of texel (x, y), in the geometric frame.
    LtcPair baseTexelLtc(int x, int y, const Vec3& woTangent, const LtcTables& tables) const;

    int size() const { return size_; }
    int levels() const { return levels_; }  // the coarsest level (log2 size); stored levels are 1..levels()
    const PrefilterSettings& settings() const { return settings_; }
    const std::vector<Vec3>& normals() const { return normals_; }  // clamped, unit, bottom-up
    uint64_t hash() const { return hash_; }
    // Bytes of the fitted tables (the cache file's payload).
    size_t storageBytes() const { return (spec_.size() + diffuse_.size()) * sizeof(uint16_t); }
    // The raw fp16 records (kRecordHalfs per LTC), for determinism tests.
    const std::vector<uint16_t>& specRecords() const { return spec_; }
    const std::vector<uint16_t>& diffuseRecords() const { return diffuse_; }

    // The texel-frame rotation R0 (columns t, b, n: the minimal rotation taking z to n, thesis §3.4.1).
    static Mat3 texelRotation(const Vec3& n);

    static constexpr int kRecordHalfs = 11;  // inv(M) 9, magnitude, Fresnel
    static constexpr uint32_t kFormatVersion = 2;  // 2: an entry of the cache service (core/util/cache_dir.h)

private:
    int size_ = 0, levels_ = 0;
    PrefilterSettings settings_;
    std::vector<Vec3> normals_;
    std::vector<size_t> levelOffset_;  // first texel of level l (index l; level 0 unused) in the stored texel order
    std::vector<uint16_t> spec_, diffuse_;
    uint64_t hash_ = 0;

    void initLayout(const std::vector<Vec3>& normals, int size, const PrefilterSettings& s);
    size_t texelCount() const { return levelOffset_.empty() ? 0 : levelOffset_.back(); }
    void fitAll();
    // Adds w·(normalised invM, mag, fres) of the stored view-interpolated LTC of a level-l texel (view-aligned frame).
    // scales: thetaScales() for the specular, null (plain linear) for the diffuse.
    void accumulateStored(int level, int x, int y, float theta, float phi, float w, bool diffuse, const float* scales,
                          float* acc) const;
    // Per-row factors (mag j0, mag j1, fres j0, fres j1) of the θ interpolation: flat(θ)/flat(θ_j) from the base table.
    void thetaScales(float theta, const LtcTables& tables, float* out) const;
};

}  // namespace specula::ltc
