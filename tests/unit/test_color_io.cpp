// Unit tests for colour management (OCIO config, views), image I/O (multi-layer EXR, PNG, atomic writes,
// comparison) and the TextureStore (colour conversion, texel/footprint filtering, wrap modes, v convention).
#include "core/color/color_config.h"
#include "core/io/image_io.h"
#include "core/texture/texture_store.h"
#include "core/util/cache_dir.h"
#include "test_support.h"

#include <OpenImageIO/imageio.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <initializer_list>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <thread>

namespace fs = std::filesystem;
using namespace specula;

namespace {

std::shared_ptr<const ColorConfig> config() {
    static auto cfg = ColorConfig::load();
    return cfg;
}

float srgbDecode(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

std::vector<std::string> leftovers(const std::string& dir) {
    std::vector<std::string> out;
    for (auto& e : fs::directory_iterator(dir)) {
        std::string n = e.path().filename().string();
        if (n.find(".tmp-") != std::string::npos) out.push_back(n);
    }
    return out;
}

ImageSet makeSet(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-2.f, 8.f);
    ImageSet s;
    s.width = w;
    s.height = h;
    auto add = [&](const std::string& name, std::vector<std::string> chans) {
        AovBuffer a;
        a.name = name;
        a.channelNames = std::move(chans);
        a.pixels.resize(size_t(w) * size_t(h) * a.channelNames.size());
        for (auto& v : a.pixels) v = u(rng);
        s.aovs.push_back(std::move(a));
    };
    add("beauty", {"R", "G", "B"});
    add("diffuse", {"R", "G", "B"});
    add("normal", {"X", "Y", "Z"});
    s.aovs[0].pixels[0] = 1e-30f;  // denormal-ish and extreme values survive too
    s.aovs[0].pixels[1] = 3.4e38f;
    s.aovs[2].pixels[5] = -0.f;
    s.metadata["specula:spp"] = "64";
    return s;
}

ImageSet constantSet(int w, int h, float v, const std::string& aov2 = "") {
    ImageSet s;
    s.width = w;
    s.height = h;
    s.aovs.push_back({"beauty", {"R", "G", "B"}, std::vector<float>(size_t(w) * size_t(h) * 3, v)});
    if (!aov2.empty()) s.aovs.push_back({aov2, {"X", "Y", "Z"}, std::vector<float>(size_t(w) * size_t(h) * 3, 0.5f)});
    return s;
}

// 8-bit RGB PNG written directly with OIIO (the texture fixture), rows top to bottom.
void writePng8(const std::string& path, int w, int h, const std::vector<uint8_t>& rgb) {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT8);
    ASSERT_TRUE(out->open(path, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, rgb.data()));
    out->close();
}

}  // namespace

// ---- ColorConfig ------------------------------------------------------------------------------------

TEST(ColorConfig, LoadsShippedConfig) {
    auto c = config();
    EXPECT_EQ(c->workingSpace(), "Linear Rec.709 (sRGB)");
    EXPECT_EQ(c->defaultDisplay(), "sRGB");
    EXPECT_EQ(c->defaultView(), "Standard");
    auto views = c->views();
    for (const char* v : {"Standard", "Filmic", "Raw"}) {
        EXPECT_NE(std::find(views.begin(), views.end(), v), views.end()) << v;
        EXPECT_TRUE(c->hasView(v)) << v;
    }
    EXPECT_FALSE(c->hasView("Filmc"));
    for (const char* n : {"sRGB", "srgb", "srgb_texture", "sRGB - Texture", "lin_rec709", "linear", "scene-linear",
                          "scene_linear", "rendering", "raw", "Raw", "non-color", "data", "ACEScg", "acescg",
                          "Linear P3-D65", "ACES2065-1", "aces2065_1", "CIE-XYZ-D65"})
        EXPECT_TRUE(c->hasColorspace(n)) << n;
    EXPECT_FALSE(c->hasColorspace("sRGBB-Texture-x"));
    EXPECT_EQ(c->canonicalColorspace("srgb_texture"), "sRGB - Texture");
    EXPECT_EQ(c->canonicalColorspace("non-color"), "raw");
    EXPECT_TRUE(c->isData("Raw"));
    EXPECT_FALSE(c->isData("acescg"));
    EXPECT_FALSE(c->cacheId().empty());
}

TEST(ColorConfig, ExplicitPathAndMissingFile) {
    auto c = ColorConfig::load(test::sourcePath("data/ocio/config.ocio"));
    EXPECT_EQ(c->workingSpace(), "Linear Rec.709 (sRGB)");
    EXPECT_THROW(ColorConfig::load("/nonexistent/config.ocio"), ColorError);
}

TEST(ColorConfig, SrgbTextureDecode) {
    for (const char* name : {"sRGB", "srgb_texture", "sRGB - Texture"}) {
        float rgb[6] = {0.5f, 0.5f, 0.5f, 0.f, 1.f, 0.04f};
        config()->toWorking(rgb, 2, name);
        EXPECT_NEAR(rgb[0], 0.21404f, 1e-4f) << name;
        EXPECT_NEAR(rgb[3], 0.f, 1e-7f);
        EXPECT_NEAR(rgb[4], 1.f, 1e-6f);
        EXPECT_NEAR(rgb[5], 0.04f / 12.92f, 1e-6f);
    }
}

