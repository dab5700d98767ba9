// P-NDF manifold serialisation and cache (issue 12 item 2, nodes/bsdf/glint_pndf/pndf_cache.h): bit-identical round
// trip, rejection and rebuild of corrupt / truncated / wrong-version files, unwritable folders, in-process sharing.
#include "nodes/bsdf/glint_pndf/pndf_cache.h"
#include "nodes/bsdf/glint_pndf/pndf_eval.h"
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"
#include "tests/unit/pndf_test_maps.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <unistd.h>
#include <vector>

using namespace specula;
using namespace specula::pndf;
using namespace specula::pndf::testing;
namespace fs = std::filesystem;

namespace {

fs::path freshDir(const char* name) {
    fs::path p = fs::temp_directory_path() / ("specula-pndf-cache-" + std::to_string(::getpid()) + "-" + name);
    fs::remove_all(p);
    return p;
}

std::vector<uint8_t> readFile(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeFile(const fs::path& p, const std::vector<uint8_t>& bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

}  // namespace

TEST(PndfCache, SerialisationRoundTripIsBitIdentical) {
    const int n = 64;
    const std::vector<Vec3> normals = sinusoidMap(n, 41, 8, 0.4, true);
    PndfManifold m(normals, n, n);
    const std::vector<uint8_t> bytes = m.serialize();
    std::shared_ptr<PndfManifold> back = PndfManifold::deserialize(bytes.data(), bytes.size());
    ASSERT_TRUE(back);
    EXPECT_TRUE(back->identicalTo(m));
    EXPECT_EQ(back->memoryBytes(), m.memoryBytes());
    // Every bound, cluster and normal, compared bit by bit through the public accessors too.
    int compared = 0;
    for (int l = 0; l < m.levelCount(); ++l)
        for (int r = 0; r < m.levelHeight(l); ++r)
            for (int c = 0; c < m.levelWidth(l); ++c) {
                const NormalBounds a = m.bounds(l, r, c), b = back->bounds(l, r, c);
                EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0) << l << " " << r << " " << c;
                if (l >= 1 && l <= m.clusterLevelCount()) {
                    const ClusterNode &ca = m.cluster(l, r, c), &cb = back->cluster(l, r, c);
                    EXPECT_EQ(std::memcmp(&ca, &cb, sizeof ca), 0) << l << " " << r << " " << c;
                }
                if (l == 0) EXPECT_EQ(m.vertex(r, c), back->vertex(r, c));
                ++compared;
            }
    EXPECT_GT(compared, n * n);
    // Same D_P to the bit, with and without clusters.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u01(0, 1);
    for (int q = 0; q < 200; ++q) {
        Footprint fp{u01(rng) * n, u01(rng) * n, 1 + 20 * u01(rng), 1 + 20 * u01(rng), FootprintKernel(q % 3)};
        Vec2d s = manifoldNormalAt(m, fp.centreX + (u01(rng) - 0.5) * fp.sigmaU,
                                   fp.centreY + (u01(rng) - 0.5) * fp.sigmaV);
        EXPECT_EQ(evalPndfHierarchy(m, fp, s), evalPndfHierarchy(*back, fp, s));
        EXPECT_EQ(evalPndfHierarchy(m, fp, s, nullptr, 1e-2), evalPndfHierarchy(*back, fp, s, nullptr, 1e-2));
    }
    // Malformed buffers are rejected, never crash: every truncation, a header claiming a huge map, bad ε_J.
    for (size_t cut : {size_t(0), size_t(7), size_t(24), bytes.size() / 2, bytes.size() - 1})
        EXPECT_FALSE(PndfManifold::deserialize(bytes.data(), cut)) << cut;
    std::vector<uint8_t> bad = bytes;
    const uint32_t huge = 1u << 16;
    std::memcpy(bad.data(), &huge, 4);
    EXPECT_FALSE(PndfManifold::deserialize(bad.data(), bad.size()));
    bad = bytes;
    const double negEps = -1;
    std::memcpy(bad.data() + 8, &negEps, 8);
    EXPECT_FALSE(PndfManifold::deserialize(bad.data(), bad.size()));
    bad = bytes;
    bad.push_back(0);
    EXPECT_FALSE(PndfManifold::deserialize(bad.data(), bad.size()));
}

TEST(PndfCache, DiskCacheWritesReadsAndSharesInProcess) {
    const fs::path dir = freshDir("rw");
    const int n = 64;
    const std::vector<Vec3> normals = sinusoidMap(n, 42, 6, 0.3);
    const PndfManifold fresh(normals, n, n);
    resetPndfCacheStats();
    {
        auto m1 = loadOrBuildManifold(normals, n, n, kDefaultJacobianClamp, dir.string());
        EXPECT_TRUE(m1->identicalTo(fresh));
    }
    PndfCacheStats st = pndfCacheStats();
    EXPECT_EQ(st.builds, 1u);
    EXPECT_EQ(st.diskWrites, 1u);
    EXPECT_EQ(st.diskHits, 0u);
    const fs::path file = pndfCachePath(dir.string(), pndfCacheKey(normals, n, n, kDefaultJacobianClamp));
    EXPECT_TRUE(fs::is_regular_file(file));
    int leftovers = 0;
    for (const auto& e : fs::directory_iterator(dir)) leftovers += e.path() != file;
    EXPECT_EQ(leftovers, 0);  // the temporary file was renamed, not left behind
    // Second load (nothing holds the first any more): read from the file, not rebuilt.
    auto m2 = loadOrBuildManifold(normals, n, n, kDefaultJacobianClamp, dir.string());
    st = pndfCacheStats();
    EXPECT_EQ(st.diskHits, 1u);
    EXPECT_EQ(st.builds, 1u);
    EXPECT_TRUE(m2->identicalTo(fresh));
    // A second material while the first holds it: the same object, no I/O.
    auto m3 = loadOrBuildManifold(normals, n, n, kDefaultJacobianClamp, dir.string());
    EXPECT_EQ(m3.get(), m2.get());
    st = pndfCacheStats();
    EXPECT_EQ(st.memoryHits, 1u);
    EXPECT_EQ(st.diskHits, 1u);
    // A different ε_J or map is a different key.
    EXPECT_FALSE(pndfCacheKey(normals, n, n, 2e-6) == pndfCacheKey(normals, n, n, kDefaultJacobianClamp));
    std::vector<Vec3> other = normals;
    other[100].x += 1e-6f;
    EXPECT_FALSE(pndfCacheKey(other, n, n, kDefaultJacobianClamp) ==
                 pndfCacheKey(normals, n, n, kDefaultJacobianClamp));
    fs::remove_all(dir);
}

TEST(PndfCache, CorruptTruncatedOrWrongVersionFilesAreRejectedAndRebuilt) {
    const fs::path dir = freshDir("corrupt");
    const int n = 32;
    const std::vector<Vec3> normals = sinusoidMap(n, 43, 5, 0.4);
    const PndfManifold fresh(normals, n, n);
    { loadOrBuildManifold(normals, n, n, kDefaultJacobianClamp, dir.string()); }
    const fs::path file = pndfCachePath(dir.string(), pndfCacheKey(normals, n, n, kDefaultJacobianClamp));
    const std::vector<uint8_t> good = readFile(file);
    ASSERT_GT(good.size(), 64u);
    struct Case {
        const char* name;
        std::vector<uint8_t> bytes;
    };
    std::vector<Case> cases;
    auto flipped = [&good](size_t at) {
        std::vector<uint8_t> b = good;
        b[at] ^= 0x10;
        return b;
    };
    cases.push_back({"payload byte flipped", flipped(good.size() / 2)});
    cases.push_back({"last byte flipped", flipped(good.size() - 1)});
    cases.push_back({"magic", flipped(0)});
    cases.push_back({"version", flipped(8)});
    cases.push_back({"key", flipped(20)});
    cases.push_back({"width", flipped(32)});
    cases.push_back({"checksum", flipped(60)});
    cases.push_back({"truncated", std::vector<uint8_t>(good.begin(), good.begin() + good.size() / 3)});
    cases.push_back({"header only", std::vector<uint8_t>(good.begin(), good.begin() + 64)});
    cases.push_back({"empty", {}});
    std::vector<uint8_t> giant = good;  // header claims a payload of 2^60 bytes: must not be allocated
    const uint64_t big = uint64_t(1) << 60;
    std::memcpy(giant.data() + 48, &big, 8);
    cases.push_back({"giant payload size", giant});
    std::vector<uint8_t> appended = good;
    appended.insert(appended.end(), 16, 0);
    cases.push_back({"trailing bytes", appended});
    for (const Case& c : cases) {
        writeFile(file, c.bytes);
        resetPndfCacheStats();
        {
            auto m = loadOrBuildManifold(normals, n, n, kDefaultJacobianClamp, dir.string());
            EXPECT_TRUE(m->identicalTo(fresh)) << c.name;
        }
        PndfCacheStats st = pndfCacheStats();
        EXPECT_EQ(st.diskRejects, 1u) << c.name;
        EXPECT_EQ(st.builds, 1u) << c.name;
        EXPECT_EQ(st.diskHits, 0u) << c.name;
        EXPECT_EQ(st.diskWrites, 1u) << c.name;
        EXPECT_EQ(readFile(file), good) << c.name << ": the rebuilt file replaces the bad one";
    }
    fs::remove_all(dir);
}

TEST(PndfCache, UnwritableOrDisabledCacheIsSkipped) {
    const int n = 16;
    const std::vector<Vec3> normals = sinusoidMap(n, 44, 3, 0.3);
    // A folder below a regular file cannot be created, whoever runs the test.
    const fs::path blocker = freshDir("blocker");
    writeFile(blocker, {1, 2, 3});
    resetPndfCacheStats();
    {
        auto m = loadOrBuildManifold(normals, n, n, kDefaultJacobianClamp, (blocker / "sub").string());
        ASSERT_TRUE(m);
        EXPECT_EQ(m->width(), n);
    }
    PndfCacheStats st = pndfCacheStats();
    EXPECT_EQ(st.builds, 1u);
    EXPECT_EQ(st.writeFailures, 1u);
    EXPECT_EQ(st.diskWrites, 0u);
    fs::remove(blocker);
    // Empty folder: no disk cache at all.
    resetPndfCacheStats();
    { loadOrBuildManifold(normals, n, n, kDefaultJacobianClamp, ""); }
    st = pndfCacheStats();
    EXPECT_EQ(st.builds, 1u);
    EXPECT_EQ(st.writeFailures + st.diskWrites + st.diskRejects + st.diskHits, 0u);
    // Default folder: SPECULA_CACHE_DIR, then XDG_CACHE_HOME/specula, then HOME/.cache/specula.
    const char* saved[3] = {std::getenv("SPECULA_CACHE_DIR"), std::getenv("XDG_CACHE_HOME"), std::getenv("HOME")};
    const std::string keep[3] = {saved[0] ? saved[0] : "", saved[1] ? saved[1] : "", saved[2] ? saved[2] : ""};
    setenv("SPECULA_CACHE_DIR", "/tmp/a", 1);
    EXPECT_EQ(defaultPndfCacheDir(), "/tmp/a");
    setenv("SPECULA_CACHE_DIR", "", 1);
    EXPECT_EQ(defaultPndfCacheDir(), "");
    unsetenv("SPECULA_CACHE_DIR");
    setenv("XDG_CACHE_HOME", "/tmp/x", 1);
    EXPECT_EQ(defaultPndfCacheDir(), "/tmp/x/specula");
    unsetenv("XDG_CACHE_HOME");
    setenv("HOME", "/tmp/h", 1);
    EXPECT_EQ(defaultPndfCacheDir(), "/tmp/h/.cache/specula");
    const char* names[3] = {"SPECULA_CACHE_DIR", "XDG_CACHE_HOME", "HOME"};
    for (int i = 0; i < 3; ++i) {
        if (saved[i]) setenv(names[i], keep[i].c_str(), 1);
        else unsetenv(names[i]);
    }
}
