// LTC normal-map prefilter (core/ltc/ltc_prefilter.h) against ltc-filtering.md §6: T12 (flat map = base table),
// T13 (per-texel ground truth, naive and LEAN-iso baselines), T14 (90° rotation), determinism, cache, the node.
#include "core/ltc/ltc_prefilter.h"
#include "core/codegen/glsl_emitter.h"
#include "core/codegen/glsl_manifest.h"
#include "core/color/color_config.h"
#include "core/io/image_io.h"

#include "core/graph/graph_material.h"
#include "core/ltc/ltc_tables.h"
#include "core/render/renderer.h"
#include "core/render/sampler.h"
#include "core/scene/scene_loader.h"
#include "core/texture/normal_map_gen.h"
#include "tests/unit/test_support.h"

#include <glm/gtc/packing.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <vector>

using namespace specula;
using namespace specula::ltc;
namespace fs = std::filesystem;

namespace {

constexpr double kPiD = 3.14159265358979323846;

// Every test of this binary writes its caches into a private directory (never the user's cache).
struct CacheEnv : ::testing::Environment {
    void SetUp() override { setenv("SPECULA_CACHE_DIR", test::tempDir("ltc-prefilter-cache").c_str(), 1); }
};
const auto* const kEnv = ::testing::AddGlobalTestEnvironment(new CacheEnv);

struct Rng {
    uint64_t s;
    double next() { return double(mix64(++s) >> 11) * (1.0 / 9007199254740992.0); }
};

Vec3 dirDeg(double thetaDeg, double phiDeg) {
    double t = thetaDeg * kPiD / 180, p = phiDeg * kPiD / 180;
    return Vec3(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)), float(std::cos(t)));
}

// A GLITTER-like map (ltc-filtering.md §5.2 table: iid flakes, rms 20°): every texel an independent normal whose tilt
// is Rayleigh-distributed with RMS 20° and uniform azimuth (counter-based hash: deterministic).
std::vector<Vec3> iidMap(int size, double rmsDeg, uint64_t seed) {
    std::vector<Vec3> n(size_t(size) * size);
    const double sigma = rmsDeg * kPiD / 180 / std::sqrt(2.0);
    for (size_t i = 0; i < n.size(); ++i) {
        double u1 = double(mix64(seed * 0x1000003 + 2 * i) >> 11) * (1.0 / 9007199254740992.0);
        double u2 = double(mix64(seed * 0x1000003 + 2 * i + 1) >> 11) * (1.0 / 9007199254740992.0);
        double tilt = sigma * std::sqrt(-2.0 * std::log(std::max(1.0 - u1, 1e-300)));
        n[i] = dirDeg(tilt * 180 / kPiD, 360 * u2);
    }
    return n;
}
std::vector<Vec3> flatMap(int size) { return std::vector<Vec3>(size_t(size) * size, Vec3(0, 0, 1)); }

// Random quads fully above the horizon (ltc-filtering.md §6: random size and tilt): centre elevation 5°..80° above the
// horizon... expressed as zenith angle 0..70°, distance 1..3, half-sizes 0.1..1, normal tilted up to 40° away from
// facing the point, any in-plane rotation; vertices with z < 0.02 are rejected.
struct Quad {
    Vec3 v[4];
};
std::vector<Quad> randomQuads(int n, uint64_t seed) {
    Rng r{seed};
    std::vector<Quad> out;
    while (int(out.size()) < n) {
        Vec3 c = dirDeg(70 * r.next(), 360 * r.next()) * float(1 + 2 * r.next());
        Vec3 face = glm::normalize(-c + dirDeg(40 * r.next(), 360 * r.next()) * glm::length(c) * 0.7f);
        Frame f = Frame::fromNormal(face);
        double rot = 2 * kPiD * r.next();
        Vec3 e1 = float(std::cos(rot)) * f.t + float(std::sin(rot)) * f.b, e2 = glm::cross(face, e1);
        float a = float(0.1 + 0.9 * r.next()), b = float(0.1 + 0.9 * r.next());
        Quad q{{c - a * e1 - b * e2, c + a * e1 - b * e2, c + a * e1 + b * e2, c - a * e1 + b * e2}};
        bool ok = true;
        for (const Vec3& v : q.v) ok &= v.z > 0.02f;
        if (ok) out.push_back(q);
    }
    return out;
}

// mag·∫_P D (two-sided, exact clipping: the quads are above the horizon, the LTC's support need not be).
double quadIntegral(const Ltc& l, const Quad& q) {
    if (!(l.magnitude > 0.f)) return 0.0;
    return double(l.magnitude) * integrate(l, q.v, 4, true, Horizon::Clip, nullptr);
}

