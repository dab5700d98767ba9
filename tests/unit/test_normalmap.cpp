// Tests for procedural normal maps (core/texture/normal_map_gen) and normal-map loading: golden hashes,
// unit normals with z > 0, per-kind slope statistics, PNG/EXR round trips through TextureStore with the
// OpenGL/DirectX convention of texture.normal_map, `specula normalmap`, and UV tangents across mesh formats.
#include "core/color/color_config.h"
#include "core/geometry/mesh_io.h"
#include "core/graph/graph_material.h"
#include "core/texture/lean_moments.h"
#include "core/texture/normal_map_gen.h"
#include "core/texture/texture_store.h"
#include "test_support.h"

// The command's own translation unit: the `specula` executable compiles it, the tests drive it through CLI11.
#include "plugin/cli/normalmap_command.cpp"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cinttypes>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

using namespace specula;

namespace {

// Golden hashes (normalMapHash: FNV-1a over the 16-bit quantised normals) at size 128, seed 7.
// A change here means every example and validation image built from these maps changes: update on purpose only.
const std::map<std::string, uint64_t>& goldenHashes() {
    static const std::map<std::string, uint64_t> h = {
        {"bumps", 0xd9d9eebc54645927ULL}, {"brushed", 0x12ea831de8596523ULL}, {"scratches", 0x4c6144704e9b3e35ULL},
        {"flakes", 0xaf6a3cd01c757ae8ULL}, {"stone", 0xcf493987f820cda9ULL}};
    return h;
}

std::string hex(uint64_t v) {
    char b[32];
    std::snprintf(b, sizeof b, "0x%016" PRIx64 "ULL", v);
    return b;
}

}  // namespace

TEST(NormalMapGen, GoldenHashes) {
    for (NormalMapKind k : allNormalMapKinds()) {
        NormalMap m = generateNormalMap(k, 128, 7);
        uint64_t h = normalMapHash(m);
        EXPECT_EQ(h, goldenHashes().at(normalMapKindName(k))) << normalMapKindName(k) << " hash is " << hex(h);
    }
}

TEST(NormalMapGen, DeterministicAndSeedSensitive) {
    for (NormalMapKind k : allNormalMapKinds()) {
        NormalMap a = generateNormalMap(k, 64, 3), b = generateNormalMap(k, 64, 3), c = generateNormalMap(k, 64, 4);
        ASSERT_EQ(a.normals.size(), b.normals.size());
        EXPECT_EQ(0, std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(Vec3)))
            << normalMapKindName(k) << ": two runs differ";
        EXPECT_NE(normalMapHash(a), normalMapHash(c)) << normalMapKindName(k) << ": seed has no effect";
    }
}

TEST(NormalMapGen, UnitNormalsWithPositiveZ) {
    for (NormalMapKind k : allNormalMapKinds()) {
        NormalMap m = generateNormalMap(k, 96, 11);  // not a power of two on purpose
        ASSERT_EQ(m.normals.size(), size_t(96 * 96));
        float worstLen = 0, minZ = 1;
        for (const Vec3& n : m.normals) {
            worstLen = std::max(worstLen, std::abs(glm::length(n) - 1.f));
            minZ = std::min(minZ, n.z);
        }
        EXPECT_LT(worstLen, 1e-6f) << normalMapKindName(k);
        EXPECT_GT(minZ, 0.2f) << normalMapKindName(k) << ": normals must stay well above the horizon";
    }
}

