// NormalMapLtcPrefilter: sample sets of footprint eBRDFs, the t-EM fits per MIP texel and view (TBB, deterministic),
// fp16 storage, the trilinear/bilinear runtime lookup and the validated, atomically written disk cache.
#include "core/ltc/ltc_prefilter.h"

#include "core/util/cache_dir.h"

#include "core/ltc/ltc_fit.h"
#include "core/ltc/ltc_tables.h"
#include "core/render/lobes/ggx.h"
#include "core/texture/normal_map_gen.h"

#include <glm/gtc/packing.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace specula::ltc {
namespace fs = std::filesystem;

namespace {

constexpr double kThetaMax = 0.999 * 1.5707963267948966;  // thesis §3.4.1: the last view stops short of grazing
constexpr float kTwoPi = 6.283185307179586f;
constexpr uint32_t kPermute = 0x9E3779B1u;  // odd: i -> i·P mod 2^n is a bijection (the stratum scramble)

struct Fnv {
    uint64_t h = 0xcbf29ce484222325ULL;
    void add(const void* p, size_t n) {
        const unsigned char* b = static_cast<const unsigned char*>(p);
        for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 0x100000001b3ULL;
    }
    template <class T>
    void value(const T& v) {
        add(&v, sizeof v);
    }
};

// Integer hash (splitmix64 finaliser) for the per-block texel positions of the large-tile sampling.
uint64_t hash64(uint64_t z) {
    z += 0x9E3779B97F4A7C15ULL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

bool isPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }
int log2i(int n) {
    int l = 0;
    while ((1 << (l + 1)) <= n) ++l;
    return l;
}

Vec3 clampNormal(Vec3 n) {
    // Same rule as LEAN (core/texture/lean_moments.cpp): |slope| <= 16, so the texel frame stays defined.
    float nz = std::max(n.z, std::max(std::abs(n.x), std::abs(n.y)) / 16.f);
    n.z = nz;
    float l2 = glm::dot(n, n);
    if (!(l2 > 0.f)) return Vec3(0, 0, 1);
    return n / std::sqrt(l2);
}

// Rotation about z by -φ: geometric frame -> view-aligned frame (the view's azimuth becomes 0; thesis §3.4.1 step 4).
Mat3 toViewAligned(float phi) {
    float c = std::cos(phi), s = std::sin(phi);
    Mat3 m(1.f);
    m[0][0] = c, m[1][0] = s;   // row 0: ( c, s, 0)
    m[0][1] = -s, m[1][1] = c;  // row 1: (-s, c, 0)
    return m;
}

Vec3 viewDir(double theta, double phi) {
    return Vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
}
double viewTheta(int j, int n) { return n > 1 ? double(j) / double(n - 1) * kThetaMax : 0.0; }
double viewPhi(int k, int n) { return double(k) / double(n) * 2.0 * 3.14159265358979323846; }

float frobenius(const Mat3& m) {
    float s = 0.f;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) s += m[c][r] * m[c][r];
    return std::sqrt(s);
}

// One planned sample of a tile: a level-0 texel and the sample numbers of its VNDF/cosine draw.
struct PlannedSample {
    int texel;
    Vec2 u;
};

// The sample plan of texel (tx, ty) of level l (§5.3; see the class comment): identical for every view.
void planTile(int size, int l, int tx, int ty, int maxSamples, std::vector<PlannedSample>& out) {
    out.clear();
    const int T = 1 << l;
    const int n = T * T;
    if (n <= maxSamples) {
        const int k = std::max(1, int(std::floor(std::sqrt(double(maxSamples) / double(n)))));
        for (int ly = 0; ly < T; ++ly)
            for (int lx = 0; lx < T; ++lx) {
                const uint32_t i = uint32_t(ly * T + lx);
                const uint32_t c = (i * kPermute) & uint32_t(n - 1);  // distinct cell of the T×T offset grid
                const float ox = (float(c % uint32_t(T)) + 0.5f) / float(T), oy = (float(c / uint32_t(T)) + 0.5f) / float(T);
                const int texel = (ty * T + ly) * size + (tx * T + lx);
                for (int b = 0; b < k; ++b)
                    for (int a = 0; a < k; ++a)
                        out.push_back({texel, Vec2((float(a) + ox) / float(k), (float(b) + oy) / float(k))});
            }
        return;
    }
    // Large tiles: m×m blocks of s×s texels (m the largest power of two with m² <= maxSamples), one texel per block
    // at a hashed position (the same in every tile of the level, like the thesis's shared permutation), one cell of the
    // m×m stratified grid each.
    int m = 1;
    while ((2 * m) * (2 * m) <= maxSamples && 2 * m <= T) m *= 2;
    const int s = T / m;
    for (int by = 0; by < m; ++by)
        for (int bx = 0; bx < m; ++bx) {
            const uint32_t bi = uint32_t(by * m + bx);
            const uint64_t h = hash64((uint64_t(l) << 40) ^ bi);
            const int hx = int(h % uint64_t(s)), hy = int((h >> 32) % uint64_t(s));
            const uint32_t c = (bi * kPermute) & uint32_t(m * m - 1);
            const Vec2 u((float(c % uint32_t(m)) + 0.5f) / float(m), (float(c / uint32_t(m)) + 0.5f) / float(m));
            out.push_back({(ty * T + by * s + hy) * size + (tx * T + bx * s + hx), u});
        }
}