// The texels of level-l texel (x, y) at level 0.
std::vector<std::pair<int, int>> footprint(int l, int x, int y) {
    std::vector<std::pair<int, int>> t;
    const int T = 1 << l;
    for (int j = 0; j < T; ++j)
        for (int i = 0; i < T; ++i) t.push_back({x * T + i, y * T + j});
    return t;
}

// An LTC of the base table on a tilted normal n with roughness alpha, in the geometric frame (the baselines).
Ltc tiltedBase(const Vec3& n, float alpha, const Vec3& wo) {
    Ltc l;
    l.magnitude = 0.f;
    const Mat3 R = NormalMapLtcPrefilter::texelRotation(n);
    const Vec3 woT = glm::transpose(R) * wo;
    if (!(woT.z > 1e-6f)) return l;
    l = ggxIsotropic(builtinTables(), std::min(alpha, 1.f), woT);
    l.invM = l.invM * glm::transpose(R);
    return l;
}

// Errors of one method against the per-texel ground truth, over quads.
struct Errors {
    double absSum = 0;  // Σ |err| / albedo
    int absCount = 0;
    std::vector<double> rel;  // |err| / E_gt for quads with E_gt > 5% of the albedo
    void add(double est, double gt, double albedo) {
        absSum += std::abs(est - gt) / albedo;
        ++absCount;
        if (gt > 0.05 * albedo) rel.push_back(std::abs(est - gt) / gt);
    }
    double mean() const { return absCount ? absSum / absCount : 0.0; }
    double median() {
        if (rel.empty()) return 0.0;
        std::nth_element(rel.begin(), rel.begin() + rel.size() / 2, rel.end());
        return rel[rel.size() / 2];
    }
};

// Texels of level l to test: all for small levels, else a spread of 6.
std::vector<std::pair<int, int>> testTexels(int w, uint64_t seed) {
    std::vector<std::pair<int, int>> t;
    if (w * w <= 6) {
        for (int y = 0; y < w; ++y)
            for (int x = 0; x < w; ++x) t.push_back({x, y});
        return t;
    }
    Rng r{seed};
    for (int k = 0; k < 6; ++k) t.push_back({int(r.next() * w) % w, int(r.next() * w) % w});
    return t;
}

}  // namespace

TEST(LtcPrefilter, FlatMapReproducesTheBaseTableAtEveryLevelAndView) {  // T12
    const LtcTables& tables = builtinTables();
    const std::vector<Quad> quads = randomQuads(24, 11);
    for (float alpha : {0.09f, 0.25f}) {
        PrefilterSettings s;
        s.alpha = alpha;
        const NormalMapLtcPrefilter P = NormalMapLtcPrefilter::build(flatMap(16), 16, s);
        double worstMean = 0, worstMag = 0;
        for (int l = 1; l <= P.levels(); ++l)
            for (double th : {0.0, 10.0, 25.0, 40.0, 52.0, 60.0, 68.0, 75.0})
                for (double ph : {0.0, 33.0, 200.0}) {
                    const Vec3 wo = dirDeg(th, ph);
                    const Ltc base = ggxIsotropic(tables, alpha, wo);
                    const LtcPair got = P.texelLtc(l, (3 * l) % (16 >> l), 0, wo, tables);
                    worstMag = std::max(worstMag, double(std::abs(got.spec.magnitude - base.magnitude)));
                    double sum = 0;
                    for (const Quad& q : quads) sum += std::abs(quadIntegral(got.spec, q) - quadIntegral(base, q));
                    const double mean = sum / quads.size() / base.magnitude;
                    worstMean = std::max(worstMean, mean);
                    EXPECT_LE(mean, 0.02) << "alpha " << alpha << " level " << l << " theta " << th << " phi " << ph;
                    EXPECT_NEAR(got.spec.magnitude, base.magnitude, 5e-3) << "level " << l << " theta " << th;
                    // Diffuse of a flat map: the cosine lobe with albedo 1.
                    double dsum = 0;
                    for (const Quad& q : quads) {
                        Ltc cosine;
                        dsum += std::abs(quadIntegral(got.diffuse, q) - quadIntegral(cosine, q));
                    }
                    EXPECT_LE(dsum / quads.size(), 0.02) << "diffuse, level " << l << " theta " << th;
                    EXPECT_NEAR(got.diffuse.magnitude, 1.f, 5e-3);
                }
        std::printf("  T12 alpha %.2f: worst quad mean |err|/mag %.4f, worst |mag err| %.2e\n", alpha, worstMean, worstMag);
        // Blended levels (MIP 0 = the base table itself): anywhere between 0 and 1 the flat map still matches.
        for (float lv : {0.f, 0.3f, 0.7f, 1.f, 2.5f}) {
            const Vec3 wo = dirDeg(45, 100);
            const Ltc base = ggxIsotropic(tables, alpha, wo);
            const LtcPair got = P.lookupLevel(lv, Vec2(0.37f, 0.81f), wo, tables);
            double sum = 0;
            for (const Quad& q : quads) sum += std::abs(quadIntegral(got.spec, q) - quadIntegral(base, q));
            EXPECT_LE(sum / quads.size() / base.magnitude, 0.02) << "level " << lv;
            EXPECT_NEAR(got.spec.magnitude, base.magnitude, 5e-3) << "level " << lv;
        }
    }
}

