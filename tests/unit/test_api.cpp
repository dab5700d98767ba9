// libspecula's public API (include/specula/specula.h, docs/api.md): loading, setLiteral, asynchronous
// rendering with tile pixel access and cancel, the output policy, GLSL, the catalogue, errors, and the
// lazily loaded image I/O module.
#include "specula/specula.h"

#include "core/api/specula.h"
#include "core/graph/node_spec.h"
#include "core/io_module/io_module.h"
#include "core/util/input_files.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <set>
#include <sys/stat.h>
#include <thread>

namespace fs = std::filesystem;
namespace sp = specula::api;
using specula::Error;
using specula::ErrorCode;

namespace {

const char* kScene = R"({
  "version": 1,
  "render": {"width": 80, "height": 40, "spp": 2, "seed": 3},
  "camera": {"position": [0, -4, 1], "look_at": [0, 0, 0.6], "fov": 40},
  "materials": {
    "gold": {"nodes": {"spec": {"type": "bsdf.ggx", "inputs": {"roughness": 0.1}}}, "output": "@spec.bsdf"},
    "floor": {"nodes": {"base": {"type": "bsdf.diffuse", "inputs": {"color": [0.5, 0.5, 0.5]}}}, "output": "@base.bsdf"}
  },
  "shapes": [
    {"type": "sphere", "radius": 0.6, "transform": {"translate": [0, 0, 0.6]}, "material": "gold"},
    {"type": "quad", "size": [8, 8], "material": "floor"}
  ],
  "lights": [{"type": "point", "position": [1.5, -2, 3], "power": 400}]
})";

std::vector<float> beauty(const sp::RenderResult& r) {
    sp::AovView b = r.aov("beauty");
    return std::vector<float>(b.pixels, b.pixels + size_t(b.width) * b.height * 3);
}

}  // namespace

TEST(Api, RegisterBuiltinNodesIsIdempotentAndThreadSafe) {
    std::vector<std::thread> t;
    for (int i = 0; i < 4; ++i) t.emplace_back([] { specula::registerBuiltinNodes(); });
    for (auto& x : t) x.join();
    size_t n = specula::graph::NodeRegistry::instance().ids().size();
    specula::registerBuiltinNodes();
    EXPECT_EQ(specula::graph::NodeRegistry::instance().ids().size(), n);
    EXPECT_NE(specula::graph::NodeRegistry::instance().find("bsdf.ggx"), nullptr);
    std::string cat = sp::nodeCatalogJson(-1);
    EXPECT_NE(cat.find("\"id\":\"bsdf.ggx\""), std::string::npos);
}

TEST(Api, StringFileAndBuilderGiveTheSameImage) {
    std::string dir = specula::test::tempDir("api_load");
    specula::test::writeFile(dir + "/s.json", kScene);
    sp::RenderResult a = sp::Scene::fromString(kScene).render();
    sp::RenderResult b = sp::Scene::fromFile(dir + "/s.json").render();
    EXPECT_EQ(beauty(a), beauty(b));

    const float pos[3] = {0, -4, 1}, at[3] = {0, 0, 0.6f}, c[3] = {0, 0, 0.6f};
    sp::Scene built = sp::SceneBuilder()
                          .resolution(80, 40)
                          .samples(2, 3)
                          .camera(pos, at, 40)
                          .material("gold", R"({"nodes": {"spec": {"type": "bsdf.ggx", "inputs": {"roughness": 0.1}}}, "output": "@spec.bsdf"})")
                          .material("floor", R"({"nodes": {"base": {"type": "bsdf.diffuse", "inputs": {"color": [0.5, 0.5, 0.5]}}}, "output": "@base.bsdf"})")
                          .sphere(c, 0.6f, "gold")
                          .shape(R"({"type": "quad", "size": [8, 8], "material": "floor"})")
                          .light(R"({"type": "point", "position": [1.5, -2, 3], "power": 400})")
                          .build();
    EXPECT_EQ(beauty(built.render()), beauty(a));
}

TEST(Api, SetLiteralRecompilesOneMaterialAndMatchesAFreshLoad) {
    sp::Scene s = sp::Scene::fromString(kScene);
    s.setLiteral("/materials/gold/nodes/spec/inputs/roughness", "0.5");
    std::string edited = kScene;
    edited.replace(edited.find("\"roughness\": 0.1"), 16, "\"roughness\": 0.5");
    EXPECT_EQ(beauty(s.render()), beauty(sp::Scene::fromString(edited).render()));
    EXPECT_NE(s.json().find("0.5"), std::string::npos);

    // A bad edit throws with the pointer and leaves the scene unchanged.
    std::vector<float> before = beauty(s.render());
    try {
        s.setLiteral("/materials/gold/nodes/spec/inputs/roughness", "\"rough\"");
        FAIL() << "expected an Error";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::BadInput);
        EXPECT_EQ(e.pointer().rfind("/materials/gold/nodes/spec/inputs/roughness", 0), 0u) << e.what();
    }
    try {
        s.setLiteral("/materials/glod/nodes/spec/inputs/roughness", "0.2");
        FAIL() << "expected an Error";
    } catch (const Error& e) {
        EXPECT_EQ(e.pointer(), "/materials/glod");
        EXPECT_EQ(e.suggestion(), "gold");
    }
    EXPECT_THROW(s.setLiteral("/camera/fov", "30"), Error);
    EXPECT_EQ(beauty(s.render()), before);
}