void storeRecord(uint16_t* dst, const Ltc& l) {
    const float norm = frobenius(l.invM);
    const float inv = norm > 0.f ? 1.f / norm : 1.f;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) dst[c * 3 + r] = glm::packHalf1x16(l.invM[c][r] * inv);
    dst[9] = glm::packHalf1x16(l.magnitude);
    dst[10] = glm::packHalf1x16(l.fresnel);
}

// Sum of weight·magnitude·inv(M) (normalised), weight·magnitude and weight·fresnel: the lookup's linear filter.
struct Acc {
    float m[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    float mag = 0.f, fres = 0.f;
    void addMatrix(const Mat3& invM, float wm) {
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) m[c * 3 + r] += wm * invM[c][r];
    }
    Mat3 matrix() const {
        Mat3 r;
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) r[c][k] = m[c * 3 + k];
        return r;
    }
};

Ltc finish(const Acc& g, const Acc& v, const Mat3& viewToGeomRight) {
    // invM (geometric) = invM_view · Rz(-φ) for the stored levels, plus the level-0 part already geometric.
    Mat3 m = v.matrix() * viewToGeomRight + g.matrix();
    Ltc l;
    l.magnitude = g.mag + v.mag;
    l.fresnel = g.fres + v.fres;
    if (frobenius(m) > 0.f && l.magnitude > 0.f) l.invM = m;
    return l;
}

LtcPair zeroPair() {
    LtcPair p;
    p.spec.magnitude = p.spec.fresnel = 0.f;
    p.diffuse.magnitude = p.diffuse.fresnel = 0.f;
    return p;
}

}  // namespace

Mat3 NormalMapLtcPrefilter::texelRotation(const Vec3& n) {
    // Rodrigues rotation about z × n by acos(n_z): the minimal rotation z -> n (thesis R0); n_z > 0 after clamping.
    const float a = 1.f / (1.f + n.z);
    Vec3 t(1.f - n.x * n.x * a, -n.x * n.y * a, -n.x);
    Vec3 b(-n.x * n.y * a, 1.f - n.y * n.y * a, -n.y);
    return Mat3(t, b, n);
}

std::vector<Vec3> NormalMapLtcPrefilter::normalsOf(const NormalMap& map) {
    const int n = map.size;
    std::vector<Vec3> out(size_t(n) * size_t(n));
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) out[size_t(y) * n + x] = map.at(x, n - 1 - y);  // store bottom-up
    return out;
}

std::vector<Vec3> NormalMapLtcPrefilter::normalsFromEncodedPixels(const float* pixels, int width, int height,
                                                                   int channels, bool directx) {
    if (!pixels || width <= 0 || height <= 0) throw PrefilterError("LTC prefilter: empty normal map");
    if (channels < 2) throw PrefilterError("LTC prefilter: a normal map needs at least 2 channels");
    if (width != height || !isPowerOfTwo(width))
        throw PrefilterError("LTC prefilter: the normal map must be square with a power-of-two size (got " +
                             std::to_string(width) + "x" + std::to_string(height) + ")");
    std::vector<Vec3> out(size_t(width) * size_t(height));
    for (int y = 0; y < height; ++y) {
        const int srcRow = height - 1 - y;
        for (int x = 0; x < width; ++x) {
            const float* p = pixels + (size_t(srcRow) * width + x) * size_t(channels);
            out[size_t(y) * width + x] = decodeNormalPixel(p, channels, directx);
        }
    }
    return out;
}

