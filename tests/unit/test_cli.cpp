// The `specula` CLI end to end: exit codes, outputs, JSON progress, compare/info, and that a failing
// or interrupted render never touches an existing output file.
#include "core/io/image_io.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

using namespace specula;
namespace fs = std::filesystem;

namespace {

std::string q(const std::string& s) { return "'" + s + "'"; }

const char* kSmallScene = R"({
  "render": {"width": 32, "height": 24, "spp": 2},
  "camera": {"position": [0, -4, 1], "look_at": [0, 0, 0.5]},
  "materials": {
    "m": {"nodes": {"s": {"type": "bsdf.ggx", "inputs": {"roughness": 0.3, "f0": [0.9, 0.8, 0.7]}}}, "output": "@s.bsdf"},
    "g": {"nodes": {"d": {"type": "bsdf.diffuse"}}, "output": "@d.bsdf"}},
  "shapes": [{"type": "sphere", "radius": 0.5, "transform": {"translate": [0, 0, 0.5]}, "material": "m"},
             {"type": "quad", "size": [8, 8], "material": "g"}],
  "lights": [{"type": "point", "position": [2, -2, 3], "power": 300}]})";

}  // namespace

TEST(Cli, RenderWritesExrWithAllAovsAndPng) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    std::string out;
    int rc = test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/img.exr") + " --progress none", &out);
    ASSERT_EQ(rc, 0) << out;
    ASSERT_TRUE(fs::exists(dir + "/img.exr"));
    ASSERT_TRUE(fs::exists(dir + "/img.png"));
    ImageSet set = readImageSet(dir + "/img.exr");
    EXPECT_EQ(set.width, 32);
    EXPECT_EQ(set.height, 24);
    for (const char* aov : {"beauty", "diffuse", "specular", "albedo", "normal", "uv", "depth"})
        EXPECT_NE(set.find(aov), nullptr) << aov;
    // No temporary files are left behind.
    int files = 0;
    for (auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
    EXPECT_EQ(files, 3);
}

TEST(Cli, ResolutionCropAndSppOverrides) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/a.exr") +
                           " --resolution 64x48 --crop 8,4,40,36 --spp 1 --seed 3 --progress none"), 0);
    ImageSet set = readImageSet(dir + "/a.exr");
    EXPECT_EQ(set.width, 32);
    EXPECT_EQ(set.height, 32);
}

TEST(Cli, JsonProgressHasOneLinePerTileAndASummary) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    std::string out;
    ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/a.exr") + " --progress json 2>/dev/null", &out), 0);
    std::istringstream in(out);
    std::string line;
    int tiles = 0, done = 0;
    while (std::getline(in, line)) {
        auto j = nlohmann::json::parse(line);
        if (j["event"] == "tile") {
            ++tiles;
            EXPECT_EQ(j["total"], 1);  // 32x24 fits one 32x32 tile
        }
        if (j["event"] == "done") {
            ++done;
            EXPECT_EQ(j["samples"], 32 * 24 * 2);
            EXPECT_EQ(j["invalid_samples"], 0);
        }
    }
    EXPECT_EQ(tiles, 1);
    EXPECT_EQ(done, 1);
}

TEST(Cli, ThreadCountDoesNotChangeTheImage) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/t1.exr") + " --threads 1 --progress none"), 0);
    ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/t2.exr") + " --threads 2 --progress none"), 0);
    CompareResult r = compareImages(dir + "/t1.exr", dir + "/t2.exr", "beauty");
    EXPECT_EQ(r.rmse, 0.0);
    EXPECT_EQ(compareImages(dir + "/t1.exr", dir + "/t2.exr", "specular").rmse, 0.0);
}

TEST(Cli, BadInputExitsOneAndLeavesExistingOutputUntouched) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/bad.json", R"({"camera": {"position": [0,-4,1], "look_at": [0,0,0]}, "shapes": [{"type": "sphere", "material": "nope"}]})");
    test::writeFile(dir + "/keep.exr", "precious");
    test::writeFile(dir + "/keep.png", "precious png");
    std::string out;
    int rc = test::runCli("render " + q(dir + "/bad.json") + " -o " + q(dir + "/keep.exr"), &out);
    EXPECT_EQ(rc, 1);
    EXPECT_NE(out.find("/shapes/0/material"), std::string::npos) << out;
    EXPECT_EQ(test::readFile(dir + "/keep.exr"), "precious");
    EXPECT_EQ(test::readFile(dir + "/keep.png"), "precious png");
}