namespace {

// T13 on one map: mean |err|/mag <= 0.03 at levels 1..min(6, levels); with 'glitter', the median relative error at
// levels >= 2 at least 2x below the naive MIP's and below LEAN-iso's.
void checkAgainstGroundTruth(const char* name, const std::vector<Vec3>& normals, int size, bool glitter) {
    const float alpha = 0.1f;
    PrefilterSettings s;
    s.alpha = alpha;
    const auto t0 = std::chrono::steady_clock::now();
    const NormalMapLtcPrefilter P = NormalMapLtcPrefilter::build(normals, size, s);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("  T13 %s prefilter %dx%d: %.2f s, %zu bytes\n", name, size, size, secs, P.storageBytes());
    const LtcTables& tables = builtinTables();
    const std::vector<Quad> quads = randomQuads(16, 23);
    for (int l = 1; l <= std::min(6, P.levels()); ++l) {
        Errors tem, naive, lean;
        const int w = size >> l;
        for (auto [x, y] : testTexels(w, 100 + l))
            for (double th : {0.0, 30.0, 60.0, 75.0}) {
                const Vec3 wo = dirDeg(th, 17 + 61 * l + th);
                // Ground truth (thesis eq. 3.5 with the base LTC per texel): the mean of the texels' quad integrals.
                const auto fp = footprint(l, x, y);
                std::vector<double> gt(quads.size(), 0.0);
                double albedo = 0;
                Vec3 nSum(0.f);
                double mx = 0, my = 0, mxx = 0, myy = 0;
                for (auto [i, j] : fp) {
                    const LtcPair b = P.baseTexelLtc(i, j, wo, tables);
                    albedo += b.spec.magnitude;
                    for (size_t k = 0; k < quads.size(); ++k) gt[k] += quadIntegral(b.spec, quads[k]);
                    const Vec3 n = P.normals()[size_t(j) * size + i];
                    nSum += n;
                    const double sx = -n.x / n.z, sy = -n.y / n.z;
                    mx += sx, my += sy, mxx += sx * sx, myy += sy * sy;
                }
                const double N = double(fp.size());
                albedo /= N;
                if (albedo < 1e-3) continue;
                mx /= N, my /= N;
                const double varX = std::max(mxx / N - mx * mx, 0.0), varY = std::max(myy / N - my * my, 0.0);
                const Ltc fit = P.texelLtc(l, x, y, wo, tables).spec;
                const Ltc nv = tiltedBase(glm::normalize(nSum), alpha, wo);
                const Ltc le = tiltedBase(glm::normalize(Vec3(float(-mx), float(-my), 1.f)),
                                          float(std::sqrt(alpha * alpha + varX + varY)), wo);
                for (size_t k = 0; k < quads.size(); ++k) {
                    const double g = gt[k] / N;
                    tem.add(quadIntegral(fit, quads[k]), g, albedo);
                    naive.add(quadIntegral(nv, quads[k]), g, albedo);
                    lean.add(quadIntegral(le, quads[k]), g, albedo);
                }
            }
        const double mt = tem.median(), mn = naive.median(), ml = lean.median();
        std::printf("  T13 %s level %d: t-EM mean |err|/mag %.4f median rel %.3f | naive %.4f / %.3f | LEAN-iso %.4f / %.3f\n",
                    name, l, tem.mean(), mt, naive.mean(), mn, lean.mean(), ml);
        EXPECT_LE(tem.mean(), 0.03) << name << " level " << l;
        if (glitter && l >= 2) {
            EXPECT_LE(2 * mt, mn) << name << " level " << l << ": not 2x better than the naive MIP";
            EXPECT_LT(mt, ml) << name << " level " << l << ": not better than LEAN-iso";
        }
    }
}

}  // namespace