uint64_t NormalMapLtcPrefilter::contentHash(const std::vector<Vec3>& normals, int size, const PrefilterSettings& s) {
    Fnv f;
    f.add("SPCLTCPF", 8);
    f.value(kFormatVersion);
    f.value(int32_t(size));
    f.value(s.alpha);
    for (int v : {s.specTheta, s.specPhi, s.diffTheta, s.diffPhi, s.maxSamples, s.iterations}) f.value(int32_t(v));
    // The magnitudes come from the base table (fitAll), so its version is part of the content.
    const std::string th = builtinTables().hash();
    f.add(th.data(), th.size());
    for (const Vec3& n : normals) {
        Vec3 c = clampNormal(n);
        f.add(&c, sizeof c);
    }
    return f.h;
}

void NormalMapLtcPrefilter::initLayout(const std::vector<Vec3>& normals, int size, const PrefilterSettings& s) {
    if (!isPowerOfTwo(size)) throw PrefilterError("LTC prefilter: size must be a power of two (got " + std::to_string(size) + ")");
    if (normals.size() != size_t(size) * size_t(size)) throw PrefilterError("LTC prefilter: normals.size() != size²");
    if (s.specTheta < 1 || s.specPhi < 1 || s.diffTheta < 1 || s.diffPhi < 1 || s.maxSamples < 1 || s.iterations < 1)
        throw PrefilterError("LTC prefilter: view grids, sample count and iterations must be >= 1");
    if (!(s.alpha > 0.f) || !(s.alpha <= 1.f)) throw PrefilterError("LTC prefilter: alpha must be in (0, 1]");
    size_ = size;
    levels_ = log2i(size);
    settings_ = s;
    normals_.resize(normals.size());
    for (size_t i = 0; i < normals.size(); ++i) normals_[i] = clampNormal(normals[i]);
    levelOffset_.assign(size_t(levels_) + 2, 0);
    for (int l = 1; l <= levels_; ++l) {
        const size_t w = size_t(size >> l);
        levelOffset_[size_t(l) + 1] = levelOffset_[size_t(l)] + w * w;
    }
    hash_ = contentHash(normals, size, s);
}