// Realistic slope statistics per kind (numbers measured at 256², seed 1; bounds leave ~20% slack).
TEST(NormalMapGen, SlopeStatisticsPerKind) {
    std::map<std::string, SlopeStats> st;
    std::map<std::string, NormalMap> maps;
    for (NormalMapKind k : allNormalMapKinds()) {
        maps[normalMapKindName(k)] = generateNormalMap(k, 256, 1);
        st[normalMapKindName(k)] = slopeStats(maps[normalMapKindName(k)]);
        const SlopeStats& s = st[normalMapKindName(k)];
        std::printf("  %-9s mean (%+.4f %+.4f)  sigma (%.4f %.4f)  rho %+.3f  principal (%.4f %.4f)\n",
                    normalMapKindName(k), s.meanX, s.meanY, s.sigmaX(), s.sigmaY(), s.rho(), s.sigmaMajor(),
                    s.sigmaMinor());
        // A tileable heightfield has zero mean slope; flakes are iid tilts (mean ~0 by symmetry).
        EXPECT_LT(std::abs(s.meanX), 0.03) << normalMapKindName(k);
        EXPECT_LT(std::abs(s.meanY), 0.03) << normalMapKindName(k);
    }
    // bumps: isotropic, RMS 0.25 per axis (normalised by construction, measured on the normals).
    EXPECT_NEAR(st["bumps"].sigmaX(), 0.25, 0.04);
    EXPECT_NEAR(st["bumps"].sigmaY(), 0.25, 0.04);
    EXPECT_LT(st["bumps"].sigmaMajor() / st["bumps"].sigmaMinor(), 1.4);
    // brushed: strongly anisotropic and correlated in the (u, v) axes (grooves at 26.6 degrees).
    EXPECT_GT(st["brushed"].sigmaMajor() / st["brushed"].sigmaMinor(), 4.0);
    EXPECT_LT(st["brushed"].rho(), -0.6);
    EXPECT_NEAR(st["brushed"].sigmaMajor(), 0.2, 0.04);
    // scratches: mostly flat, with steep groove walls.
    {
        int flat = 0, steep = 0;
        for (const Vec3& n : maps["scratches"].normals) {
            float sl = std::sqrt(n.x * n.x + n.y * n.y) / n.z;
            flat += sl < 0.05f;
            steep += sl > 0.25f;
        }
        double fFlat = double(flat) / maps["scratches"].normals.size(), fSteep = double(steep) / maps["scratches"].normals.size();
        std::printf("  scratches: %.1f%% flat (< 0.05), %.1f%% steep (> 0.25)\n", 100 * fFlat, 100 * fSteep);
        EXPECT_GT(fFlat, 0.7);
        EXPECT_GT(fSteep, 0.02);
    }
    // flakes: piecewise constant (most texels equal their right neighbour), ~0.35 RMS per axis, isotropic.
    {
        const NormalMap& m = maps["flakes"];
        int same = 0;
        for (int y = 0; y < m.size; ++y)
            for (int x = 0; x + 1 < m.size; ++x) same += m.at(x, y) == m.at(x + 1, y);
        double f = double(same) / (m.size * (m.size - 1));
        std::printf("  flakes: %.1f%% of texels equal their right neighbour\n", 100 * f);
        EXPECT_GT(f, 0.7);
        EXPECT_NEAR(st["flakes"].sigmaX(), 0.35, 0.08);
        EXPECT_NEAR(st["flakes"].sigmaY(), 0.35, 0.08);
    }
    // stone: rough (RMS ~0.27 per axis) and smooth inside stones (neighbours close), unlike flakes.
    EXPECT_NEAR(std::sqrt((st["stone"].varX + st["stone"].varY) / 2), 0.27, 0.05);
    // Visibly different: the mean |Δn| between any two kinds is large.
    for (auto& [a, ma] : maps)
        for (auto& [b, mb] : maps) {
            if (a >= b) continue;
            double d = 0;
            for (size_t i = 0; i < ma.normals.size(); ++i) d += glm::length(ma.normals[i] - mb.normals[i]);
            d /= ma.normals.size();
            EXPECT_GT(d, 0.1) << a << " vs " << b;
        }
}

