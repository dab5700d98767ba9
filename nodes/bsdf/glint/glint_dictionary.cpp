// Glint dictionary generation (spec glint-brdf.md §2.1 with its recommendations: Specula-owned PRNG and normal
// deviates, texel-centre sampling renormalised exactly, box-filtered MIP chain per row) and its on-disk cache.
#include "nodes/bsdf/glint/glint_dictionary.h"

#include "core/render/sampler.h"
#include "core/texture/pyramid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>

namespace specula::glint {

NormalStream::NormalStream(uint64_t seed) : state_(seed) {}

uint64_t NormalStream::nextU64() {
    state_ += 0x9E3779B97F4A7C15ULL;  // SplitMix64 (Steele et al. 2014): Weyl step + mix64 finaliser
    return mix64(state_);
}

double NormalStream::next() {
    if (hasSpare_) {
        hasSpare_ = false;
        return spare_;
    }
    // Box-Muller (1958) in double: u1 in (0, 1] so log(u1) is finite, u2 in [0, 1).
    const double u1 = double((nextU64() >> 11) + 1) * 0x1.0p-53;
    const double u2 = double(nextU64() >> 11) * 0x1.0p-53;
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double phi = 2.0 * 3.14159265358979323846 * u2;
    spare_ = r * std::sin(phi);
    hasSpare_ = true;
    return r * std::cos(phi);
}

std::vector<double> dictionaryMeans(int marginal, int count) {
    NormalStream ns(mix64(kSeed + uint64_t(marginal)));
    std::vector<double> mu(static_cast<size_t>(count));
    for (auto& m : mu) m = kSigmaO * ns.next();
    return mu;
}

namespace {

constexpr uint32_t kCacheVersion = 1;
constexpr char kMagic[8] = {'S', 'P', 'G', 'L', 'D', 'I', 'C', 'T'};

uint64_t fnv1a(const void* p, size_t n, uint64_t h = 1469598103934665603ULL) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ULL;
    return h;
}

// One marginal d: all 16 levels, each 127 floats (spec §2.1 steps 2-4, §2.2 pyramid).
void generateMarginal(int d, float* out) {
    const std::vector<double> mu = dictionaryMeans(d, kMeans);
    const double inv = 1.0 / (kSigmaL * std::sqrt(2.0 * 3.14159265358979323846));
    const double k2 = -0.5 / (kSigmaL * kSigmaL);
    const double cut = 8.0 * kSigmaL;  // lobes further than 8 sigma_l contribute < 1e-14 relative
    double acc[kRes] = {};
    int done = 0;
    for (int k = 0; k < kLevels; ++k) {
        // Level k uses the prefix of 2^k means (nested prefixes: LOD coherence).
        const int upto = 1 << k;
        for (; done < upto; ++done) {
            for (double c : {mu[size_t(done)], -mu[size_t(done)]}) {
                int lo = std::max(0, int(std::ceil((c - cut) / kDelta - 0.5)));
                int hi = std::min(kRes - 1, int(std::floor((c + cut) / kDelta - 0.5)));
                for (int i = lo; i <= hi; ++i) {
                    const double x = (i + 0.5) * kDelta - c;  // texel-centre convention
                    acc[i] += inv * std::exp(k2 * x * x);
                }
            }
        }
        // p_{d,k}(x) = 2^-(k+1) sum_{m<2^k} [g(x - mu_m) + g(x + mu_m)], then the exact renormalisation
        // 2 * Delta * sum_i p_i = 1 (mirrored-repeat linear interpolation integrates to exactly this).
        double sum = 0.0;
        for (int i = 0; i < kRes; ++i) sum += acc[i];
        const double scale = sum > 0.0 ? 1.0 / (2.0 * kDelta * sum) : 0.0;
        float* row = out + size_t(k) * kRowFloats;
        for (int i = 0; i < kRes; ++i) row[i] = float(acc[i] * scale);
        // Box MIP chain: level m+1 = 2:1 average of level m (keeps 2 Delta_m sum = 1 exactly in exact arithmetic), the
        // pyramid's GL box on a 64 x 1 image (core/texture/pyramid.h), its levels packed behind MIP 0 in the row.
        const Pyramid chain = Pyramid::build(kRes, 1, 1, std::vector<float>(row, row + kRes), PyramidReduction::GlBox);
        for (int m = 1; m < kMips; ++m) std::copy_n(chain.level(m).texels.data(), mipRes(m), row + mipOffset(m));
    }
}

}  // namespace