TEST(LtcPrefilter, MatchesPerTexelGroundTruthAndBeatsNaiveAndLeanOnGlitter) {  // T13
    // The spec's GLITTER-like map (§5.2 table): iid per-texel flakes, RMS tilt 20°.
    checkAgainstGroundTruth("iid", iidMap(64, 20, 5), 64, true);
}

TEST(LtcPrefilter, MatchesPerTexelGroundTruthOnGeneratedFlakes) {  // T13 on the generator's flakes (cells ~8 texels)
    checkAgainstGroundTruth("flakes", NormalMapLtcPrefilter::normalsOf(generateNormalMap(NormalMapKind::Flakes, 32, 5)), 32,
                            false);
}

TEST(LtcPrefilter, SmoothMapMatchesGroundTruth) {  // T13 (mean error only: on smooth maps LEAN-iso may win)
    const int size = 32;
    const float alpha = 0.1f;
    const std::vector<Vec3> normals = NormalMapLtcPrefilter::normalsOf(generateNormalMap(NormalMapKind::Stone, size, 3));
    PrefilterSettings s;
    s.alpha = alpha;
    const NormalMapLtcPrefilter P = NormalMapLtcPrefilter::build(normals, size, s);
    const std::vector<Quad> quads = randomQuads(16, 29);
    const LtcTables& tables = builtinTables();
    for (int l = 1; l <= P.levels(); ++l) {
        Errors tem;
        for (auto [x, y] : testTexels(size >> l, 200 + l))
            for (double th : {0.0, 30.0, 60.0, 75.0}) {
                const Vec3 wo = dirDeg(th, 40 + 23 * l);
                const auto fp = footprint(l, x, y);
                std::vector<double> gt(quads.size(), 0.0);
                double albedo = 0;
                for (auto [i, j] : fp) {
                    const LtcPair b = P.baseTexelLtc(i, j, wo, builtinTables());
                    albedo += b.spec.magnitude;
                    for (size_t k = 0; k < quads.size(); ++k) gt[k] += quadIntegral(b.spec, quads[k]);
                }
                albedo /= double(fp.size());
                if (albedo < 1e-3) continue;
                const Ltc fit = P.texelLtc(l, x, y, wo, tables).spec;
                for (size_t k = 0; k < quads.size(); ++k) tem.add(quadIntegral(fit, quads[k]), gt[k] / double(fp.size()), albedo);
            }
        std::printf("  T13 stone level %d: mean |err|/mag %.4f median rel %.3f\n", l, tem.mean(), tem.median());
        EXPECT_LE(tem.mean(), 0.03) << "level " << l;
    }
}

TEST(LtcPrefilter, RotatingMapAndViewBy90DegreesGivesTheSameShading) {  // T14
    const int size = 32;
    const float alpha = 0.1f;
    const std::vector<Vec3> n0 = iidMap(size, 20, 9);
    // Rotation by +90° about z: texel (x, y) -> (S−1−y, x), normal and view (x, y, z) -> (−y, x, z).
    std::vector<Vec3> n1(n0.size());
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const Vec3 n = n0[size_t(y) * size + x];
            n1[size_t(x) * size + (size - 1 - y)] = Vec3(-n.y, n.x, n.z);
        }
    auto rot = [](const Vec3& v) { return Vec3(-v.y, v.x, v.z); };
    PrefilterSettings s;
    s.alpha = alpha;
    const NormalMapLtcPrefilter A = NormalMapLtcPrefilter::build(n0, size, s), B = NormalMapLtcPrefilter::build(n1, size, s);
    const std::vector<Quad> quads = randomQuads(16, 31);
    for (int l = 1; l <= A.levels(); ++l) {
        const int w = size >> l;
        double sum = 0;
        int count = 0;
        for (auto [x, y] : testTexels(w, 300 + l))
            for (double th : {0.0, 30.0, 60.0, 75.0}) {
                const Vec3 wo = dirDeg(th, 10 + 37 * l);
                const LtcPair a = A.texelLtc(l, x, y, wo, builtinTables()), b = B.texelLtc(l, w - 1 - y, x, rot(wo), builtinTables());
                if (a.spec.magnitude < 1e-3f) continue;
                for (const Quad& q : quads) {
                    Quad r{{rot(q.v[0]), rot(q.v[1]), rot(q.v[2]), rot(q.v[3])}};
                    sum += std::abs(quadIntegral(a.spec, q) - quadIntegral(b.spec, r)) / a.spec.magnitude;
                    ++count;
                }
            }
        std::printf("  T14 level %d: mean |diff|/mag %.4f\n", l, sum / count);
        EXPECT_LE(sum / count, 0.03) << "level " << l;
    }
}