void NormalMapLtcPrefilter::fitAll() {
    const PrefilterSettings& s = settings_;
    const int nSpec = s.specTheta * s.specPhi, nDiff = s.diffTheta * s.diffPhi;
    const size_t nTexels = texelCount();
    spec_.assign(nTexels * size_t(nSpec) * kRecordHalfs, 0);
    diffuse_.assign(nTexels * size_t(nDiff) * kRecordHalfs, 0);
    std::vector<Mat3> rot(normals_.size());
    for (size_t i = 0; i < normals_.size(); ++i) rot[i] = texelRotation(normals_[i]);
    const float alpha = std::max(s.alpha, 1e-3f);
    const LtcTables& tables = builtinTables();

    // Magnitude and Fresnel moment of every stored (texel, view), exactly: the mean over the footprint's level-0 texels
    // of the base table's values for each texel (0 where it faces away), i.e. the albedo of the thesis's ground truth
    // (eq. 3.5 with the base LTC per texel) and of the level-0 lookup, so the 0-1 level blend has no jump. The mean
    // G2/G1 weight of 256 stratified VNDF samples is biased by up to ~1% at α ≈ 0.1 (the weight drops steeply near
    // the VNDF disk's rim, which a 16×16 midpoint grid under-samples), above T12's 5e-3. Per view: level-0 values, then
    // exact 2×2 box means level by level (double).
    const int nSpecV = s.specTheta * s.specPhi, nDiffV = s.diffTheta * s.diffPhi;
    std::vector<float> specMoments(nTexels * size_t(nSpecV) * 2), diffMag(nTexels * size_t(nDiffV));
    tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(0, nSpecV + nDiffV, [&](int v) {
            const bool diffuse = v >= nSpecV;
            const int vi = diffuse ? v - nSpecV : v;
            const int nt = diffuse ? s.diffTheta : s.specTheta, np = diffuse ? s.diffPhi : s.specPhi;
            const Vec3 wo = viewDir(viewTheta(vi / np, nt), viewPhi(vi % np, np));
            int w = size_;
            std::vector<double> cur(size_t(w) * w * 2);
            for (size_t q = 0; q < cur.size() / 2; ++q) {
                const Vec3 woT = glm::transpose(rot[q]) * wo;
                if (!(woT.z > 1e-6f)) {
                    cur[2 * q] = cur[2 * q + 1] = 0.0;
                } else if (diffuse) {
                    cur[2 * q] = 1.0, cur[2 * q + 1] = 0.0;
                } else {
                    const Ltc b = ggxIsotropic(tables, alpha, woT);
                    cur[2 * q] = b.magnitude, cur[2 * q + 1] = b.fresnel;
                }
            }
            for (int l = 1; l <= levels_; ++l) {
                const int nw = w / 2;
                std::vector<double> next(size_t(nw) * nw * 2);
                for (int y = 0; y < nw; ++y)
                    for (int x = 0; x < nw; ++x)
                        for (int c = 0; c < 2; ++c)
                            next[(size_t(y) * nw + x) * 2 + c] =
                                0.25 * (cur[(size_t(2 * y) * w + 2 * x) * 2 + c] + cur[(size_t(2 * y) * w + 2 * x + 1) * 2 + c] +
                                        cur[(size_t(2 * y + 1) * w + 2 * x) * 2 + c] +
                                        cur[(size_t(2 * y + 1) * w + 2 * x + 1) * 2 + c]);
                cur.swap(next);
                w = nw;
                for (size_t t = 0; t < size_t(w) * w; ++t) {
                    const size_t flat = levelOffset_[size_t(l)] + t;
                    if (diffuse) {
                        diffMag[flat * size_t(nDiffV) + size_t(vi)] = float(cur[2 * t]);
                    } else {
                        specMoments[(flat * size_t(nSpecV) + size_t(vi)) * 2] = float(cur[2 * t]);
                        specMoments[(flat * size_t(nSpecV) + size_t(vi)) * 2 + 1] = float(cur[2 * t + 1]);
                    }
                }
            }
        });
    });

    // One texel of one level: its plan, then every view. Texels are independent, so the result does not depend on
    // how TBB splits the range. isolate(): a render thread that triggers a fit while holding a lock cannot pick up
    // another render task (which could wait on that lock) from inside this parallel loop.
    auto fitTexel = [&](size_t flat, std::vector<PlannedSample>& plan, std::vector<WeightedDirection>& dirs) {
        int l = 1;
        while (flat >= levelOffset_[size_t(l) + 1]) ++l;
        const int w = size_ >> l;
        const size_t local = flat - levelOffset_[size_t(l)];
        const int tx = int(local % size_t(w)), ty = int(local / size_t(w));
        planTile(size_, l, tx, ty, s.maxSamples, plan);
        for (int pass = 0; pass < 2; ++pass) {
            const bool diffuse = pass == 1;
            const int nt = diffuse ? s.diffTheta : s.specTheta, np = diffuse ? s.diffPhi : s.specPhi;
            for (int j = 0; j < nt; ++j)
                for (int k = 0; k < np; ++k) {
                    const double theta = viewTheta(j, nt), phi = viewPhi(k, np);
                    const Vec3 wo = viewDir(theta, phi);
                    const Mat3 align = toViewAligned(float(phi));
                    dirs.clear();
                    double wsum = 0.0;
                    for (const PlannedSample& ps : plan) {
                        const Mat3& R = rot[size_t(ps.texel)];
                        const Vec3 woT = glm::transpose(R) * wo;
                        if (!(woT.z > 1e-6f)) continue;  // texel faces away from the view: weight 0
                        Vec3 wiT;
                        float weight = 1.f;
                        if (!diffuse) {
                            // VNDF sample weighted by G2/G1 (height-correlated Smith: (1 + Λo)/(1 + Λo + Λi)), so the
                            // mean weight is the texel's ∫ f·cos with F = 1 (ltc-filtering.md §5.2 "weights G2/G1").
                            const Vec3 h = ggx::sampleVisibleNormal(woT, ps.u, alpha, alpha);
                            wiT = ggx::reflect(woT, h);
                            if (!(wiT.z > 0.f)) continue;
                            const float lo = ggx::lambda(woT, alpha, alpha), li = ggx::lambda(wiT, alpha, alpha);
                            weight = (1.f + lo) / (1.f + lo + li);
                        } else {
                            // Cosine sample (Malley) in the texel frame: Lambert f·cos has unit albedo per texel.
                            const float r = std::sqrt(ps.u.x), ph = kTwoPi * ps.u.y;
                            wiT = Vec3(r * std::cos(ph), r * std::sin(ph), std::sqrt(std::max(0.f, 1.f - ps.u.x)));
                        }
                        wsum += weight;
                        dirs.push_back({glm::normalize(align * (R * wiT)), weight});
                    }
                    Ltc fit;
                    if (!dirs.empty() && wsum > 0.0) fit = fitStudentT(dirs, Vec3(1, 0, 0), s.iterations);
                    // The eBRDF is the equal-weight mixture over the footprint texels (thesis eq. 3.5): its albedo
                    // and Fresnel moment are the exact footprint means computed above.
                    const size_t vi = size_t(j * np + k);
                    fit.magnitude = diffuse ? diffMag[flat * size_t(nDiffV) + vi] : specMoments[(flat * size_t(nSpecV) + vi) * 2];
                    fit.fresnel = diffuse ? 0.f : specMoments[(flat * size_t(nSpecV) + vi) * 2 + 1];
                    std::vector<uint16_t>& dst = diffuse ? diffuse_ : spec_;
                    storeRecord(&dst[(flat * size_t(nt * np) + size_t(j * np + k)) * kRecordHalfs], fit);
                }
        }
    };
    tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, nTexels), [&](const tbb::blocked_range<size_t>& r) {
            std::vector<PlannedSample> plan;
            std::vector<WeightedDirection> dirs;
            plan.reserve(size_t(s.maxSamples));
            dirs.reserve(size_t(s.maxSamples));
            for (size_t t = r.begin(); t != r.end(); ++t) fitTexel(t, plan, dirs);
        });
    });
}