TEST(NormalMapGen, Tileable) {
    // Opposite edges continue each other like interior neighbours do (periodic noise / Voronoi / wrapped
    // scratches): the mean |Δn| across the u seam (column n-1 -> 0) is no larger than the largest mean |Δn| over
    // the interior column boundaries, and likewise for the v seam and row boundaries.
    for (NormalMapKind k : allNormalMapKinds()) {
        NormalMap m = generateNormalMap(k, 128, 5);
        const int n = m.size;
        auto colStep = [&](int x0, int x1) {
            double s = 0;
            for (int y = 0; y < n; ++y) s += glm::length(m.at(x1, y) - m.at(x0, y));
            return s / n;
        };
        auto rowStep = [&](int y0, int y1) {
            double s = 0;
            for (int x = 0; x < n; ++x) s += glm::length(m.at(x, y1) - m.at(x, y0));
            return s / n;
        };
        double maxCol = 0, maxRow = 0;
        for (int i = 0; i + 1 < n; ++i) maxCol = std::max(maxCol, colStep(i, i + 1)), maxRow = std::max(maxRow, rowStep(i, i + 1));
        EXPECT_LE(colStep(n - 1, 0), maxCol) << normalMapKindName(k);
        EXPECT_LE(rowStep(n - 1, 0), maxRow) << normalMapKindName(k);
    }
}

namespace {
int runNormalmap(const std::vector<std::string>& args);  // below, with the command's other tests
}  // namespace

// `specula normalmap --kind brushed --angle A` (issue 17 item 6): the grooves run along the direction used (the nearest
// seamless integer direction, within 3.6 degrees of the request): the slope covariance's major axis (across the
// grooves) is perpendicular to it. The default direction reproduces the default brushed map bit for bit, and every
// direction tiles.
TEST(NormalMapGen, BrushAngleTurnsTheGrooves) {
    double used = 0;
    EXPECT_EQ(generateBrushedNormalMap(128, 3, 26.565, &used).normals, generateNormalMap(NormalMapKind::Brushed, 128, 3).normals);
    EXPECT_NEAR(used, 26.565, 1e-3);
    for (double asked : {0.0, 10.0, 45.0, 90.0, 118.0, 163.0, -30.0, 400.0}) {
        NormalMap m = generateBrushedNormalMap(256, 1, asked, &used);
        double wrapped = std::fmod(std::fmod(asked, 180.0) + 180.0, 180.0), err = std::abs(used - wrapped);
        EXPECT_LE(std::min(err, 180.0 - err), 3.6) << asked;
        const SlopeStats st = slopeStats(m);
        EXPECT_GT(st.sigmaMajor() / st.sigmaMinor(), 3.0) << asked;
        const double major = 0.5 * std::atan2(2 * st.covXY, st.varX - st.varY) * 180.0 / 3.14159265358979323846;  // across the grooves
        double d = std::fmod(std::abs(major + 90.0 - used), 180.0);
        EXPECT_LT(std::min(d, 180.0 - d), 4.0) << "asked " << asked << ", used " << used << ", grooves along " << major + 90;
        const int n = m.size;
        double seam = 0, inner = 0;
        for (int y = 0; y < n; ++y) seam += glm::length(m.at(0, y) - m.at(n - 1, y)), inner += glm::length(m.at(1, y) - m.at(0, y));
        EXPECT_LT(seam, 2.5 * inner) << "the u seam of the tile at " << asked;
    }
    EXPECT_THROW(generateBrushedNormalMap(128, 1, std::nan(""), nullptr), NormalMapError);
    std::string dir = test::tempDir("nm-angle");
    EXPECT_EQ(runNormalmap({"--kind", "brushed", "--angle", "60", "--size", "32", "-o", dir + "/b.exr", "--quiet"}), 0);
    EXPECT_EQ(runNormalmap({"--kind", "bumps", "--angle", "60", "--size", "32", "-o", dir + "/c.exr"}), kExitUsage);
}

TEST(NormalMapGen, RejectsBadArguments) {
    EXPECT_THROW(generateNormalMap(NormalMapKind::Bumps, 4, 1), NormalMapError);
    EXPECT_THROW(parseNormalMapKind("wood"), NormalMapError);
    NormalMap m = generateNormalMap(NormalMapKind::Bumps, 8, 1);
    EXPECT_THROW(writeNormalMap(m, test::tempDir("nm-bad") + "/x.jpg"), NormalMapError);
}

// ---- files, TextureStore loading, conventions ----------------------------------------------------------