TEST(ColorConfig, StandardViewOfMiddleGrey) {
    float rgb[6] = {0.18f, 0.18f, 0.18f, 0.09f, 0.09f, 0.09f};
    config()->toDisplay(rgb, 1, "Standard");
    EXPECT_NEAR(rgb[0], 0.4613f, 1e-3f);
    config()->toDisplay(rgb + 3, 1, "", 1.f);  // default view, +1 stop
    EXPECT_NEAR(rgb[3], 0.4613f, 1e-3f);
    float hot[3] = {5.f, -1.f, 1.f};
    config()->toDisplay(hot, 1, "Standard");
    EXPECT_FLOAT_EQ(hot[0], 1.f);  // clamped
    EXPECT_FLOAT_EQ(hot[1], 0.f);
    EXPECT_NEAR(hot[2], 1.f, 1e-6f);
}

TEST(ColorConfig, RawIsIdentity) {
    const float src[6] = {-1.f, 0.25f, 3.5f, 1e-8f, 0.5f, 100.f};
    for (const char* name : {"raw", "Raw", "non-color", "data"}) {
        float rgb[6];
        std::memcpy(rgb, src, sizeof rgb);
        config()->toWorking(rgb, 2, name);
        EXPECT_EQ(std::memcmp(rgb, src, sizeof rgb), 0) << name;
        config()->fromWorking(rgb, 2, name);
        EXPECT_EQ(std::memcmp(rgb, src, sizeof rgb), 0) << name;
    }
    float rgb[6];
    std::memcpy(rgb, src, sizeof rgb);
    config()->toDisplay(rgb, 2, "Raw");
    for (int i = 0; i < 6; ++i) EXPECT_FLOAT_EQ(rgb[i], src[i]);
}

TEST(ColorConfig, AcesCgRoundTrip) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 4.f);
    std::vector<float> v(300), orig;
    for (auto& x : v) x = u(rng);
    orig = v;
    config()->fromWorking(v.data(), 100, "acescg");
    config()->toWorking(v.data(), 100, "ACEScg");
    for (size_t i = 0; i < v.size(); ++i) EXPECT_NEAR(v[i], orig[i], 1e-5f * std::max(1.f, orig[i]));
    // Pure ACEScg red is outside Rec.709: negative green/blue in the working space.
    float red[3] = {1.f, 0.f, 0.f};
    config()->toWorking(red, 1, "ACEScg");
    EXPECT_NEAR(red[0], 1.70505f, 1e-4f);
    EXPECT_NEAR(red[1], -0.13026f, 1e-4f);
    EXPECT_NEAR(red[2], -0.02400f, 1e-4f);
    // White stays white.
    float white[3] = {1.f, 1.f, 1.f};
    config()->toWorking(white, 1, "ACEScg");
    for (float w : white) EXPECT_NEAR(w, 1.f, 1e-4f);
}

TEST(ColorConfig, FilmicViewIsMonotonicAndBounded) {
    std::vector<float> xs = {0.f};
    for (float e = -14.f; e <= 14.f; e += 0.05f) xs.push_back(0.18f * std::exp2(e));
    xs.push_back(1e6f);
    std::vector<float> rgb;
    for (float x : xs) rgb.insert(rgb.end(), {x, x, x});
    config()->toDisplay(rgb.data(), xs.size(), "Filmic");
    EXPECT_NEAR(rgb[0], 0.f, 1e-3f);
    for (size_t i = 1; i < xs.size(); ++i) {
        EXPECT_GE(rgb[i * 3], rgb[(i - 1) * 3]) << "at x=" << xs[i];
        EXPECT_LT(rgb[i * 3], 1.f);
    }
    // Strictly increasing through the useful range, highlights compressed relative to Standard.
    float probe[12] = {0.01f, 0.01f, 0.01f, 0.18f, 0.18f, 0.18f, 1.f, 1.f, 1.f, 4.f, 4.f, 4.f};
    config()->toDisplay(probe, 4, "Filmic");
    EXPECT_LT(probe[0], probe[3]);
    EXPECT_LT(probe[3], probe[6]);
    EXPECT_LT(probe[6], probe[9]);
    EXPECT_LT(probe[6], 0.95f);  // 1.0 is not clipped as in Standard
    EXPECT_GT(probe[9], 0.9f);
    EXPECT_NEAR(probe[3], 0.46f, 0.03f);  // middle grey where Standard puts it
}

TEST(ColorConfig, UnknownNamesListValidAndNearest) {
    float rgb[3] = {0.5f, 0.5f, 0.5f};
    // The ColorError message of call() names every fragment.
    auto expectColorError = [](const auto& call, std::initializer_list<const char*> fragments) {
        try {
            call();
            ADD_FAILURE() << "expected ColorError";
        } catch (const ColorError& e) {
            const std::string m = e.what();
            for (const char* f : fragments) EXPECT_NE(m.find(f), std::string::npos) << m;
        }
    };
    expectColorError([&] { config()->toWorking(rgb, 1, "srgb_textur"); },
                     {"did you mean 'srgb_texture'", "ACEScg", "Raw"});
    expectColorError([&] { config()->toDisplay(rgb, 1, "Filmc"); }, {"did you mean 'Filmic'", "Standard"});
    EXPECT_THROW(config()->toWorking(rgb, 0, "nope"), ColorError);  // validated even with no pixels
}