NormalMapLtcPrefilter NormalMapLtcPrefilter::build(const std::vector<Vec3>& normals, int size, const PrefilterSettings& s) {
    NormalMapLtcPrefilter p;
    p.initLayout(normals, size, s);
    p.fitAll();
    return p;
}

// ---- lookup -------------------------------------------------------------------------------------------------------

void NormalMapLtcPrefilter::thetaScales(float theta, const LtcTables& tables, float* out) const {
    // Magnitude and Fresnel moment are interpolated in θ as ratios to those of the flat surface (the base table at
    // the same α): the albedo's curvature in θ near grazing is mostly the flat GGX's, which the ratio divides out
    // (a flat map is then exact between the view rows; plain linear interpolation was off by 6e-3 at 68°).
    const int nt = settings_.specTheta;
    out[0] = out[1] = out[2] = out[3] = 1.f;
    if (nt < 2) return;
    float tt = std::min(std::max(float(double(theta) / kThetaMax) * float(nt - 1), 0.f), float(nt - 1));
    const int j0 = std::min(int(std::floor(tt)), nt - 2);
    const float a = std::max(settings_.alpha, 1e-3f);
    const Ltc at = ggxIsotropic(tables, a, Vec3(std::sin(theta), 0.f, std::cos(theta)));
    for (int r = 0; r < 2; ++r) {
        const Ltc node = ggxIsotropic(tables, a, viewDir(viewTheta(j0 + r, nt), 0.0));
        if (node.magnitude > 1e-4f) out[r] = at.magnitude / node.magnitude;
        if (node.fresnel > 1e-4f) out[2 + r] = at.fresnel / node.fresnel;
    }
}

void NormalMapLtcPrefilter::accumulateStored(int level, int x, int y, float theta, float phi, float w, bool diffuse,
                                             const float* scales, float* accRaw) const {
    Acc& acc = *reinterpret_cast<Acc*>(accRaw);
    const int nt = diffuse ? settings_.diffTheta : settings_.specTheta, np = diffuse ? settings_.diffPhi : settings_.specPhi;
    const std::vector<uint16_t>& src = diffuse ? diffuse_ : spec_;
    // θ: linear between the two nearest rows (clamped); φ: linear between the two nearest azimuths, wrapping.
    float tt = nt > 1 ? float(double(theta) / kThetaMax) * float(nt - 1) : 0.f;
    tt = std::min(std::max(tt, 0.f), float(nt - 1));
    int j0 = std::min(int(std::floor(tt)), std::max(nt - 2, 0));
    float ft = nt > 1 ? tt - float(j0) : 0.f;
    float tp = phi / kTwoPi * float(np);
    float fp0 = std::floor(tp);
    float fp = tp - fp0;
    int k0 = ((int(fp0) % np) + np) % np, k1 = (k0 + 1) % np;
    const size_t flat = levelOffset_[size_t(level)] + size_t(y) * size_t(size_ >> level) + size_t(x);
    const int j1 = std::min(j0 + 1, nt - 1);
    // scales = (mag row j0, mag row j1, fres row j0, fres row j1): see thetaScales.
    const float sm[2] = {scales ? scales[0] : 1.f, scales ? scales[1] : 1.f};
    const float sf[2] = {scales ? scales[2] : 1.f, scales ? scales[3] : 1.f};
    const struct {
        int view, row;
        float w;
    } views[4] = {{j0 * np + k0, 0, (1.f - ft) * (1.f - fp)},
                  {j0 * np + k1, 0, (1.f - ft) * fp},
                  {j1 * np + k0, 1, ft * (1.f - fp)},
                  {j1 * np + k1, 1, ft * fp}};
    for (const auto& e : views) {
        const float ww = w * e.w;
        if (ww == 0.f) continue;
        const uint16_t* rec = &src[(flat * size_t(nt * np) + size_t(e.view)) * kRecordHalfs];
        const float mag = glm::unpackHalf1x16(rec[9]) * sm[e.row];
        const float wm = ww * mag;
        for (int k = 0; k < 9; ++k) acc.m[k] += wm * glm::unpackHalf1x16(rec[k]);
        acc.mag += wm;
        acc.fres += ww * glm::unpackHalf1x16(rec[10]) * sf[e.row];
    }
}