// LoadOptions::max* (issue 16 item 2): a host's caps refuse the scene at the pointer of what exceeds them; a cap can
// only lower the built-in maximum, and the same scene loads under caps it fits.
TEST(Api, LoadOptionLimitsRefuseScenesBeyondThem) {
    auto refusedAt = [](const sp::LoadOptions& lo) {
        try {
            sp::Scene::fromString(kScene, "", lo);
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::BadInput) << e.what();
            return e.pointer();
        }
        return std::string("(loaded)");
    };
    sp::LoadOptions lo;
    lo.maxSpp = 1;
    EXPECT_EQ(refusedAt(lo), "/render/spp");
    lo = {};
    lo.maxPixels = 100;
    EXPECT_EQ(refusedAt(lo), "/render/width");
    lo = {};
    lo.maxTriangles = 100;
    EXPECT_EQ(refusedAt(lo).rfind("/shapes/", 0), 0u);
    lo = {};
    lo.maxGraphNodes = 1;  // every material of kScene has one node: it fits
    EXPECT_EQ(refusedAt(lo), "(loaded)");
    std::string twoNodes = kScene;
    twoNodes.replace(twoNodes.find("{\"spec\":"), 9, "{\"extra\": {\"type\": \"bsdf.diffuse\"}, \"spec\":");
    try {
        sp::Scene::fromString(twoNodes, "", lo);
        ADD_FAILURE() << "a two-node material passed a one-node cap";
    } catch (const Error& e) {
        EXPECT_EQ(e.pointer(), "/materials/gold/nodes") << e.what();
    }
    lo = {};
    lo.maxJsonDepth = 2;
    EXPECT_NE(refusedAt(lo), "(loaded)");
    lo = {};
    lo.maxSpp = 2, lo.maxPixels = int64_t(1) << 40, lo.maxJsonDepth = 1000;  // above the built-in: the built-in holds
    EXPECT_EQ(refusedAt(lo), "(loaded)");
}

// setValue: any pointer; a literal goes through setLiteral, anything else re-loads the edited document with the
// original LoadOptions; failures name the pointer and leave the scene unchanged.
TEST(Api, SetValueEditsAnyPointerAndMatchesAFreshLoad) {
    sp::Scene s = sp::Scene::fromString(kScene);
    s.setValue("/render/spp", "3");
    s.setValue("/camera/fov", "30");
    s.setValue("/materials/gold/nodes/spec/inputs/roughness", "0.4");
    std::string edited = kScene;
    edited.replace(edited.find("\"spp\": 2"), 8, "\"spp\": 3");
    edited.replace(edited.find("\"fov\": 40"), 9, "\"fov\": 30");
    edited.replace(edited.find("\"roughness\": 0.1"), 16, "\"roughness\": 0.4");
    sp::RenderResult r = s.render();
    EXPECT_EQ(r.stats().samples, 80u * 40u * 3u);
    EXPECT_EQ(beauty(r), beauty(sp::Scene::fromString(edited).render()));
    s.setValue("/lights/-", R"({"type": "point", "position": [-1.5, -2, 3], "power": 100})");
    EXPECT_NE(s.json().find("-1.5"), std::string::npos);

    // LoadOptions stay in force across a re-load.
    sp::LoadOptions lo;
    lo.spp = 1;
    sp::Scene o = sp::Scene::fromString(kScene, "", lo);
    o.setValue("/render/width", "40");
    sp::RenderResult ro = o.render();
    EXPECT_EQ(ro.width(), 40);
    EXPECT_EQ(ro.stats().samples, 40u * 40u * 1u);

    std::vector<float> before = beauty(s.render());
    auto expectError = [&](const char* pointer, const char* value, const std::string& wantPointer, const char* suggestion) {
        try {
            s.setValue(pointer, value);
            ADD_FAILURE() << "expected an Error for " << pointer;
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::BadInput) << e.what();
            EXPECT_EQ(e.pointer(), wantPointer) << e.what();
            if (suggestion) EXPECT_EQ(e.suggestion(), suggestion) << e.what();
        }
    };
    expectError("/render/sppp", "4", "/render/sppp", "spp");                           // the loader's unknown key
    expectError("/render/spp", "0", "/render/spp", nullptr);                           // out of range
    expectError("/render/spp", "{nope", "/render/spp", nullptr);                       // not JSON
    expectError("/rendr/spp", "4", "/rendr", "render");                                // missing parent
    expectError("/materials/glod/nodes/spec/inputs/roughness", "0.2", "/materials/glod", "gold");
    expectError("/shapes/7/radius", "1", "/shapes/7/radius", nullptr);                 // array index out of range
    expectError("render/spp", "4", "render/spp", nullptr);                             // not a pointer
    EXPECT_EQ(beauty(s.render()), before);
}