// Writes the map as 8-bit PNG (our writer does 16-bit PNG and float EXR; 8-bit comes from OIIO directly).
void write8bit(const NormalMap& m, const std::string& path) {
    std::vector<uint8_t> px(m.normals.size() * 3);
    for (size_t i = 0; i < m.normals.size(); ++i)
        for (int k = 0; k < 3; ++k) px[i * 3 + k] = uint8_t(std::floor((m.normals[i][k] + 1.f) * 0.5f * 255.f + 0.5f));
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(path, OIIO::ImageSpec(m.size, m.size, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
    out->close();
}

TEST(NormalMapFiles, PngAndExrRoundTripThroughTextureStore) {
    std::string dir = test::tempDir("nm-files");
    NormalMap m = generateNormalMap(NormalMapKind::Stone, 64, 2);
    writeNormalMap(m, dir + "/n16.png");
    writeNormalMap(m, dir + "/nf.exr");
    write8bit(m, dir + "/n8.png");
    {
        auto in = OIIO::ImageInput::open(dir + "/n16.png");
        ASSERT_TRUE(in);
        EXPECT_EQ(in->spec().format, OIIO::TypeDesc::UINT16);
        auto ine = OIIO::ImageInput::open(dir + "/nf.exr");
        ASSERT_TRUE(ine);
        EXPECT_EQ(ine->spec().format, OIIO::TypeDesc::FLOAT);
    }
    TextureStore store(ColorConfig::load("builtin"));
    // Quantisation step of the encoding (n = 2c - 1): 2/65535 (16-bit), 2/255 (8-bit); float is exact to 1 ulp.
    const std::pair<std::string, float> files[] = {{"nf.exr", 1e-6f}, {"n16.png", 2.f / 65535.f}, {"n8.png", 2.f / 255.f}};
    for (auto& [f, tol] : files) {
        TextureHandle h = store.load(dir + "/" + f, "raw");
        ASSERT_EQ(store.width(h), 64);
        ASSERT_EQ(store.channels(h), 3);
        const auto& px = store.pixels(h);
        float worst = 0;
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x)
                for (int k = 0; k < 3; ++k)
                    worst = std::max(worst, std::abs(2.f * px[(size_t(y) * 64 + x) * 3 + k] - 1.f - m.at(x, y)[k]));
        EXPECT_LE(worst, 0.5f * tol + 1e-6f) << f;
        // The store's filtered lookup: v = 0 is the bottom row, so texel (x, y) (file row y) sits at v = 1 - (y+.5)/64.
        float c[3];
        store.sample(h, Vec2((10 + 0.5f) / 64, 1.f - (50 + 0.5f) / 64), Vec2(0.f), Vec2(0.f), c, 3);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(2.f * c[k] - 1.f, m.at(10, 50)[k], tol + 1e-5f) << f;
        // LEAN pyramid from the stored pixels sees the same slopes as the generator's map.
        LeanPyramid P = LeanPyramid::fromEncodedPixels(px.data(), 64, 64, 3, false);
        LeanPyramid Q = LeanPyramid::fromNormalMap(m);
        LeanMoments a = P.texel(P.levels() - 1, 0, 0), b = Q.texel(Q.levels() - 1, 0, 0);
        EXPECT_NEAR(a.xx, b.xx, 20 * tol) << f;
        EXPECT_NEAR(a.xy, b.xy, 20 * tol) << f;
    }
}

// texture.normal_map decodes colour -> world normal; its 'directx' convention must invert a DirectX-authored map
// (green flipped) back to the same world normal, and a LEAN pyramid built with directx = true must agree.
TEST(NormalMapFiles, OpenGlAndDirectXConventionsAgree) {
    std::string dir = test::tempDir("nm-conv");
    NormalMap gl = generateNormalMap(NormalMapKind::Bumps, 32, 9);
    NormalMap dx = gl;
    for (Vec3& n : dx.normals) n.y = -n.y;
    writeNormalMap(gl, dir + "/gl.exr");
    writeNormalMap(dx, dir + "/dx.exr");
    TextureStore store(ColorConfig::load("builtin"));
    GraphLoadContext ctx{&store, dir};
    auto material = [&](const std::string& file, const std::string& conv) {
        nlohmann::json m = {
            {"nodes",
             {{"img", {{"type", "texture.image"}, {"inputs", {{"file", file}, {"colorspace", "raw"}}}}},
              {"nm", {{"type", "texture.normal_map"}, {"inputs", {{"color", "@img.color"}, {"convention", conv}}}}},
              {"spec", {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", 0.3}, {"normal", "@nm.normal"}}}}}}},
            {"output", "@spec.bsdf"}};
        return loadGraphMaterial(m, "/materials/x", ctx);
    };
    auto mGl = material("gl.exr", "opengl"), mDx = material("dx.exr", "directx");
    ScratchArena arena;
    int checked = 0;
    for (int y = 0; y < 32; y += 5)
        for (int x = 0; x < 32; x += 3) {
            ShadingPoint sp;
            sp.uv = Vec2((x + 0.5f) / 32, 1.f - (y + 0.5f) / 32);
            sp.n = sp.ng = Vec3(0, 0, 1);
            sp.tangent = Vec4(1, 0, 0, 1);
            sp.wo = glm::normalize(Vec3(0.2f, -0.3f, 1.f));
            sp.frame = Frame::fromNormalTangent(sp.n, Vec3(1, 0, 0));
            ShadingPoint a = sp, b = sp;
            Closure ca, cb;
            mGl->shade(a, arena, ca);
            mDx->shade(b, arena, cb);
            // The lobe's frame normal is the decoded world normal; texel (x, y) of the OpenGL map is its normal.
            ASSERT_EQ(ca.size(), 1);
            ASSERT_EQ(cb.size(), 1);
            EXPECT_LT(glm::distance(ca.frame(0).n, cb.frame(0).n), 1e-5f);
            EXPECT_LT(glm::distance(ca.frame(0).n, gl.at(x, y)), 1e-4f);
            arena.reset();
            ++checked;
        }
    EXPECT_GT(checked, 40);
    std::vector<float> gpx, dpx;
    const auto& g = store.pixels(store.load(dir + "/gl.exr", "raw"));
    const auto& d = store.pixels(store.load(dir + "/dx.exr", "raw"));
    LeanPyramid P = LeanPyramid::fromEncodedPixels(g.data(), 32, 32, 3, false);
    LeanPyramid Q = LeanPyramid::fromEncodedPixels(d.data(), 32, 32, 3, true);
    for (int l = 0; l < P.levels(); ++l) {
        LeanMoments a = P.texel(l, 0, 0), b = Q.texel(l, 0, 0);
        EXPECT_NEAR(a.y, b.y, 1e-5f);
        EXPECT_NEAR(a.xy, b.xy, 1e-5f);
    }
}

// ---- `specula normalmap` -----------------------------------------------------------------------------
namespace {
int runNormalmap(const std::vector<std::string>& args) {
    CLI::App app{"test"};
    app.require_subcommand(1);
    int code = 0;
    addNormalmapCommand(app, code);
    std::vector<std::string> argv = {"specula", "normalmap"};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<char*> ptrs;
    for (auto& a : argv) ptrs.push_back(a.data());
    try {
        app.parse(int(ptrs.size()), ptrs.data());
    } catch (const CLI::ParseError& e) {
        return kExitUsage;
    }
    return code;
}
}  // namespace

TEST(NormalmapCommand, WritesDeterministicFilesOfEveryKind) {
    std::string dir = test::tempDir("nm-cli");
    for (NormalMapKind k : allNormalMapKinds()) {
        std::string name = normalMapKindName(k);
        std::string a = dir + "/" + name + "_a.exr", b = dir + "/" + name + "_b.exr", p = dir + "/" + name + ".png";
        ASSERT_EQ(runNormalmap({"--kind", name, "--size", "64", "--seed", "5", "-o", a, "--quiet"}), 0);
        ASSERT_EQ(runNormalmap({"--kind", name, "--size", "64", "--seed", "5", "-o", b, "--quiet"}), 0);
        ASSERT_EQ(runNormalmap({"--kind", name, "--size", "64", "--seed", "5", "-o", p, "--quiet"}), 0);
        OIIO::ImageBuf A(a), B(b), P(p);
        ASSERT_TRUE(A.read(0, 0, true, OIIO::TypeDesc::FLOAT) && B.read(0, 0, true, OIIO::TypeDesc::FLOAT) &&
                    P.read(0, 0, true, OIIO::TypeDesc::FLOAT));
        EXPECT_EQ(A.spec().width, 64);
        EXPECT_EQ(P.nativespec().format, OIIO::TypeDesc::UINT16);
        std::vector<float> pa(64 * 64 * 3), pb(pa.size()), pp(pa.size());
        A.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, pa.data());
        B.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, pb.data());
        P.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, pp.data());
        EXPECT_EQ(pa, pb) << name;
        NormalMap m = generateNormalMap(k, 64, 5);
        for (size_t i = 0; i < m.normals.size(); ++i)
            for (int c = 0; c < 3; ++c) {
                ASSERT_EQ(pa[i * 3 + c], (m.normals[i][c] + 1.f) * 0.5f) << name;
                ASSERT_NEAR(pp[i * 3 + c], (m.normals[i][c] + 1.f) * 0.5f, 0.51f / 65535.f) << name;
            }
    }
    EXPECT_EQ(runNormalmap({"--kind", "wood", "-o", dir + "/x.exr"}), kExitUsage);
    EXPECT_EQ(runNormalmap({"--kind", "bumps", "--size", "4", "-o", dir + "/x.exr"}), kExitUsage);
    EXPECT_EQ(runNormalmap({"--kind", "bumps", "--size", "16", "-o", dir + "/x.bmp", "--quiet"}), kExitUsage);
    EXPECT_EQ(runNormalmap({"--kind", "bumps", "--size", "16", "-o", dir + "/missing/x.exr"}), kExitIo);
}

// ---- tangents from UVs, identical for OBJ / PLY / glTF, oriented for normal maps ------------------------
namespace {
std::string base64(const std::string& in) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8) | uint8_t(in[i + 2]);
        for (int k = 3; k >= 0; --k) out += t[(v >> (6 * k)) & 63];
    }
    if (i + 1 == in.size()) {
        uint32_t v = uint8_t(in[i]) << 16;
        out += t[(v >> 18) & 63], out += t[(v >> 12) & 63], out += "==";
    } else if (i + 2 == in.size()) {
        uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8);
        out += t[(v >> 18) & 63], out += t[(v >> 12) & 63], out += t[(v >> 6) & 63], out += '=';
    }
    return out;
}
}  // namespace