TEST(Cli, ExitCodes) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    test::writeFile(dir + "/broken.json", "{\"camera\": ");
    std::string out;
    EXPECT_EQ(test::runCli("render " + q(dir + "/missing.json"), &out), 3) << out;
    EXPECT_EQ(test::runCli("render " + q(dir + "/broken.json"), &out), 1) << out;
    EXPECT_NE(out.find("malformed JSON"), std::string::npos) << out;
    EXPECT_EQ(test::runCli("render", &out), 2) << out;
    EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " --spp 0", &out), 2) << out;
    EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " --resolution 10by10", &out), 2) << out;
    EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/no/such/dir/x.exr"), &out), 3) << out;
    EXPECT_EQ(test::runCli("frobnicate", &out), 2) << out;
    EXPECT_EQ(test::runCli("info " + q(dir + "/s.json"), &out), 0) << out;
    EXPECT_NE(out.find("shapes: 2"), std::string::npos) << out;
    EXPECT_EQ(test::runCli("compare " + q(dir + "/nope1.exr") + " " + q(dir + "/nope2.exr"), &out), 3) << out;
}

TEST(Cli, CompareReportsRmseMaePsnrAndWritesDiffMap) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/a.exr") + " --progress none"), 0);
    ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/b.exr") + " --seed 5 --progress none"), 0);
    std::string out;
    ASSERT_EQ(test::runCli("compare " + q(dir + "/a.exr") + " " + q(dir + "/a.exr") + " --json", &out), 0) << out;
    auto same = nlohmann::json::parse(out);
    EXPECT_EQ(same["rmse"], 0.0);
    ASSERT_EQ(test::runCli("compare " + q(dir + "/a.exr") + " " + q(dir + "/b.exr") + " --aov specular --json --diff " +
                               q(dir + "/diff.png"), &out), 0) << out;
    auto diff = nlohmann::json::parse(out);
    EXPECT_GT(diff["rmse"].get<double>(), 0.0);
    EXPECT_GE(diff["rmse"].get<double>(), diff["mae"].get<double>());
    EXPECT_TRUE(fs::exists(dir + "/diff.png"));
}

TEST(Cli, InterruptWritesPartialFileAndNeverClobbersTarget) {
    std::string dir = test::tempDir("cli");
    // Slow enough to be interrupted: many samples per pixel, many small tiles.
    std::string slow = kSmallScene;
    slow.replace(slow.find("\"spp\": 2"), 8, "\"spp\": 100000");
    test::writeFile(dir + "/slow.json", slow);
    test::writeFile(dir + "/target.exr", "existing");
    int pipefd[2];
    ASSERT_EQ(pipe(pipefd), 0);
    pid_t pid = fork();
    if (pid == 0) {
        dup2(pipefd[1], STDOUT_FILENO);
        close(pipefd[0]);
        std::string scene = dir + "/slow.json", target = dir + "/target.exr";
        execl(SPECULA_CLI, SPECULA_CLI, "render", scene.c_str(), "-o", target.c_str(), "--progress", "json", "--threads", "2",
              (char*)nullptr);
        _exit(127);
    }
    close(pipefd[1]);
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    kill(pid, SIGINT);
    int status = 0;
    waitpid(pid, &status, 0);
    std::string out;
    char buf[4096];
    ssize_t n;
    while ((n = read(pipefd[0], buf, sizeof buf)) > 0) out.append(buf, size_t(n));
    close(pipefd[0]);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 130) << out;
    EXPECT_EQ(test::readFile(dir + "/target.exr"), "existing");
    EXPECT_FALSE(fs::exists(dir + "/target.png"));
    ASSERT_TRUE(fs::exists(dir + "/target.partial.exr"));
    EXPECT_NE(out.find("\"event\":\"cancelled\""), std::string::npos) << out;
    ImageSet partial = readImageSet(dir + "/target.partial.exr");
    EXPECT_EQ(partial.width, 32);
}