TEST(LtcPrefilter, OneAndTwoThreadsAreBitIdentical) {
    const std::vector<Vec3> n = iidMap(16, 20, 13);
    PrefilterSettings s;
    NormalMapLtcPrefilter a, b;
    tbb::task_arena(1).execute([&] { a = NormalMapLtcPrefilter::build(n, 16, s); });
    tbb::task_arena(2).execute([&] { b = NormalMapLtcPrefilter::build(n, 16, s); });
    ASSERT_EQ(a.specRecords().size(), b.specRecords().size());
    EXPECT_TRUE(a.specRecords() == b.specRecords());
    EXPECT_TRUE(a.diffuseRecords() == b.diffuseRecords());
    // Storage: (16² − 1)/3 = 85 texels × (128 + 8) views × 22 bytes.
    EXPECT_EQ(a.storageBytes(), size_t(85 * 136 * 22));
}

TEST(LtcPrefilter, DiskCacheRoundTripAndCorruptFilesAreRefitted) {
    const std::string dir = test::tempDir("ltc-prefilter-roundtrip");
    const std::vector<Vec3> n = iidMap(8, 20, 17);
    PrefilterSettings s;
    s.specTheta = 4, s.specPhi = 8;
    CacheOutcome o;
    auto a = NormalMapLtcPrefilter::loadOrBuild(n, 8, s, dir, &o);
    EXPECT_EQ(o, CacheOutcome::Fitted);
    const std::string path = NormalMapLtcPrefilter::cachePath(dir, a->hash());
    ASSERT_TRUE(fs::exists(path));
    for (const auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path().string(), path) << "a temporary file was left";
    auto b = NormalMapLtcPrefilter::loadOrBuild(n, 8, s, dir, &o);
    EXPECT_EQ(o, CacheOutcome::Loaded);
    EXPECT_TRUE(a->specRecords() == b->specRecords());
    EXPECT_TRUE(a->diffuseRecords() == b->diffuseRecords());
    // Other parameters: another file.
    PrefilterSettings s2 = s;
    s2.alpha = 0.2f;
    EXPECT_NE(NormalMapLtcPrefilter::contentHash(n, 8, s2), a->hash());
    std::vector<Vec3> n2 = n;
    n2[5].x += 0.01f;
    EXPECT_NE(NormalMapLtcPrefilter::contentHash(n2, 8, s), a->hash());

    const std::string good = test::readFile(path);
    auto corruptWith = [&](const std::string& bytes) {
        std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
        NormalMapLtcPrefilter probe;
        EXPECT_FALSE(probe.readFile(path, n, 8, s));
        auto c = NormalMapLtcPrefilter::loadOrBuild(n, 8, s, dir, &o);
        EXPECT_EQ(o, CacheOutcome::FittedAfterInvalidCache);
        EXPECT_TRUE(c->specRecords() == a->specRecords());
        EXPECT_EQ(test::readFile(path), good) << "the refit did not rewrite the cache";
    };
    corruptWith(good.substr(0, good.size() / 2));             // truncated
    corruptWith(good.substr(0, 40));                          // truncated inside the header
    corruptWith("");                                          // empty
    {
        std::string flipped = good;
        flipped[good.size() - 7] ^= 0x20;  // payload bit flip: checksum
        corruptWith(flipped);
    }
    {
        std::string header = good;
        header[12] = char(0x7f);  // size field: 2^31-ish texels claimed
        corruptWith(header);
    }
    corruptWith(good + "extra");  // padded
    corruptWith(std::string(good.size(), 'x'));
    // Settings mismatch with a valid file of other settings at this path: rejected by the header.
    auto other = NormalMapLtcPrefilter::build(n, 8, s2);
    ASSERT_TRUE(other.writeFile(path));
    NormalMapLtcPrefilter probe;
    EXPECT_FALSE(probe.readFile(path, n, 8, s));
    // An unwritable cache directory is not an error.
    auto d = NormalMapLtcPrefilter::loadOrBuild(n, 8, s, "/proc/specula-no-such-dir", &o);
    EXPECT_EQ(o, CacheOutcome::Fitted);
    EXPECT_TRUE(d->specRecords() == a->specRecords());
}