// Issue 17 item 5: every colorspace name, alias and role the built-in config accepts is in docs/scene-format.md's
// "Colorspace names" section (as `name`, compared without case, as the loader compares them).
TEST(ColorConfig, EveryAcceptedColorspaceNameIsDocumented) {
    const std::string page = test::readFile(test::sourcePath("docs/scene-format.md"));
    const size_t from = page.find("### Colorspace names"), to = page.find("\n## ", from);
    ASSERT_NE(from, std::string::npos);
    std::string section = page.substr(from, to - from);
    auto lower = [](std::string t) {
        for (char& c : t) c = char(std::tolower(static_cast<unsigned char>(c)));
        return t;
    };
    section = lower(section);
    const std::vector<std::string> names = config()->acceptedColorspaceNames();
    EXPECT_GT(names.size(), 20u);
    for (const std::string& n : names)
        EXPECT_NE(section.find("`" + lower(n) + "`"), std::string::npos) << "'" << n << "' is accepted but not documented";
}

TEST(ColorConfig, ConcurrentConversionsAgree) {
    std::vector<std::thread> threads;
    std::vector<float> results(8, 0.f);
    for (int t = 0; t < 8; ++t)
        threads.emplace_back([&, t] {
            for (int k = 0; k < 50; ++k) {
                float rgb[3] = {0.5f, 0.18f, 0.7f};
                config()->toWorking(rgb, 1, k % 2 ? "sRGB" : "acescg");
                float d[3] = {0.18f, 0.18f, 0.18f};
                config()->toDisplay(d, 1, k % 3 ? "Filmic" : "Standard", float(k % 4));
                if (k == 49) results[size_t(t)] = rgb[0] + d[0];
            }
        });
    for (auto& th : threads) th.join();
    for (float r : results) EXPECT_FLOAT_EQ(r, results[0]);
}

// ---- Image I/O --------------------------------------------------------------------------------------

TEST(ImageIo, ExrRoundTripIsBitExact) {
    std::string dir = test::tempDir("exr");
    std::string path = dir + "/three.exr";
    ImageSet s = makeSet(13, 7, 42);
    writeExr(path, s, *config());
    ImageSet r = readImageSet(path);
    ASSERT_EQ(r.width, 13);
    ASSERT_EQ(r.height, 7);
    ASSERT_EQ(r.aovs.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(r.aovs[i].name, s.aovs[i].name);
        EXPECT_EQ(r.aovs[i].channelNames, s.aovs[i].channelNames);
        ASSERT_EQ(r.aovs[i].pixels.size(), s.aovs[i].pixels.size());
        EXPECT_EQ(std::memcmp(r.aovs[i].pixels.data(), s.aovs[i].pixels.data(), s.aovs[i].pixels.size() * 4), 0)
            << s.aovs[i].name;
    }
    EXPECT_EQ(r.metadata["specula:spp"], "64");
    EXPECT_EQ(r.metadata["oiio:ColorSpace"], config()->workingSpace());
    EXPECT_TRUE(leftovers(dir).empty());
}

TEST(ImageIo, ExrChannelNamesFormatAndMetadata) {
    std::string dir = test::tempDir("exrnames");
    std::string path = dir + "/aovs.exr";
    const int w = 4, h = 3;
    const size_t n = size_t(w) * size_t(h);
    ImageSet s;
    s.width = w;
    s.height = h;
    s.aovs.push_back({"beauty", {"R", "G", "B"}, std::vector<float>(n * 3, 0.5f)});
    s.aovs.push_back({"diffuse", {"R", "G", "B"}, std::vector<float>(n * 3, 0.25f)});
    s.aovs.push_back({"normal", {"X", "Y", "Z"}, std::vector<float>(n * 3, -0.5f)});
    s.aovs.push_back({"uv", {"U", "V"}, std::vector<float>(n * 2, 0.75f)});
    s.aovs.push_back({"depth", {"Z"}, std::vector<float>(n, 12.5f)});
    s.metadata["specula:scene"] = "cornell.json";
    writeExr(path, s, *config());

    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in);
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<std::string> names = spec.channelnames;
    std::sort(names.begin(), names.end());
    std::vector<std::string> expect = {"B",        "G",        "R",        "depth.Z",  "diffuse.B", "diffuse.G",
                                       "diffuse.R", "normal.X", "normal.Y", "normal.Z", "uv.U",      "uv.V"};
    EXPECT_EQ(names, expect);
    EXPECT_EQ(spec.format, OIIO::TypeDesc::FLOAT);
    for (const auto& f : spec.channelformats) EXPECT_EQ(f, OIIO::TypeDesc::FLOAT);
    EXPECT_EQ(spec.get_string_attribute("compression"), "zip");
    EXPECT_EQ(spec.get_string_attribute("specula:colorSpace"), "Linear Rec.709 (sRGB)");
    EXPECT_EQ(spec.get_string_attribute("specula:scene"), "cornell.json");
    in->close();

    ImageSet r = readImageSet(path);
    ASSERT_EQ(r.aovs.size(), 5u);
    EXPECT_EQ(r.aovs[0].name, "beauty");
    EXPECT_EQ(r.metadata["oiio:ColorSpace"], "Linear Rec.709 (sRGB)");
    ASSERT_TRUE(r.find("uv"));
    EXPECT_EQ(r.find("uv")->channelNames, (std::vector<std::string>{"U", "V"}));
    ASSERT_TRUE(r.find("depth"));
    EXPECT_EQ(r.find("depth")->pixels[5], 12.5f);
}

