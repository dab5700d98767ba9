// Glint dictionary (Chermain et al. 2020, spec glint-brdf.md §2): N = 192 multiscale 1D slope marginals over
// L = 16 levels, generated deterministically (SplitMix64 + Box-Muller), centre-sampled, with a box MIP pyramid.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace specula::glint {

// Dictionary constants of spec §1 (authors' values, C20 code "dict_16_192_64_0p5_0p02").
constexpr int kLevels = 16;                  // L: LODs of the dictionary and of the virtual cell hierarchy
constexpr int kMarginals = 192;              // N: 64 rows x 3 RGB channels
constexpr int kRes = 64;                     // R: texels per tabulated marginal
constexpr int kMips = 7;                     // 64, 32, 16, 8, 4, 2, 1 (GGAA pyramid, spec §2.2)
constexpr int kRowFloats = 2 * kRes - 1;     // 127 floats per (level, marginal): the whole chain
constexpr int kMeans = 1 << (kLevels - 1);   // K = 32768 means per marginal
constexpr double kAlphaDict = 0.5;           // alpha_d
constexpr double kSigmaO = 0.35355339059327373;  // sigma_o = alpha_d / sqrt(2); 4 sigma_o = sqrt(2)
constexpr double kSigmaL = 0.02;             // sigma_l: std of one lobe ("microfacet")
constexpr double kDelta = 4.0 * kSigmaO / kRes;  // texel spacing at MIP 0 (0.0220971)
constexpr uint64_t kSeed = 0x5eec1a6117D1C7ULL;  // fixed generator seed (documented, never changes)

// Offset of MIP m inside a row's 127 floats: 0, 64, 96, 112, 120, 124, 126.
constexpr int mipOffset(int m) { return 2 * kRes - (2 * kRes >> m); }
constexpr int mipRes(int m) { return kRes >> m; }

// Deterministic normal deviates: SplitMix64 (core/render/sampler.h mix64) + Box-Muller in double.
// Draw order: marginal-major; for marginal d the stream is seeded with mix64(kSeed + d) and yields the means
// mu_{d,0}, mu_{d,1}, ... in index order, two per Box-Muller pair (cos branch first).
class NormalStream {
public:
    explicit NormalStream(uint64_t seed);
    double next();  // N(0, 1)

private:
    uint64_t nextU64();
    uint64_t state_;
    double spare_ = 0.0;
    bool hasSpare_ = false;
};

// The first 'count' means N(0, sigma_o^2) of marginal d (spec §2.1 step 1).
std::vector<double> dictionaryMeans(int marginal, int count);

class Dictionary {
public:
    // The process-wide dictionary: loaded from the cache file if present and valid, else generated
    // (about a second on one core) and written to the cache. Thread-safe (std::call_once).
    static const Dictionary& instance();
    // Generates from scratch (no cache). Deterministic: byte-identical output on every call.
    static Dictionary generate();
    // Cache directory: $SPECULA_CACHE_DIR, else $XDG_CACHE_HOME/specula, else $HOME/.cache/specula;
    // "" disables caching.
    static std::string cacheDir();

    // Row of (level k, marginal d): 127 floats, MIP 0 (64 texel-centre samples of p_{d,k}) then MIPs 1..6.
    const float* row(int level, int marginal) const {
        return data_.data() + (size_t(level) * kMarginals + size_t(marginal)) * kRowFloats;
    }
    const float* mip(int level, int marginal, int m) const { return row(level, marginal) + mipOffset(m); }
    const std::vector<float>& data() const { return data_; }

    // FNV-1a 64 over the float32 bytes of every row (all MIPs): the golden hash.
    uint64_t hash() const;
    // Memory of this CPU table (float32, all MIPs) and of the GPU layouts (spec §2.2).
    size_t bytesCpu() const { return data_.size() * sizeof(float); }
    static constexpr size_t bytesBaseRgb16f() { return size_t(kRes) * kLevels * (kMarginals / 3) * 3 * 2; }
    static constexpr size_t bytesChainRgb16f() { return size_t(kRowFloats) * kLevels * (kMarginals / 3) * 3 * 2; }
    static constexpr size_t bytesChainRgba32f() { return size_t(kRowFloats) * kLevels * (kMarginals / 3) * 4 * 4; }

    // GPU texture layout of C20/C21 (spec §2.2): GL_TEXTURE_1D_ARRAY, width 64 >> m, 1024 layers,
    // layer = k*64 + d/3, channel = d%3, RGBA32F (alpha = 0) so the shader reads exactly the CPU floats.
    // Returns the texels of MIP m, layer-major (what glTexImage2D(GL_TEXTURE_1D_ARRAY, m, ...) expects).
    std::vector<float> gpuMipRgba(int m) const;
    static constexpr int kGpuLayers = kLevels * kMarginals / 3;  // 1024

    // Cumulative mass of the unfiltered marginal (MIP 0 under the GL_LINEAR + mirrored-repeat reconstruction that
    // sampleLinear reads), in slope units: marginalCdf(k, d, x) = integral of p_{d,k}(|x'|) over x' in [0, x], an odd
    // function of x with limit +-1/2 at |x| >= 4 sigma_o. The mass over [a, b] is cdf(b) - cdf(a): what integrating a
    // cell's separable slope distribution over a box needs (area lights), and what sampling a cell inverts.
    float marginalCdf(int level, int marginal, float x) const {
        return float((x < 0.f ? -1.0 : 1.0) * mipCdf(level, marginal, 0, std::abs(double(x))));
    }
    // The same for MIP m (GGAA reads MIPs 1-6, C21 §4.2) at ax >= 0, in double: exact for the piecewise-linear
    // reconstruction (piecewise quadratic between the MIP's texel centres).
    double mipCdf(int level, int marginal, int m, double ax) const;
    // The inverse on the half line: x >= 0 with marginalCdf(k, d, x) = u / 2, for u in [0, 1).
    float sampleMarginal(int level, int marginal, float u) const;
    // Cumulative mass of MIP m (resolution n = 64 >> m) at its n texel centres and at 4 sigma_o (n + 1 floats).
    static constexpr int kCdfRowFloats = kRowFloats + kMips;
    static constexpr int cdfMipOffset(int m) { return mipOffset(m) + m; }
    const float* cdfNodes(int level, int marginal, int m = 0) const {
        return cdf_.data() + (size_t(level) * kMarginals + size_t(marginal)) * kCdfRowFloats + cdfMipOffset(m);
    }

    double generationSeconds() const { return seconds_; }
    bool fromCache() const { return fromCache_; }

private:
    void buildCdf();
    std::vector<float> data_;
    std::vector<float> cdf_;
    double seconds_ = 0.0;
    bool fromCache_ = false;
};

}  // namespace specula::glint