Dictionary Dictionary::generate() {
    auto t0 = std::chrono::steady_clock::now();
    Dictionary dict;
    dict.data_.assign(size_t(kLevels) * kMarginals * kRowFloats, 0.f);
    std::vector<float> perMarginal(size_t(kMarginals) * kLevels * kRowFloats);
    // Marginals are independent streams, so the parallel loop is deterministic.
    tbb::parallel_for(0, kMarginals, [&](int d) { generateMarginal(d, perMarginal.data() + size_t(d) * kLevels * kRowFloats); });
    for (int d = 0; d < kMarginals; ++d)
        for (int k = 0; k < kLevels; ++k)
            std::memcpy(dict.data_.data() + (size_t(k) * kMarginals + d) * kRowFloats,
                        perMarginal.data() + (size_t(d) * kLevels + k) * kRowFloats, kRowFloats * sizeof(float));
    dict.buildCdf();
    dict.seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return dict;
}

// C[i] = mass over [0, x_i] at the texel centres x_i = (i + 1/2) s of each MIP (spacing s = 4 sigma_o / n), in double:
// the half texel [0, x_0] is flat at p_0 (the mirror of texel 0), each segment between centres is linear, and
// [x_{n-1}, 4 sigma_o] is flat at p_{n-1}.
void Dictionary::buildCdf() {
    cdf_.assign(size_t(kLevels) * kMarginals * kCdfRowFloats, 0.f);
    for (int k = 0; k < kLevels; ++k)
        for (int d = 0; d < kMarginals; ++d)
            for (int m = 0; m < kMips; ++m) {
                const float* p = mip(k, d, m);
                float* c = cdf_.data() + (size_t(k) * kMarginals + d) * kCdfRowFloats + cdfMipOffset(m);
                const int n = mipRes(m);
                const double s = 4.0 * kSigmaO / n;
                double acc = 0.5 * s * p[0];
                c[0] = float(acc);
                for (int i = 0; i + 1 < n; ++i) c[i + 1] = float(acc += 0.5 * s * (double(p[i]) + double(p[i + 1])));
                c[n] = float(acc + 0.5 * s * p[n - 1]);
            }
}

double Dictionary::mipCdf(int level, int marginal, int m, double ax) const {
    const float* p = this->mip(level, marginal, m);
    const float* c = cdfNodes(level, marginal, m);
    const int n = mipRes(m);
    const double s = 4.0 * kSigmaO / n;
    const double t = ax / s - 0.5;  // position in texel-centre units
    if (t <= 0.0) return p[0] * ax;
    if (t >= n - 1) return std::min(c[n - 1] + p[n - 1] * (ax - (n - 0.5) * s), double(c[n]));
    const int i = int(t);
    const double f = t - i;
    return c[i] + s * f * (p[i] + 0.5 * (double(p[i + 1]) - p[i]) * f);
}