TEST(ImageIo, ReadsPlainImagesAndUnprefixedChannels) {
    std::string dir = test::tempDir("plain");
    // Luminance + Z EXR written by someone else.
    std::string path = dir + "/yz.exr";
    {
        auto out = OIIO::ImageOutput::create(path);
        OIIO::ImageSpec spec(2, 2, 2, OIIO::TypeDesc::FLOAT);
        spec.channelnames = {"Y", "Z"};
        ASSERT_TRUE(out->open(path, spec));
        float px[8] = {0.1f, 1.f, 0.2f, 2.f, 0.3f, 3.f, 0.4f, 4.f};
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px));
        out->close();
    }
    ImageSet r = readImageSet(path);
    ASSERT_TRUE(r.find("beauty"));
    EXPECT_EQ(r.find("beauty")->channelNames, std::vector<std::string>{"Y"});
    EXPECT_FLOAT_EQ(r.find("beauty")->pixels[3], 0.4f);
    ASSERT_TRUE(r.find("depth"));
    EXPECT_FLOAT_EQ(r.find("depth")->pixels[2], 3.f);

    std::string png = dir + "/plain.png";
    writePng8(png, 2, 1, {0, 128, 255, 10, 20, 30});
    ImageSet p = readImageSet(png);
    ASSERT_EQ(p.aovs.size(), 1u);
    EXPECT_EQ(p.aovs[0].name, "beauty");
    EXPECT_EQ(p.aovs[0].channelNames, (std::vector<std::string>{"R", "G", "B"}));
    EXPECT_FLOAT_EQ(p.aovs[0].pixels[2], 1.f);
    EXPECT_THROW(readImageSet(dir + "/missing.exr"), ImageIoError);
}

TEST(ImageIo, PngGoesThroughTheViewAndIsTaggedSrgb) {
    std::string dir = test::tempDir("png");
    std::string path = dir + "/grey.png";
    writePng(path, constantSet(3, 2, 0.18f), *config(), "Standard");
    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().format, OIIO::TypeDesc::UINT8);
    EXPECT_EQ(in->spec().nchannels, 3);
    EXPECT_EQ(in->spec().get_string_attribute("oiio:ColorSpace"), "sRGB");
    std::vector<uint8_t> px(3 * 2 * 3);
    ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()));
    in->close();
    for (uint8_t v : px) EXPECT_EQ(v, 118);  // round(0.46136 * 255)

    writePng(path, constantSet(3, 2, 0.18f), *config(), "", 2.f);  // default view, +2 stops: 0.72
    ImageSet r = readImageSet(path);
    float expect = 0.72f;
    config()->toDisplay(&expect, 0, "Standard");  // (validates only)
    float e3[3] = {0.72f, 0.72f, 0.72f};
    config()->toDisplay(e3, 1, "Standard");
    EXPECT_NEAR(r.aovs[0].pixels[0], std::round(e3[0] * 255.f) / 255.f, 1e-6f);
    EXPECT_THROW(writePng(dir + "/bad.png", constantSet(2, 2, 0.1f), *config(), "Filmc"), ImageIoError);
    EXPECT_FALSE(fs::exists(dir + "/bad.png"));
    EXPECT_TRUE(leftovers(dir).empty());
}

TEST(ImageIo, AtomicWrites) {
    std::string dir = test::tempDir("atomic");
    // Non-existent directory: throws, creates nothing.
    std::string missingDir = dir + "/no/such/dir";
    EXPECT_THROW(writeExr(missingDir + "/x.exr", constantSet(2, 2, 1.f), *config()), ImageIoError);
    EXPECT_THROW(writePng(missingDir + "/x.png", constantSet(2, 2, 1.f), *config(), ""), ImageIoError);
    EXPECT_THROW(writeFileAtomic(missingDir + "/x.txt", "hello"), ImageIoError);
    EXPECT_FALSE(fs::exists(dir + "/no"));

    // An existing file is replaced only on success.
    std::string path = dir + "/out.exr";
    test::writeFile(path, "old contents");
    ImageSet bad = constantSet(2, 2, 1.f);
    bad.aovs[0].pixels.resize(5);  // inconsistent: rejected
    EXPECT_THROW(writeExr(path, bad, *config()), ImageIoError);
    EXPECT_EQ(test::readFile(path), "old contents");
    writeExr(path, constantSet(2, 2, 0.5f), *config());
    EXPECT_FLOAT_EQ(readImageSet(path).aovs[0].pixels[0], 0.5f);

    // A failure after the temp file exists (rename onto a directory) removes the temp file.
    fs::create_directories(dir + "/adir.exr");
    EXPECT_THROW(writeExr(dir + "/adir.exr", constantSet(2, 2, 0.5f), *config()), ImageIoError);
    EXPECT_THROW(writeFileAtomic(dir + "/adir.exr", "bytes"), ImageIoError);
    EXPECT_TRUE(fs::is_directory(dir + "/adir.exr"));

    writeFileAtomic(dir + "/note.txt", "first");
    writeFileAtomic(dir + "/note.txt", "second");
    EXPECT_EQ(test::readFile(dir + "/note.txt"), "second");
    EXPECT_TRUE(leftovers(dir).empty()) << leftovers(dir).front();
}