LtcPair NormalMapLtcPrefilter::baseTexelLtc(int x, int y, const Vec3& wo, const LtcTables& tables) const {
    LtcPair p = zeroPair();
    const Mat3 R = texelRotation(normals_[size_t(y) * size_ + x]);
    const Mat3 Rt = glm::transpose(R);
    const Vec3 woT = Rt * wo;
    if (!(woT.z > 1e-6f)) return p;  // facing away: no light reflected towards wo (as in the fit)
    Ltc b = ggxIsotropic(tables, std::max(settings_.alpha, 1e-3f), woT);
    p.spec = b;
    p.spec.invM = b.invM * Rt;  // geometric direction -> texel frame -> cosine space
    p.diffuse.invM = Rt;        // the cosine lobe about the texel normal: M = R
    p.diffuse.magnitude = 1.f;
    p.diffuse.fresnel = 0.f;
    return p;
}

LtcPair NormalMapLtcPrefilter::texelLtc(int level, int x, int y, const Vec3& wo, const LtcTables& tables) const {
    if (level < 1 || level > levels_ || !(wo.z > 0.f)) return zeroPair();
    const float theta = std::acos(std::min(wo.z, 1.f));
    float phi = std::atan2(wo.y, wo.x);
    if (phi < 0.f) phi += kTwoPi;
    const Mat3 back = toViewAligned(phi);
    float scales[4];
    thetaScales(theta, tables, scales);
    LtcPair out;
    for (int d = 0; d < 2; ++d) {
        Acc v, g;
        accumulateStored(level, x, y, theta, phi, 1.f, d == 1, d == 1 ? nullptr : scales, reinterpret_cast<float*>(&v));
        (d ? out.diffuse : out.spec) = finish(g, v, back);
    }
    out.diffuse.fresnel = 0.f;
    return out;
}