TEST(Api, TilesCoverTheImageOnceWithFinalPixels) {
    sp::Scene s = sp::Scene::fromString(kScene);
    std::mutex m;
    std::vector<float> copy(80 * 40 * 3, -1.f);
    int calls = 0, total = 0;
    sp::RenderJob job = s.renderAsync({}, [&](const sp::Tile& t) {
        std::lock_guard<std::mutex> lock(m);  // the callback is serial already; the lock is for the reader below
        ++calls;
        total = t.tilesTotal;
        for (int y = t.y0; y < t.y1; ++y)
            for (int x = t.x0; x < t.x1; ++x)
                for (int k = 0; k < 3; ++k) copy[(size_t(y) * 80 + x) * 3 + k] = t.rgb(x, y)[k];
        return true;
    });
    sp::RenderResult r = job.wait();
    EXPECT_EQ(calls, total);
    EXPECT_EQ(r.stats().tilesDone, total);
    EXPECT_FALSE(r.stats().cancelled);
    EXPECT_EQ(copy, beauty(r));  // every pixel handed over once, already final
    EXPECT_EQ(r.aov("depth").channels(), 1);
    EXPECT_THROW(r.aov("nope"), Error);
}

TEST(Api, OutputPolicyAtomicPartialNeverClobbering) {
    std::string dir = specula::test::tempDir("api_out");
    specula::test::writeFile(dir + "/s.json", kScene);
    sp::Scene s = sp::Scene::fromFile(dir + "/s.json");
    sp::RenderResult full = s.render();
    sp::WrittenOutputs w = s.writeOutputs(full, dir + "/out.exr");
    EXPECT_FALSE(w.partial);
    EXPECT_TRUE(fs::exists(dir + "/out.exr"));
    EXPECT_TRUE(fs::exists(dir + "/out.png"));
    auto size = fs::file_size(dir + "/out.exr");

    sp::RenderOptions one;
    one.threads = 1;
    sp::RenderResult cut = s.render(one, [](const sp::Tile&) { return false; });
    EXPECT_TRUE(cut.stats().cancelled);
    sp::WrittenOutputs p = s.writeOutputs(cut, dir + "/out.exr");
    EXPECT_TRUE(p.partial);
    EXPECT_EQ(p.exr, sp::partialPathFor(dir + "/out.exr"));
    EXPECT_TRUE(fs::exists(dir + "/out.partial.exr"));
    EXPECT_EQ(fs::file_size(dir + "/out.exr"), size);  // the complete image is untouched
    for (auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos);

    auto code = [&](const std::string& path) {
        try {
            s.writeOutputs(full, path);
        } catch (const Error& e) {
            return e.code();
        }
        return ErrorCode::Ok;
    };
    EXPECT_EQ(code(dir + "/out.tif"), ErrorCode::Usage);
    // OUT.png: the viewed PNG alone (issue 17 item 5), no EXR beside it.
    EXPECT_EQ(code(dir + "/only.png"), ErrorCode::Ok);
    EXPECT_TRUE(fs::exists(dir + "/only.png"));
    EXPECT_FALSE(fs::exists(dir + "/only.exr"));
    EXPECT_EQ(code(dir + "/missing/out.exr"), ErrorCode::Io);
    EXPECT_THROW(specula::checkOutputPath(dir + "/s.exr", dir + "/s.exr"), Error);  // never the input itself
}

TEST(Api, GlslAndErrors) {
    sp::Scene s = sp::Scene::fromString(kScene);
    sp::GlslModule g = s.compileGlsl("gold");
    EXPECT_GT(g.source.size(), 100u);
    nlohmann::json manifest = nlohmann::json::parse(g.resourcesJson);
    EXPECT_EQ(manifest["format"], "specula-glsl-manifest");
    EXPECT_EQ(manifest["entry_points"]["eval"], "specula_eval");
    EXPECT_FALSE(manifest["uniform_block"]["members"].empty());  // the material's literals
    EXPECT_TRUE(manifest["resources"].is_array());
    EXPECT_THROW(s.compileGlsl(""), Error);  // two materials: name one
    try {
        sp::Scene::fromString(R"({"version": 1, "camera": {"position": [0,-4,1], "look_at": [0,0,0]}, "shapes": [{"type": "sphre"}]})");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::BadInput);
        EXPECT_EQ(e.exitCode(), 1);
        EXPECT_EQ(e.pointer(), "/shapes/0/type");
        EXPECT_EQ(e.suggestion(), "sphere");
    }
    try {
        sp::Scene::fromFile("/nonexistent/scene.json");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::Io);
    }
}