TEST(ImageIo, CompareImages) {
    std::string dir = test::tempDir("cmp");
    std::string a = dir + "/a.exr", b = dir + "/b.exr", a2 = dir + "/a2.exr";
    writeExr(a, constantSet(16, 8, 0.25f, "normal"), *config());
    writeExr(a2, constantSet(16, 8, 0.25f, "normal"), *config());
    writeExr(b, constantSet(16, 8, 0.5f, "normal"), *config());

    CompareResult same = compareImages(a, a2);
    EXPECT_EQ(same.rmse, 0.0);
    EXPECT_EQ(same.mae, 0.0);
    EXPECT_TRUE(std::isinf(same.psnr) && same.psnr > 0);
    EXPECT_EQ(same.width, 16);
    EXPECT_EQ(same.channels, 3);

    CompareResult off = compareImages(a, b, "beauty", dir + "/diff.png");
    EXPECT_DOUBLE_EQ(off.rmse, 0.25);
    EXPECT_DOUBLE_EQ(off.mae, 0.25);
    EXPECT_DOUBLE_EQ(off.peak, 0.5);  // b is the reference: PSNR uses its peak, not 1
    EXPECT_NEAR(off.psnr, 20.0 * std::log10(0.5 / 0.25), 1e-9);
    EXPECT_NEAR(off.meanA, 0.25, 1e-9);
    EXPECT_NEAR(off.meanB, 0.5, 1e-9);
    ASSERT_TRUE(fs::exists(dir + "/diff.png"));
    ImageSet diff = readImageSet(dir + "/diff.png");
    EXPECT_EQ(diff.width, 16);
    EXPECT_GT(diff.height, 8);  // image + colour bar

    CompareResult nrm = compareImages(a, b, "normal");
    EXPECT_EQ(nrm.rmse, 0.0);

    try {
        compareImages(a, b, "specular");
        FAIL() << "expected ImageIoError";
    } catch (const ImageIoError& e) {
        std::string m = e.what();
        EXPECT_NE(m.find("specular"), std::string::npos) << m;
        EXPECT_NE(m.find("beauty"), std::string::npos) << m;
        EXPECT_NE(m.find("normal"), std::string::npos) << m;
    }
    std::string c = dir + "/c.exr";
    writeExr(c, constantSet(8, 8, 0.25f), *config());
    try {
        compareImages(a, c);
        FAIL() << "expected ImageIoError";
    } catch (const ImageIoError& e) {
        std::string m = e.what();
        EXPECT_NE(m.find("16x8"), std::string::npos) << m;
        EXPECT_NE(m.find("8x8"), std::string::npos) << m;
    }
    EXPECT_THROW(compareImages(a, dir + "/nope.exr"), ImageIoError);
}

TEST(ImageIo, DiffMapOfAVaryingDifference) {
    std::string dir = test::tempDir("diffmap");
    ImageSet A = constantSet(64, 32, 0.f), B = constantSet(64, 32, 0.f);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            for (int c = 0; c < 3; ++c) B.aovs[0].pixels[(size_t(y) * 64 + size_t(x)) * 3 + size_t(c)] = float(x) / 63.f;
    writeExr(dir + "/a.exr", A, *config());
    writeExr(dir + "/b.exr", B, *config());
    CompareResult r = compareImages(dir + "/a.exr", dir + "/b.exr", "beauty", dir + "/d.png");
    EXPECT_NEAR(r.mae, 0.5, 1e-6);
    ImageSet d = readImageSet(dir + "/d.png");
    const auto& p = d.aovs[0].pixels;
    // Left column is the colormap's low end, right column its high end: they differ.
    float left = p[0] + p[1] + p[2], right = p[63 * 3] + p[63 * 3 + 1] + p[63 * 3 + 2];
    EXPECT_GT(std::fabs(left - right), 0.3f);
}

// ---- TextureStore -----------------------------------------------------------------------------------