TEST(Cli, BsdfCommandMatchesTheLambertClosedForm) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    std::string out;
    // Material 'g' is bsdf.diffuse with the default albedo 0.8: f·cos = 0.8/π · cos θi, pdf = cos θi / π.
    ASSERT_EQ(test::runCli("bsdf " + q(dir + "/s.json") + " --material g --wo 0,0,1 --wi 0.6,0,0.8", &out), 0) << out;
    auto j = nlohmann::json::parse(out);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(j["f"][c].get<double>(), 0.8 / M_PI * 0.8, 1e-5);
    EXPECT_NEAR(j["pdf"].get<double>(), 0.8 / M_PI, 1e-5);
    // Below the horizon nothing is reflected.
    ASSERT_EQ(test::runCli("bsdf " + q(dir + "/s.json") + " --material g --wo 0,0,1 --wi 0.6,0,-0.8", &out), 0) << out;
    EXPECT_EQ(nlohmann::json::parse(out)["pdf"].get<double>(), 0.0);
}

TEST(Cli, GlslAndPlotCommandsWriteTheirOutputs) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    std::string out;
    ASSERT_EQ(test::runCli("glsl " + q(dir + "/s.json") + " --material m -o " + q(dir + "/m.glsl"), &out), 0) << out;
    std::string glsl = test::readFile(dir + "/m.glsl");
    EXPECT_NE(glsl.find("#version 450"), std::string::npos);
    EXPECT_NE(glsl.find("vec3 specula_eval(SpeculaShadingInputs s, vec3 wo, vec3 wi)"), std::string::npos);
    EXPECT_NE(glsl.find("bsdf.ggx"), std::string::npos);  // comments name the node ids
    // An unknown material is bad input with a suggestion, and writes nothing.
    EXPECT_EQ(test::runCli("glsl " + q(dir + "/s.json") + " --material mm -o " + q(dir + "/x.glsl"), &out), 1) << out;
    EXPECT_FALSE(fs::exists(dir + "/x.glsl"));
    ASSERT_EQ(test::runCli("plot " + q(dir + "/s.json") + " --material m --wo 0.3,0,0.95 -o " + q(dir + "/lobe.png"), &out), 0) << out;
    EXPECT_TRUE(fs::exists(dir + "/lobe.png"));
}

TEST(Cli, GlslResourcesWritesAManifestAndEveryLevel) {
    std::string dir = test::tempDir("cli-res");
    fs::create_directories(dir + "/res");
    std::string out;
    const std::string tubes = test::sourcePath("examples/glint/tubes.json");
    ASSERT_EQ(test::runCli("glsl " + q(tubes) + " -o " + q(dir + "/t.glsl") + " --prefix tubes --binding-base 3 --set 1 --resources " +
                               q(dir + "/res"),
                           &out),
              0)
        << out;
    nlohmann::json m = nlohmann::json::parse(test::readFile(dir + "/res/manifest.json"));
    EXPECT_EQ(m["uniform_block"]["binding"], 3);
    EXPECT_EQ(m["uniform_block"]["set"], 1);
    ASSERT_EQ(m["resources"].size(), 1u);  // the glint dictionary
    const auto& r = m["resources"][0];
    EXPECT_EQ(r["binding"], 4);
    EXPECT_EQ(r["glsl_type"], "sampler1DArray");
    EXPECT_EQ(r["kind"], "builtin_table");
    ASSERT_EQ(r["levels"].size(), 7u);
    EXPECT_EQ(r["levels"][0]["width"], 64);
    EXPECT_EQ(r["levels"][0]["height"], 1024);
    for (const auto& lv : r["levels"]) EXPECT_TRUE(fs::exists(dir + "/res/" + lv["exr"].get<std::string>())) << lv.dump();
    std::string glsl = test::readFile(dir + "/t.glsl");
    EXPECT_NE(glsl.find("layout(set = 1, binding = 4) uniform sampler1DArray " + r["name"].get<std::string>()), std::string::npos);
    EXPECT_NE(glsl.find("vec3 specula_tubes_eval(SpeculaShadingInputs s, vec3 wo, vec3 wi)"), std::string::npos);
    // A missing resource folder is an I/O error (exit 3) and writes no module.
    EXPECT_EQ(test::runCli("glsl " + q(tubes) + " -o " + q(dir + "/u.glsl") + " --resources " + q(dir + "/nope"), &out), 3) << out;
    EXPECT_FALSE(fs::exists(dir + "/u.glsl"));
    // The module never replaces its input.
    std::string copy = dir + "/copy.json";
    fs::copy_file(tubes, copy);
    EXPECT_EQ(test::runCli("glsl " + q(copy) + " -o " + q(copy), &out), 2) << out;
    EXPECT_EQ(test::readFile(copy), test::readFile(tubes));
}