TEST(LtcPrefilter, LookupFiltersAcrossTexelsLevelsAndViews) {
    const int size = 16;
    const std::vector<Vec3> n = iidMap(size, 20, 19);
    PrefilterSettings s;
    const NormalMapLtcPrefilter P = NormalMapLtcPrefilter::build(n, size, s);
    const LtcTables& t = builtinTables();
    const Vec3 wo = dirDeg(35, 70);
    // Texel centres at a whole level give that texel (bilinear weight 1), in both lookup forms.
    const int l = 2, w = size >> l;
    const Vec2 uv((1 + 0.5f) / w, (2 + 0.5f) / w);
    const LtcPair a = P.lookupLevel(float(l), uv, wo, t), b = P.texelLtc(l, 1, 2, wo, t);
    EXPECT_NEAR(a.spec.magnitude, b.spec.magnitude, 1e-6f);
    const Vec2 d(float(1 << l) / size, 0.f);
    const LtcPair c = P.lookup(uv, d, Vec2(0.f), wo, t);
    EXPECT_NEAR(c.spec.magnitude, b.spec.magnitude, 1e-5f);
    // Level 0: the texel's own base LTC; footprint 0 means level 0.
    const Vec2 uv0((5 + 0.5f) / size, (9 + 0.5f) / size);
    const LtcPair z = P.lookup(uv0, Vec2(0.f), Vec2(0.f), wo, t), zb = P.baseTexelLtc(5, 9, wo, t);
    EXPECT_NEAR(z.spec.magnitude, zb.spec.magnitude, 1e-6f);
    EXPECT_NEAR(z.diffuse.magnitude, zb.diffuse.magnitude, 1e-6f);
    // Continuity across the level-0/1 blend and along uv: no jumps in the quad integral.
    const std::vector<Quad> quads = randomQuads(4, 37);
    double prev = -1, worst = 0;
    for (int k = 0; k <= 40; ++k) {
        const LtcPair p = P.lookupLevel(0.025f * k, Vec2(0.3f, 0.6f), wo, t);
        const double e = quadIntegral(p.spec, quads[0]);
        if (prev >= 0) worst = std::max(worst, std::abs(e - prev));
        prev = e;
    }
    EXPECT_LT(worst, 0.05 * std::max(prev, 1e-3));
    // Views below the horizon reflect nothing.
    EXPECT_EQ(P.lookup(uv, d, d, Vec3(0.6f, 0, -0.8f), t).spec.magnitude, 0.f);
    // Non-power-of-two or non-square maps are refused.
    EXPECT_THROW(NormalMapLtcPrefilter::build(flatMap(12), 12, s), PrefilterError);
    std::vector<float> px(16 * 8 * 3, 0.5f);
    EXPECT_THROW(NormalMapLtcPrefilter::normalsFromEncodedPixels(px.data(), 16, 8, 3, false), PrefilterError);
}

// ---- the node -------------------------------------------------------------------------------------------------------

TEST(LtcNormalMapNode, RendersUnderQuadAndEnvironmentLightsAndLtcMatchesSampling) {
    const std::string dir = test::tempDir("ltc-node-scene");
    writeNormalMap(generateNormalMap(NormalMapKind::Flakes, 16, 4), dir + "/flakes.png");
    auto scene = [&](const std::string& areaLights, const std::string& light) {
        return R"({"render": {"width": 24, "height": 18, "spp": 64, "integrator": "direct", "area_lights": ")" + areaLights +
               R"("},
            "camera": {"position": [0, -3, 2.5], "look_at": [0, 0, 0], "fov": 45},
            "materials": {"m": {"nodes": {"n": {"type": "bsdf.ltc_normal_map", "inputs": {"normal_map": "flakes.png",
                "roughness": 0.4, "specular_color": [0.9, 0.8, 0.6], "diffuse_color": 0.3}}}, "output": "@n.bsdf"}},
            "shapes": [{"type": "quad", "size": [4, 4], "material": "m"}],
            "lights": [)" + light + "]}";
    };
    const std::string quad = R"({"type": "quad", "position": [0.2, 0.8, 1.5], "look_at": [0, 0, 0], "size": [1.2, 0.8], "power": 60})";
    Scene ltcScene = loadSceneFromString(scene("ltc", quad), dir);
    Scene sampledScene = loadSceneFromString(scene("sampled", quad), dir);
    RenderOutput a = renderScene(ltcScene), b = renderScene(sampledScene);
    EXPECT_EQ(a.stats.invalidSamples, 0u);
    EXPECT_EQ(b.stats.invalidSamples, 0u);
    for (const char* aov : {"diffuse", "specular"}) {
        const auto& pa = a.images.find(aov)->pixels;
        const auto& pb = b.images.find(aov)->pixels;
        double sa = 0, sb = 0;
        for (size_t i = 0; i < pa.size(); ++i) sa += pa[i], sb += pb[i];
        std::printf("  node %s: ltc %.4f sampled %.4f\n", aov, sa, sb);
        ASSERT_GT(sb, 0.0) << aov;
        EXPECT_NEAR(sa / sb, 1.0, 0.03) << aov << ": analytic quad light != sampled";
    }
    Scene env = loadSceneFromString(scene("ltc", R"({"type": "environment", "color": [0.5, 0.5, 0.5]})"), dir);
    RenderOutput e = renderScene(env);
    EXPECT_EQ(e.stats.invalidSamples, 0u);
    double sum = 0;
    for (float v : e.images.find("beauty")->pixels) {
        ASSERT_TRUE(std::isfinite(v));
        sum += v;
    }
    EXPECT_GT(sum, 0.0);
}