namespace {

struct TextureFixture : ::testing::Test {
    std::string dir;
    std::string png;
    static constexpr uint8_t kA = 51, kB = 204;  // sRGB codes of the checker
    void SetUp() override {
        dir = test::tempDir("tex");
        setenv("SPECULA_CACHE_DIR", (dir + "/cache").c_str(), 1);
        png = dir + "/checker.png";
        std::vector<uint8_t> rgb;
        for (int y = 0; y < 8; ++y)  // row 0 = top
            for (int x = 0; x < 8; ++x) {
                uint8_t v = ((x + y) % 2) ? kB : kA;
                // Mark the bottom-left texel red-ish so orientation is unambiguous.
                if (x == 0 && y == 7) rgb.insert(rgb.end(), {255, 0, 0});
                else rgb.insert(rgb.end(), {v, v, v});
            }
        writePng8(png, 8, 8, rgb);
    }
    static float lin(uint8_t code) { return srgbDecode(float(code) / 255.f); }
};

}  // namespace

TEST_F(TextureFixture, TexelCentresGiveDecodedValues) {
    TextureStore store(config());
    TextureHandle h = store.load(png, "sRGB");
    ASSERT_TRUE(h.valid());
    EXPECT_EQ(store.width(h), 8);
    EXPECT_EQ(store.height(h), 8);
    EXPECT_EQ(store.channels(h), 3);
    const auto& px = store.pixels(h);
    ASSERT_EQ(px.size(), 8u * 8u * 3u);
    EXPECT_NEAR(px[0], lin(kA), 1e-5f);                    // top-left
    EXPECT_NEAR(px[(7 * 8 + 0) * 3 + 0], 1.f, 1e-5f);      // bottom-left marker (red)
    EXPECT_NEAR(px[(7 * 8 + 0) * 3 + 1], 0.f, 1e-6f);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            Vec2 uv((x + 0.5f) / 8.f, 1.f - (y + 0.5f) / 8.f);  // y counts from the top
            Color3 c = store.sampleRgb(h, uv, Vec2(0.f), Vec2(0.f));
            const float* e = &px[(size_t(y) * 8 + size_t(x)) * 3];
            EXPECT_NEAR(c.x, e[0], 1e-5f) << x << "," << y;
            EXPECT_NEAR(c.y, e[1], 1e-5f) << x << "," << y;
            EXPECT_NEAR(c.z, e[2], 1e-5f) << x << "," << y;
        }
}

TEST_F(TextureFixture, VZeroIsTheBottomRow) {
    TextureStore store(config());
    TextureHandle h = store.load(png, "srgb_texture");
    Color3 bottomLeft = store.sampleRgb(h, Vec2(0.5f / 8.f, 0.01f), Vec2(0.f), Vec2(0.f), TextureWrap::Clamp);
    EXPECT_NEAR(bottomLeft.x, 1.f, 1e-4f);
    EXPECT_NEAR(bottomLeft.y, 0.f, 1e-4f);
    Color3 topLeft = store.sampleRgb(h, Vec2(0.5f / 8.f, 0.99f), Vec2(0.f), Vec2(0.f), TextureWrap::Clamp);
    EXPECT_NEAR(topLeft.x, lin(kA), 1e-4f);
    EXPECT_NEAR(topLeft.y, lin(kA), 1e-4f);
}

TEST_F(TextureFixture, LargeFootprintGivesTheAverage) {
    TextureStore store(config());
    TextureHandle h = store.load(png, "sRGB");
    double mean = 0;
    for (float v : store.pixels(h)) mean += v;
    mean /= double(store.pixels(h).size());
    Color3 c = store.sampleRgb(h, Vec2(0.5f, 0.5f), Vec2(1.f, 0.f), Vec2(0.f, 1.f));
    float got = (c.x + c.y + c.z) / 3.f;
    EXPECT_NEAR(got, mean, 0.02 * mean);
    // Green: the checker's linear mean, except the marker (a kB texel whose green is 0), within 2%.
    float checkerMean = 0.5f * (lin(kA) + lin(kB));
    EXPECT_NEAR(c.y, checkerMean - lin(kB) / 64.f, 0.02f * checkerMean);
    // An anisotropic footprint (wide in u only) averages along u but not v on the top row.
    Color3 row = store.sampleRgb(h, Vec2(0.5f, 1.f - 0.5f / 8.f), Vec2(1.f, 0.f), Vec2(0.f, 1.f / 64.f),
                                 TextureWrap::Clamp);
    EXPECT_NEAR(row.y, checkerMean, 0.05f * checkerMean);
}

TEST_F(TextureFixture, WrapModes) {
    TextureStore store(config());
    TextureHandle h = store.load(png, "sRGB");
    const auto& px = store.pixels(h);
    auto texel = [&](int x, int y) { return px[(size_t(y) * 8 + size_t(x)) * 3 + 1]; };  // green channel
    const float v = 1.f - 2.5f / 8.f;  // row 2 from the top
    auto at = [&](float u, TextureWrap w) { return store.sampleRgb(h, Vec2(u, v), Vec2(0.f), Vec2(0.f), w).y; };
    EXPECT_NEAR(at(1.f + 1.5f / 8.f, TextureWrap::Repeat), texel(1, 2), 1e-5f);
    EXPECT_NEAR(at(-1.f + 1.5f / 8.f, TextureWrap::Repeat), texel(1, 2), 1e-5f);
    EXPECT_NEAR(at(1.5f, TextureWrap::Clamp), texel(7, 2), 1e-5f);
    EXPECT_NEAR(at(-0.5f, TextureWrap::Clamp), texel(0, 2), 1e-5f);
    EXPECT_NEAR(at(1.f + 1.5f / 8.f, TextureWrap::Mirror), texel(6, 2), 1e-5f);
    EXPECT_NEAR(at(1.5f, TextureWrap::Black), 0.f, 1e-6f);
    EXPECT_NEAR(at(1.5f / 8.f, TextureWrap::Black), texel(1, 2), 1e-5f);
}