// Start-up (issue 9 item 8): the CLI answers --version and bsdf without loading OpenImageIO.
TEST(Api, VersionAndBsdfDoNotLoadImageIo) {
    // LD_DEBUG=libs lists every shared library the dynamic loader opens.
    auto loadedLibs = [](const std::string& args) {
        std::string cmd = std::string("LD_DEBUG=libs ") + SPECULA_CLI + " " + args + " 2>&1";
        std::string text;
        if (FILE* p = popen(cmd.c_str(), "r")) {
            char buf[4096];
            size_t n;
            while ((n = fread(buf, 1, sizeof buf, p)) > 0) text.append(buf, n);
            pclose(p);
        }
        return text;
    };
    std::string v = loadedLibs("--version");
    EXPECT_NE(v.find(std::string("specula ") + SPECULA_VERSION), std::string::npos);
    EXPECT_EQ(v.find("libOpenImageIO"), std::string::npos);
    EXPECT_EQ(v.find("libspecula_io"), std::string::npos);
    std::string demo = specula::test::sourcePath("examples/metals.json");
    std::string b = loadedLibs("bsdf " + demo + " --material gold_mirror --wo 0,0,1 --wi 0.3,0,1");
    EXPECT_NE(b.find("\"pdf\""), std::string::npos);
    EXPECT_EQ(b.find("libOpenImageIO"), std::string::npos);
    // ... and a render does load it (to write its images).
    std::string dir = specula::test::tempDir("api_startup");
    specula::test::writeFile(dir + "/s.json", kScene);
    std::string r = loadedLibs("render " + dir + "/s.json -o " + dir + "/s.exr --progress none");
    EXPECT_NE(r.find("libspecula_io"), std::string::npos);
    // In process: loading a scene without textures and compiling GLSL keeps the module unloaded here too,
    // unless an earlier test in this process wrote an image.
    if (!specula::io_module::loaded()) {
        sp::Scene s = sp::Scene::fromString(kScene);
        s.compileGlsl("gold");
        EXPECT_FALSE(specula::io_module::loaded());
    }
}

// A file the command read and that was then replaced by rename (an editor's save, `specula view`'s reload) frees its
// inode number, and ext4 hands that number to the very next file created in the folder: the command's own temporary
// output. That new file is not an input (the view test failed on it, exit 2); the live input still is, under any name.
TEST(InputFiles, ARecycledInodeIsNotAnInputButTheLiveInputIs) {
    using specula::InputFileScope;
    using specula::noteInputFile;
    using specula::refuseOverwritingInputs;
    const fs::path dir = specula::test::tempDir("input_files");
    auto write = [](const fs::path& p, const char* text) {
        std::FILE* f = std::fopen(p.c_str(), "wb");
        ASSERT_NE(f, nullptr) << p;
        std::fputs(text, f);
        std::fclose(f);
    };
    InputFileScope scope;
    const fs::path scene = dir / "scene.json", link = dir / "link.json";
    write(scene, "{}");
    noteInputFile(scene.string());
    fs::create_hard_link(scene, link);
    EXPECT_THROW(refuseOverwritingInputs(link.string(), {}, "output"), Error)
        << "a second name of the input is the input";

    // Replace the scene by rename (its first inode stays alive under link.json), then free that inode and create
    // files until one gets its number.
    struct stat first {};
    ASSERT_EQ(::stat(scene.c_str(), &first), 0);
    write(dir / "scene.json.tmp", "{\"version\": 1}");
    fs::rename(dir / "scene.json.tmp", scene);
    EXPECT_THROW(refuseOverwritingInputs(link.string(), {}, "output"), Error) << "renamed over, the read file lives on";
    fs::remove(link);
    bool reused = false;
    for (int i = 0; i < 64 && !reused; ++i) {
        const fs::path out = dir / ("out" + std::to_string(i) + ".exr");
        write(out, "x");
        struct stat st {};
        ASSERT_EQ(::stat(out.c_str(), &st), 0);
        if (st.st_ino == first.st_ino && st.st_dev == first.st_dev) {
            reused = true;
            EXPECT_NO_THROW(refuseOverwritingInputs(out.string(), {}, "output"))
                << "inode " << st.st_ino << " was recycled";
        }
    }
    if (!reused) GTEST_SKIP() << "this file system did not reuse the inode number within 64 files";
}