float Dictionary::sampleMarginal(int level, int marginal, float u) const {
    const float* p = row(level, marginal);
    const float* c = cdfNodes(level, marginal);
    const float delta = float(kDelta);
    const float target = std::clamp(u, 0.f, 1.f) * c[kRes];  // c[kRes] = 1/2 up to rounding
    if (target <= c[0]) return p[0] > 0.f ? target / p[0] : 0.5f * delta;
    if (target >= c[kRes - 1]) {
        const float x0 = (kRes - 0.5f) * delta;
        return p[kRes - 1] > 0.f ? std::min(x0 + (target - c[kRes - 1]) / p[kRes - 1], float(4.0 * kSigmaO)) : x0;
    }
    // Segment i with c[i] < target <= c[i+1] (c is non-decreasing; zero-mass segments are skipped by the search).
    // std::upper_bound over the 64 nodes without data-dependent branches: count the nodes <= target by halving steps
    // (the same index; the CDF rows are read at random, so mispredicted branches would serialise the misses).
    const float* b = c;
    for (int step = kRes / 2; step > 0; step >>= 1) b = target < b[step - 1] ? b : b + step;
    const int i = int(b - c) - 1;
    const float r = (target - c[i]) / delta, dp = p[i + 1] - p[i];
    // Solve p_i f + dp f^2 / 2 = r in the stable form f = 2r / (p_i + sqrt(p_i^2 + 2 dp r)).
    const float disc = std::sqrt(std::max(p[i] * p[i] + 2.f * dp * r, 0.f));
    const float den = p[i] + disc;
    const float f = den > 0.f ? std::clamp(2.f * r / den, 0.f, 1.f) : 0.5f;
    return (float(i) + 0.5f + f) * delta;
}

uint64_t Dictionary::hash() const { return fnv1a(data_.data(), data_.size() * sizeof(float)); }

std::string Dictionary::cacheDir() {
    if (const char* e = std::getenv("SPECULA_CACHE_DIR")) return e;
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/specula";
    if (const char* h = std::getenv("HOME"); h && *h) return std::string(h) + "/.cache/specula";
    return "";
}

std::vector<float> Dictionary::gpuMipRgba(int m) const {
    const int w = mipRes(m);
    std::vector<float> px(size_t(kGpuLayers) * w * 4, 0.f);
    for (int k = 0; k < kLevels; ++k)
        for (int d = 0; d < kMarginals; ++d) {
            const int layer = k * (kMarginals / 3) + d / 3, ch = d % 3;
            const float* src = mip(k, d, m);
            for (int i = 0; i < w; ++i) px[(size_t(layer) * w + i) * 4 + ch] = src[i];
        }
    return px;
}

const Dictionary& Dictionary::instance() {
    static Dictionary dict;
    static std::once_flag once;
    std::call_once(once, [] {
        auto t0 = std::chrono::steady_clock::now();
        const size_t n = size_t(kLevels) * kMarginals * kRowFloats;
        std::string dir = cacheDir();
        std::string file = dir.empty() ? "" : dir + "/glint_dict_v" + std::to_string(kCacheVersion) + "_16_192_64.bin";
        if (!file.empty()) {
            std::ifstream in(file, std::ios::binary);
            char magic[8];
            uint64_t stored = 0;
            std::vector<float> buf(n);
            if (in.read(magic, 8) && std::memcmp(magic, kMagic, 8) == 0 && in.read(reinterpret_cast<char*>(&stored), 8) &&
                in.read(reinterpret_cast<char*>(buf.data()), std::streamsize(n * sizeof(float))) &&
                fnv1a(buf.data(), n * sizeof(float)) == stored) {
                dict.data_ = std::move(buf);
                dict.buildCdf();
                dict.fromCache_ = true;
                dict.seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                return;
            }
        }
        dict = generate();
        if (!file.empty()) {
            std::error_code ec;
            std::filesystem::create_directories(dir, ec);
            // Write to a unique temporary file and rename: concurrent processes never see a partial cache.
            std::string tmp = file + ".tmp" + std::to_string(uint64_t(std::chrono::steady_clock::now().time_since_epoch().count()));
            {
                std::ofstream out(tmp, std::ios::binary);
                uint64_t h = dict.hash();
                out.write(kMagic, 8);
                out.write(reinterpret_cast<const char*>(&h), 8);
                out.write(reinterpret_cast<const char*>(dict.data_.data()), std::streamsize(n * sizeof(float)));
            }
            std::filesystem::rename(tmp, file, ec);
            if (ec) std::filesystem::remove(tmp, ec);
        }
    });
    return dict;
}

}  // namespace specula::glint