TEST_F(TextureFixture, RawChannelsAndFill) {
    TextureStore store(config());
    TextureHandle raw = store.load(png, "raw");
    TextureHandle srgb = store.load(png, "sRGB");
    EXPECT_NE(raw.index, srgb.index);
    EXPECT_NEAR(store.pixels(raw)[0], kA / 255.f, 1e-6f);  // not decoded
    float out[4];
    store.sample(raw, Vec2(0.5f / 8.f, 1.f - 0.5f / 8.f), Vec2(0.f), Vec2(0.f), out, 4);
    EXPECT_NEAR(out[0], kA / 255.f, 1e-6f);
    EXPECT_FLOAT_EQ(out[3], 1.f);  // alpha filled with 1

    // A one-channel texture replicates to RGB.
    std::string grey = dir + "/grey.png";
    {
        auto o = OIIO::ImageOutput::create(grey);
        OIIO::ImageSpec spec(2, 2, 1, OIIO::TypeDesc::UINT8);
        ASSERT_TRUE(o->open(grey, spec));
        uint8_t g[4] = {128, 128, 128, 128};
        ASSERT_TRUE(o->write_image(OIIO::TypeDesc::UINT8, g));
        o->close();
    }
    TextureHandle gh = store.load(grey, "sRGB");
    EXPECT_EQ(store.channels(gh), 1);
    Color3 c = store.sampleRgb(gh, Vec2(0.5f), Vec2(0.f), Vec2(0.f));
    EXPECT_NEAR(c.x, lin(128), 1e-5f);
    EXPECT_NEAR(c.z, lin(128), 1e-5f);
}

TEST_F(TextureFixture, ReuseAndCache) {
    TextureStore store(config());
    TextureHandle a = store.load(png, "sRGB");
    TextureHandle b = store.load(png, "sRGB - Texture");  // same canonical colorspace
    EXPECT_EQ(a.index, b.index);
    std::vector<fs::path> tx;
    for (auto& e : fs::recursive_directory_iterator(dir + "/cache"))
        if (e.path().extension() == ".tx") tx.push_back(e.path());
    ASSERT_EQ(tx.size(), 1u);
    auto stamp = fs::last_write_time(tx[0]);
    {
        TextureStore other(config());
        TextureHandle c = other.load(png, "srgb");
        EXPECT_NEAR(other.pixels(c)[0], lin(kA), 1e-5f);
    }
    size_t count = 0;
    for (auto& e : fs::recursive_directory_iterator(dir + "/cache")) {
        if (e.path().extension() == ".tx") ++count;
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos);
    }
    EXPECT_EQ(count, 1u);
    EXPECT_EQ(fs::last_write_time(tx[0]), stamp);  // reused, not rebuilt
}

TEST_F(TextureFixture, Errors) {
    TextureStore store(config());
    try {
        store.load(dir + "/missing.png", "sRGB");
        FAIL();
    } catch (const TextureError& e) {
        EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos);
    }
    try {
        store.load(png, "sRGBB");
        FAIL();
    } catch (const TextureError& e) {
        std::string m = e.what();
        EXPECT_NE(m.find("checker.png"), std::string::npos) << m;
        EXPECT_NE(m.find("did you mean"), std::string::npos) << m;
    }
    std::string junk = dir + "/junk.png";
    test::writeFile(junk, "not a png at all");
    try {
        store.load(junk, "sRGB");
        FAIL();
    } catch (const TextureError& e) {
        EXPECT_NE(std::string(e.what()).find("junk.png"), std::string::npos);
    }
    EXPECT_THROW(store.width(TextureHandle{}), TextureError);
    EXPECT_THROW(store.width(TextureHandle{99}), TextureError);
}

TEST_F(TextureFixture, ConcurrentSamplingIsConsistent) {
    TextureStore store(config());
    TextureHandle h = store.load(png, "sRGB");
    std::vector<double> sums(4, 0.0);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            double s = 0;
            for (int i = 0; i < 4000; ++i) {
                float u = float(i % 97) / 97.f, v = float(i % 89) / 89.f;
                Color3 c = store.sampleRgb(h, Vec2(u, v), Vec2(0.01f * float(i % 5), 0.f), Vec2(0.f, 0.01f));
                s += double(c.x + c.y + c.z);
            }
            sums[size_t(t)] = s;
        });
    for (auto& th : threads) th.join();
    for (double s : sums) EXPECT_EQ(s, sums[0]);
}

// ---- cache checksums (issue 35) --------------------------------------------------------------------------------