TEST(LtcNormalMapNode, GeneratedMapsFlatStrengthAndMirroredFrames) {
    // strength 0 is the flat map: the specular lobe equals the base table's (MIP 0) and the diffuse the cosine lobe.
    auto shade = [](const nlohmann::json& inputs, const ShadingPoint& sp, ScratchArena& arena, Closure& cl) {
        nlohmann::json m = {{"nodes", {{"n", {{"type", "bsdf.ltc_normal_map"}, {"inputs", inputs}}}}}, {"output", "@n.bsdf"}};
        auto mat = loadGraphMaterial(m, "/materials/x", GraphLoadContext{});
        mat->shade(sp, arena, cl);
        return mat;
    };
    ShadingPoint sp;
    sp.n = sp.ng = Vec3(0, 0, 1);
    sp.tangent = Vec4(1, 0, 0, 1);
    sp.uv = Vec2(0.3f, 0.4f);
    sp.wo = dirDeg(40, 20);
    ScratchArena arena;
    Closure cl;
    auto m0 = shade({{"normal_map", "generate:flakes:16:2"}, {"strength", 0.0}, {"roughness", 0.5}}, sp, arena, cl);
    ASSERT_EQ(cl.size(), 2);
    const Vec3 wi = dirDeg(35, 200);
    const auto* spec = dynamic_cast<const LtcLobe*>(cl.lobe(0));
    ASSERT_NE(spec, nullptr);
    const Ltc base = ggxIsotropic(builtinTables(), 0.25f, sp.wo);
    EXPECT_NEAR(spec->ltc().magnitude, base.magnitude, 1e-4f);
    EXPECT_NEAR(spec->ltc().density(wi), base.density(wi), 1e-3f * base.density(wi));
    // A left-handed frame (sign < 0) mirrors the map: shading (wo, wi) with sign −1 equals shading the y-mirrored
    // directions with sign +1.
    Closure c1, c2;
    ScratchArena a1, a2;
    ShadingPoint sm = sp;
    sm.tangent.w = -1.f;
    auto m1 = shade({{"normal_map", "generate:flakes:16:2"}}, sm, a1, c1);
    ShadingPoint sr = sp;
    sr.wo.y = -sr.wo.y;
    auto m2 = shade({{"normal_map", "generate:flakes:16:2"}}, sr, a2, c2);
    const Vec3 wim(wi.x, -wi.y, wi.z);
    const Color3 f1 = test::query(c1, sm.wo, wi).f.total(), f2 = test::query(c2, sr.wo, wim).f.total();
    EXPECT_NEAR(f1.x, f2.x, 1e-4f * std::max(f2.x, 1e-3f));
    // Energy: ∫ f cos <= 1 even with bright specular and diffuse colours (the diffuse takes what the specular leaves).
    Closure c3;
    ScratchArena a3;
    auto m3 = shade({{"normal_map", "generate:flakes:16:2"}, {"specular_color", 1.0}, {"diffuse_color", 1.0}}, sp, a3, c3);
    EXPECT_LE(c3.albedo(sp.wo).x, 1.f + 1e-5f);
    // A missing texture store or a bad generator string is an input error.
    EXPECT_THROW(shade({{"normal_map", "some.png"}}, sp, arena, cl), std::exception);
    EXPECT_THROW(shade({{"normal_map", "generate:flakes:12:1"}}, sp, arena, cl), std::exception);
}