LtcPair NormalMapLtcPrefilter::lookupLevel(float level, Vec2 uv, const Vec3& wo, const LtcTables& tables) const {
    if (!(wo.z > 0.f) || size_ == 0) return zeroPair();
    const float theta = std::acos(std::min(wo.z, 1.f));
    float phi = std::atan2(wo.y, wo.x);
    if (phi < 0.f) phi += kTwoPi;
    if (!(level > 0.f)) level = 0.f;  // also NaN
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) uv = Vec2(0.f);  // keeps the texel indices defined
    level = std::min(level, float(levels_));
    const int l0 = std::min(int(std::floor(level)), levels_);
    const float f = l0 < levels_ ? level - float(l0) : 0.f;
    Acc gs, gd, vs, vd;  // geometric-frame (level 0) and view-aligned (stored levels) sums, specular and diffuse
    float scales[4] = {1.f, 1.f, 1.f, 1.f};
    if (l0 + (f > 0.f ? 1 : 0) >= 1) thetaScales(theta, tables, scales);
    for (int pass = 0; pass < 2; ++pass) {
        const int l = l0 + pass;
        const float wl = pass == 0 ? 1.f - f : f;
        if (wl <= 0.f) continue;
        const int n = size_ >> l;
        // GL_LINEAR on level l with repeat wrap: texel centres at (i + 1/2)/n.
        const float sx = uv.x * float(n) - 0.5f, sy = uv.y * float(n) - 0.5f;
        const float fx0 = std::floor(sx), fy0 = std::floor(sy);
        const float ax = sx - fx0, ay = sy - fy0;
        const int ix = int(fx0), iy = int(fy0);
        for (int c = 0; c < 4; ++c) {
            const int dx = c & 1, dy = c >> 1;
            const float w = wl * (dx ? ax : 1.f - ax) * (dy ? ay : 1.f - ay);
            if (w == 0.f) continue;
            const int x = (((ix + dx) % n) + n) % n, y = (((iy + dy) % n) + n) % n;
            if (l == 0) {
                LtcPair b = baseTexelLtc(x, y, wo, tables);
                if (b.spec.magnitude > 0.f) {
                    const float nrm = frobenius(b.spec.invM);
                    gs.addMatrix(b.spec.invM, w * b.spec.magnitude / nrm);
                    gs.mag += w * b.spec.magnitude;
                    gs.fres += w * b.spec.fresnel;
                }
                if (b.diffuse.magnitude > 0.f) {
                    gd.addMatrix(b.diffuse.invM, w / std::sqrt(3.f));  // a rotation has Frobenius norm √3
                    gd.mag += w;
                }
            } else {
                accumulateStored(l, x, y, theta, phi, w, false, scales, reinterpret_cast<float*>(&vs));
                accumulateStored(l, x, y, theta, phi, w, true, nullptr, reinterpret_cast<float*>(&vd));
            }
        }
    }
    const Mat3 back = toViewAligned(phi);
    LtcPair out;
    out.spec = finish(gs, vs, back);
    out.diffuse = finish(gd, vd, back);
    out.diffuse.fresnel = 0.f;
    return out;
}

LtcPair NormalMapLtcPrefilter::lookup(Vec2 uv, Vec2 duvdx, Vec2 duvdy, const Vec3& wo, const LtcTables& tables) const {
    // Isotropic footprint (GL's ρ = max of the axis lengths in texels), as LeanFilter::Trilinear.
    const float rho = std::max(std::sqrt(glm::dot(duvdx, duvdx)), std::sqrt(glm::dot(duvdy, duvdy))) * float(size_);
    const float level = rho > 0.f ? std::log2(rho) : 0.f;
    return lookupLevel(level, uv, wo, tables);
}

// ---- disk cache ---------------------------------------------------------------------------------------------------

namespace {

// The request a cache file answers, at the start of its payload (an entry of the cache service, core/util/cache_dir.h,
// whose header holds the format tag, the size and the content checksum); every field is checked on read against what
// the parameters imply. No padding: the file's bytes are a function of its content.
struct RequestHeader {
    uint32_t version;
    uint32_t size;
    uint32_t levels;
    uint32_t specTheta, specPhi, diffTheta, diffPhi;
    uint32_t maxSamples, iterations;
    uint32_t recordHalfs;
    float alpha;
    uint32_t reserved;
    uint64_t hash;
    uint64_t specCount, diffCount;  // uint16 values in each payload
};
static_assert(sizeof(RequestHeader) == 72, "cache header layout");

std::string cacheTag() { return "ltc-prefilter " + std::to_string(NormalMapLtcPrefilter::kFormatVersion); }

RequestHeader expectedHeader(const NormalMapLtcPrefilter& p) {
    RequestHeader h{};
    const PrefilterSettings& s = p.settings();
    h.version = NormalMapLtcPrefilter::kFormatVersion;
    h.size = uint32_t(p.size());
    h.levels = uint32_t(p.levels());
    h.specTheta = uint32_t(s.specTheta), h.specPhi = uint32_t(s.specPhi);
    h.diffTheta = uint32_t(s.diffTheta), h.diffPhi = uint32_t(s.diffPhi);
    h.maxSamples = uint32_t(s.maxSamples), h.iterations = uint32_t(s.iterations);
    h.recordHalfs = NormalMapLtcPrefilter::kRecordHalfs;
    h.alpha = s.alpha;
    h.reserved = 0;
    h.hash = p.hash();
    return h;
}

}  // namespace

std::string NormalMapLtcPrefilter::defaultCacheDir() {
    if (const char* e = std::getenv("SPECULA_CACHE_DIR"); e && *e) return (fs::path(e) / "ltc").string();
    if (const char* e = std::getenv("XDG_CACHE_HOME"); e && *e) return (fs::path(e) / "specula" / "ltc").string();
    if (const char* e = std::getenv("HOME"); e && *e) return (fs::path(e) / ".cache" / "specula" / "ltc").string();
    return (fs::temp_directory_path() / ("specula-" + std::to_string(getuid())) / "ltc").string();
}