TEST(NormalMapTangents, ComputedFromUvsConsistentlyAcrossFormats) {
    // A bent strip (two quads at an angle) with a rotated and mirrored UV layout, no tangents in any file.
    std::vector<Vec3> P = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.5f}, {0, 1, 0.5f}, {1, 2, 0.5f}, {0, 2, 0.5f}};
    std::vector<Vec2> UV = {{0.2f, 0.1f}, {0.2f, 0.6f}, {0.7f, 0.6f}, {0.7f, 0.1f}, {0.9f, 0.6f}, {0.9f, 0.1f}};
    std::vector<glm::uvec3> F = {{0, 1, 2}, {0, 2, 3}, {3, 2, 4}, {3, 4, 5}};
    std::string dir = test::tempDir("nm-tangents");
    {
        std::ofstream o(dir + "/m.obj");
        for (auto& p : P) o << "v " << p.x << ' ' << p.y << ' ' << p.z << "\n";
        for (auto& t : UV) o << "vt " << t.x << ' ' << t.y << "\n";
        for (auto& f : F) o << "f " << f.x + 1 << '/' << f.x + 1 << ' ' << f.y + 1 << '/' << f.y + 1 << ' ' << f.z + 1 << '/' << f.z + 1 << "\n";
    }
    {
        std::ofstream o(dir + "/m.ply");
        o << "ply\nformat ascii 1.0\nelement vertex " << P.size()
          << "\nproperty float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\nelement face "
          << F.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
        for (size_t i = 0; i < P.size(); ++i) o << P[i].x << ' ' << P[i].y << ' ' << P[i].z << ' ' << UV[i].x << ' ' << UV[i].y << "\n";
        for (auto& f : F) o << "3 " << f.x << ' ' << f.y << ' ' << f.z << "\n";
    }
    {
        std::string bin;
        auto put = [&](const void* p, size_t n) { bin.append(static_cast<const char*>(p), n); };
        for (auto& p : P) put(&p, 12);
        for (auto& t : UV) {
            Vec2 g(t.x, 1.f - t.y);  // glTF: v down
            put(&g, 8);
        }
        for (auto& f : F) put(&f, 12);
        nlohmann::json j = {
            {"asset", {{"version", "2.0"}}},
            {"buffers", {{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}}},
            {"bufferViews",
             {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 72}},
              {{"buffer", 0}, {"byteOffset", 72}, {"byteLength", 48}},
              {{"buffer", 0}, {"byteOffset", 120}, {"byteLength", 48}}}},
            {"accessors",
             {{{"bufferView", 0}, {"componentType", 5126}, {"count", 6}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 2, 0.5}}},
              {{"bufferView", 1}, {"componentType", 5126}, {"count", 6}, {"type", "VEC2"}},
              {{"bufferView", 2}, {"componentType", 5125}, {"count", 12}, {"type", "SCALAR"}}}},
            {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}}}, {"indices", 2}}}}}}},
            {"nodes", {{{"mesh", 0}}}},
            {"scenes", {{{"nodes", {0}}}}},
            {"scene", 0}};
        std::ofstream(dir + "/m.gltf") << j.dump();
    }
    TriangleMesh obj = loadMesh(dir + "/m.obj"), ply = loadMesh(dir + "/m.ply"), gltf = loadMesh(dir + "/m.gltf");
    for (const TriangleMesh* m : {&obj, &ply, &gltf}) {
        ASSERT_EQ(m->tangents.size(), m->positions.size());
        ASSERT_EQ(m->uvs.size(), m->positions.size());
    }
    // Match vertices by position (loaders may reorder), then compare tangent frames.
    auto find = [](const TriangleMesh& m, Vec3 p, Vec2 uv) {
        for (size_t i = 0; i < m.positions.size(); ++i)
            if (glm::distance(m.positions[i], p) < 1e-6f && glm::distance(m.uvs[i], uv) < 1e-6f) return int(i);
        return -1;
    };
    for (size_t v = 0; v < P.size(); ++v) {
        int io = find(obj, P[v], UV[v]), ip = find(ply, P[v], UV[v]), ig = find(gltf, P[v], UV[v]);
        ASSERT_GE(io, 0);
        ASSERT_GE(ip, 0);
        ASSERT_GE(ig, 0) << "glTF vertex " << v << " (uv v-flip)";
        Vec4 to = obj.tangents[size_t(io)], tp = ply.tangents[size_t(ip)], tg = gltf.tangents[size_t(ig)];
        EXPECT_LT(glm::distance(Vec3(to), Vec3(tp)), 1e-5f) << v;
        EXPECT_LT(glm::distance(Vec3(to), Vec3(tg)), 1e-5f) << v;
        EXPECT_EQ(to.w, tp.w);
        EXPECT_EQ(to.w, tg.w);
    }
    // Orientation: the tangent follows +u and sign·(N×T) follows +v (so a normal map's +x/+y tilt towards +u/+v).
    // Triangle 0: u grows along P3-P0 (y/z direction), v grows along P1-P0 (+x): a mirrored layout, so w = -1.
    int i0 = find(obj, P[0], UV[0]);
    Vec3 t(obj.tangents[size_t(i0)]), n = glm::normalize(obj.normals[size_t(i0)]);
    Vec3 b = obj.tangents[size_t(i0)].w * glm::cross(n, t);
    EXPECT_GT(glm::dot(t, glm::normalize(P[3] - P[0])), 0.95f);
    EXPECT_GT(glm::dot(b, Vec3(1, 0, 0)), 0.95f);
    EXPECT_EQ(obj.tangents[size_t(i0)].w, -1.f);
}