// The uniform literals reach prepare (PrepareContext::number): the tables are fitted for roughness 0.6 and strength
// 0.5 when the material is compiled, and the GLSL export holds exactly those tables (level g of the 2D array = stored
// level g + 1, each LTC premultiplied by its magnitude), written to the manifest as a layered resource.
TEST(LtcNormalMapNode, PrepareFitsTheUniformLiteralsAndExportsTheTablesForGlsl) {
    const nlohmann::json m = {{"nodes", {{"n", {{"type", "bsdf.ltc_normal_map"},
                                               {"inputs", {{"normal_map", "generate:flakes:8:5"}, {"roughness", 0.6},
                                                           {"strength", 0.5}}}}}}},
                              {"output", "@n.bsdf"}};
    graph::GraphDesc g = graph::parseGraph(m, "/materials/x");
    codegen::GlslModule mod = codegen::emitGlsl(g);
    ASSERT_EQ(mod.resources.size(), 4u);
    EXPECT_EQ(mod.resources[0].glslType, "sampler2DArray");
    EXPECT_EQ(mod.resources[0].file, "generate:flakes:8:5");
    const std::vector<graph::ResourceImage> images = codegen::exportGlslResources(g, mod, GraphLoadContext{});
    ASSERT_EQ(images.size(), 4u);
    // The prefilter the node must have used: normals scaled by the strength, alpha = roughness².
    std::vector<Vec3> n = NormalMapLtcPrefilter::normalsOf(generateNormalMap(NormalMapKind::Flakes, 8, 5));
    for (Vec3& v : n) v = Vec3(v.x * 0.5f, v.y * 0.5f, v.z);
    PrefilterSettings s;
    s.alpha = 0.6f * 0.6f;
    auto p = NormalMapLtcPrefilter::loadOrBuild(n, 8, s, NormalMapLtcPrefilter::defaultCacheDir());
    const graph::ResourceImage& t = images[0];
    ASSERT_EQ(t.levels.size(), 3u);  // stored levels 1..3: 4², 2², 1²
    const int nSpec = s.specTheta * s.specPhi, nDiff = s.diffTheta * s.diffPhi, layers = 3 * (nSpec + nDiff);
    size_t first = 0;
    for (int l = 0; l < 3; ++l) {
        const int w = 4 >> l;
        ASSERT_EQ(t.levels[size_t(l)].width, w);
        ASSERT_EQ(t.levels[size_t(l)].layers, layers);
        ASSERT_EQ(t.levels[size_t(l)].rgba.size(), size_t(w) * w * layers * 4);
        // Texel (w − 1, 0) of the level, the last specular view and the last diffuse view.
        const size_t texel = size_t(w - 1), flat = first + texel;
        for (int lobe = 0; lobe < 2; ++lobe) {
            const int nv = lobe ? nDiff : nSpec, v = nv - 1;
            const uint16_t* rec = &(lobe ? p->diffuseRecords() : p->specRecords())[(flat * size_t(nv) + size_t(v)) * 11];
            const float mag = glm::unpackHalf1x16(rec[9]);
            const int layer = 3 * ((lobe ? nSpec : 0) + v);
            const float* px0 = &t.levels[size_t(l)].rgba[(size_t(layer) * w * w + texel) * 4];
            const float* px2 = &t.levels[size_t(l)].rgba[(size_t(layer + 2) * w * w + texel) * 4];
            EXPECT_EQ(px0[0], mag * glm::unpackHalf1x16(rec[0])) << "level " << l << " lobe " << lobe;
            EXPECT_EQ(px2[0], mag * glm::unpackHalf1x16(rec[8]));
            EXPECT_EQ(px2[1], mag);
            EXPECT_EQ(px2[2], glm::unpackHalf1x16(rec[10]));
        }
        first += size_t(w) * w;
    }
    // normals: the clamped normals of level 0.
    ASSERT_EQ(images[1].levels.size(), 1u);
    EXPECT_EQ(images[1].levels[0].rgba[4 * 9 + 2], p->normals()[9].z);
    // The manifest lists the layer count, and the level's EXR stacks the layers.
    const std::string dir = test::tempDir("ltc-nm-manifest");
    const nlohmann::json man = codegen::writeGlslResources(mod, images, dir, *ColorConfig::load("builtin"));
    ASSERT_EQ(man["resources"].size(), 4u);
    EXPECT_EQ(man["resources"][0]["glsl_type"], "sampler2DArray");
    EXPECT_EQ(man["resources"][0]["levels"][0]["layers"], layers);
    EXPECT_FALSE(man["resources"][1]["levels"][0].contains("layers"));
    ImageSet exr = readImageSet(dir + "/" + man["resources"][0]["levels"][1]["exr"].get<std::string>());
    EXPECT_EQ(exr.width, 2);
    EXPECT_EQ(exr.height, 2 * layers);
}