std::string NormalMapLtcPrefilter::cachePath(const std::string& dir, uint64_t hash) {
    char name[40];
    std::snprintf(name, sizeof name, "prefilter-%016llx.bin", static_cast<unsigned long long>(hash));
    return (fs::path(dir) / name).string();
}

bool NormalMapLtcPrefilter::writeFile(const std::string& path) const {
    RequestHeader h = expectedHeader(*this);
    h.specCount = spec_.size();
    h.diffCount = diffuse_.size();
    return writeCacheEntry(path, cacheTag(),
                           {{&h, sizeof h},
                            {spec_.data(), spec_.size() * sizeof(uint16_t)},
                            {diffuse_.data(), diffuse_.size() * sizeof(uint16_t)}});
}

bool NormalMapLtcPrefilter::readFile(const std::string& path, const std::vector<Vec3>& normals, int size,
                                     const PrefilterSettings& s) {
    NormalMapLtcPrefilter p;
    try {
        p.initLayout(normals, size, s);
    } catch (const PrefilterError&) {
        return false;
    }
    const RequestHeader want = expectedHeader(p);
    const uint64_t specCount = p.texelCount() * uint64_t(s.specTheta * s.specPhi) * kRecordHalfs;
    const uint64_t diffCount = p.texelCount() * uint64_t(s.diffTheta * s.diffPhi) * kRecordHalfs;
    // The size is fixed by the parameters: anything else (truncated, padded, another layout) is rejected before
    // any allocation from file data.
    const uint64_t bytes = sizeof(RequestHeader) + (specCount + diffCount) * sizeof(uint16_t);
    std::vector<uint8_t> payload;
    if (readCacheEntry(path, cacheTag(), bytes, payload) != CacheLookup::Hit) return false;
    RequestHeader h{};
    if (payload.size() != bytes) {
        warnCorruptCacheEntry(path, "has the wrong size for its settings");
        return false;
    }
    std::memcpy(&h, payload.data(), sizeof h);
    if (h.version != want.version || h.size != want.size || h.levels != want.levels || h.specTheta != want.specTheta ||
        h.specPhi != want.specPhi || h.diffTheta != want.diffTheta || h.diffPhi != want.diffPhi ||
        h.maxSamples != want.maxSamples || h.iterations != want.iterations || h.recordHalfs != want.recordHalfs ||
        std::memcmp(&h.alpha, &want.alpha, sizeof(float)) != 0 || h.hash != want.hash || h.specCount != specCount ||
        h.diffCount != diffCount) {
        warnCorruptCacheEntry(path, "answers other settings or another normal map");
        return false;
    }
    p.spec_.resize(size_t(specCount));
    p.diffuse_.resize(size_t(diffCount));
    std::memcpy(p.spec_.data(), payload.data() + sizeof h, size_t(specCount) * sizeof(uint16_t));
    std::memcpy(p.diffuse_.data(), payload.data() + sizeof h + size_t(specCount) * sizeof(uint16_t),
                size_t(diffCount) * sizeof(uint16_t));
    *this = std::move(p);
    return true;
}

std::shared_ptr<const NormalMapLtcPrefilter> NormalMapLtcPrefilter::loadOrBuild(const std::vector<Vec3>& normals, int size,
                                                                                const PrefilterSettings& s,
                                                                                const std::string& dir,
                                                                                CacheOutcome* outcome) {
    auto p = std::make_shared<NormalMapLtcPrefilter>();
    if (dir.empty()) {
        *p = build(normals, size, s);
        if (outcome) *outcome = CacheOutcome::FittedNoCache;
        return p;
    }
    const std::string path = cachePath(dir, contentHash(normals, size, s));
    std::error_code ec;
    const bool existed = fs::exists(path, ec);
    if (existed && p->readFile(path, normals, size, s)) {
        if (outcome) *outcome = CacheOutcome::Loaded;
        return p;
    }
    *p = build(normals, size, s);
    fs::create_directories(dir, ec);
    p->writeFile(path);  // best effort: an unwritable cache only costs the refit next time
    if (outcome) *outcome = existed ? CacheOutcome::FittedAfterInvalidCache : CacheOutcome::Fitted;
    return p;
}

}  // namespace specula::ltc