TEST(CacheChecksum, DependsOnTheBytesNotOnHowTheyArrive) {
    std::vector<unsigned char> bytes(1000);
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = uint8_t(i * 7 + 3);
    const uint64_t whole = contentChecksum(bytes.data(), bytes.size());
    for (size_t piece : {1u, 3u, 7u, 8u, 13u, 999u}) {
        ContentChecksum c;
        for (size_t at = 0; at < bytes.size(); at += piece) c.add(bytes.data() + at, std::min(piece, bytes.size() - at));
        EXPECT_EQ(c.value(), whole) << "pieces of " << piece;
    }
    // Every single bit flip changes it, and so do a trailing zero and a truncation.
    for (size_t i = 0; i < bytes.size(); i += 37)
        for (int bit = 0; bit < 8; ++bit) {
            std::vector<unsigned char> flipped = bytes;
            flipped[i] ^= uint8_t(1u << bit);
            EXPECT_NE(contentChecksum(flipped.data(), flipped.size()), whole) << i << ":" << bit;
        }
    std::vector<unsigned char> padded = bytes;
    padded.push_back(0);
    EXPECT_NE(contentChecksum(padded.data(), padded.size()), whole);
    EXPECT_NE(contentChecksum(bytes.data(), bytes.size() - 1), whole);
}

// A cached .tx that is corrupted (bytes flipped, truncated, a valid texture of other content under its name, or
// without its checksum sidecar) is rebuilt, not sampled: every lookup equals the one through the intact cache bit for
// bit, and the rebuilt file carries a matching checksum. Before issue 35, OIIO sampled such a file unchecked.
TEST_F(TextureFixture, CorruptedCacheIsRebuiltNotUsed) {
    // Lookups through the intact cache: texel centres and a few footprints (they read the coarser MIP levels too).
    auto lookups = [](TextureStore& store, TextureHandle h) {
        std::vector<float> v;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
                const Vec2 uv((x + 0.5f) / 8.f, (y + 0.5f) / 8.f);
                for (float width : {0.f, 0.3f, 1.f}) {
                    Color3 c = store.sampleRgb(h, uv, Vec2(width, 0.f), Vec2(0.f, width));
                    v.insert(v.end(), {c.x, c.y, c.z});
                }
            }
        return v;
    };
    auto txFiles = [](const std::string& folder) {
        std::vector<fs::path> tx;
        for (auto& e : fs::recursive_directory_iterator(folder))
            if (e.path().extension() == ".tx") tx.push_back(e.path());
        return tx;
    };
    std::vector<float> reference;
    {
        TextureStore store(config());
        reference = lookups(store, store.load(png, "sRGB"));
    }
    const std::vector<fs::path> intact = txFiles(dir + "/cache");
    ASSERT_EQ(intact.size(), 1u);
    ASSERT_TRUE(cacheChecksumMatches(intact[0].string()));
    const std::string intactBytes = test::readFile(intact[0].string());

    // A valid texture of other content and the same size: the inverted checker, cached in a folder of its own.
    const std::string otherPng = dir + "/inverted.png";
    {
        std::vector<uint8_t> rgb;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
                const uint8_t v = ((x + y) % 2) ? kA : kB;
                rgb.insert(rgb.end(), {v, v, v});
            }
        writePng8(otherPng, 8, 8, rgb);
        setenv("SPECULA_CACHE_DIR", (dir + "/cache-other").c_str(), 1);
        TextureStore store(config());
        store.load(otherPng, "sRGB");
    }
    const std::vector<fs::path> others = txFiles(dir + "/cache-other");
    ASSERT_EQ(others.size(), 1u);
    const std::string foreignBytes = test::readFile(others[0].string());

    std::string flipped = intactBytes;
    for (size_t i = flipped.size() / 3; i < flipped.size(); i += 61) flipped[i] = char(flipped[i] ^ 0x5a);
    const struct {
        const char* name;
        std::string bytes;
        bool keepSidecar;
    } corruptions[] = {
        {"flipped", flipped, true},
        {"truncated", intactBytes.substr(0, intactBytes.size() / 2), true},
        {"foreign", foreignBytes, true},
        {"no-sidecar", intactBytes, false},
    };
    for (const auto& c : corruptions) {
        SCOPED_TRACE(c.name);
        const std::string base = dir + "/cache-" + c.name;
        const fs::path file = fs::path(base) / intact[0].parent_path().filename() / intact[0].filename();
        fs::create_directories(file.parent_path());
        test::writeFile(file.string(), c.bytes);
        if (c.keepSidecar) fs::copy_file(cacheChecksumPath(intact[0].string()), cacheChecksumPath(file.string()));
        setenv("SPECULA_CACHE_DIR", base.c_str(), 1);
        TextureStore store(config());
        const std::vector<float> got = lookups(store, store.load(png, "sRGB"));
        ASSERT_EQ(got.size(), reference.size());
        EXPECT_EQ(std::memcmp(got.data(), reference.data(), got.size() * sizeof(float)), 0);
        EXPECT_TRUE(cacheChecksumMatches(file.string()));
        if (c.keepSidecar) {  // replaced by a rebuild (compared by checksum: a failure should not print the file)
            const std::string now = test::readFile(file.string());
            EXPECT_NE(contentChecksum(now.data(), now.size()), contentChecksum(c.bytes.data(), c.bytes.size()));
        }
    }
}
