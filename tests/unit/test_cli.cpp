// The `specula` CLI end to end: exit codes, outputs, JSON progress, compare/info, and that a failing
// or interrupted render never touches an existing output file.
#include "core/color/color_config.h"
#include "core/io/image_io.h"
#include "core/scene/gltf_scene.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <algorithm>
#include <cmath>
#include <limits>
#include <regex>
#include <csignal>
#include <filesystem>
#include <sys/wait.h>
#include <sstream>
#include <thread>
#include <unistd.h>

using namespace specula;
namespace fs = std::filesystem;
constexpr double kPiD = 3.14159265358979323846;

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
    // PSNR uses the reference's peak (b's largest specular value), not 1.0.
    EXPECT_GT(diff["psnr_peak"].get<double>(), 0.0);
    EXPECT_NE(diff["psnr_peak"].get<double>(), 1.0);
    EXPECT_NEAR(diff["psnr"].get<double>(), 20.0 * std::log10(diff["psnr_peak"].get<double>() / diff["rmse"].get<double>()), 1e-4);
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
    // Issue 17 item 5: titles, axes (ticks and names) and colour bars are labelled. White text pixels (the panels
    // are false colour, the background black) in each band of the 256-pixel layout: titles above the panels, the y
    // axes' labels left of each panel, the x axes' below, the colour bars' range and quantity under the bars.
    ImageSet plot = readImageSet(dir + "/lobe.png");
    ASSERT_EQ(plot.width, 40 + 256 + 48 + 256 + 14);
    ASSERT_EQ(plot.height, 24 + 256 + 34 + 6 + 14 + 20);
    const AovBuffer& px = plot.aovs.front();
    auto whiteIn = [&](int x0, int y0, int x1, int y1) {
        int n = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const float* p = &px.pixels[(size_t(y) * plot.width + x) * size_t(px.channels())];
                n += p[0] > 0.6f && p[1] > 0.6f && p[2] > 0.6f;
            }
        return n;
    };
    const int left = 40, right = 40 + 256 + 48, below = 24 + 256, bars = 24 + 256 + 34 + 6 + 14;
    for (int x0 : {left, right}) {
        EXPECT_GT(whiteIn(x0, 0, x0 + 256, 22), 60) << "title above the panel at x " << x0;
        EXPECT_GT(whiteIn(x0 - 40, 24, x0 - 2, below), 30) << "y axis labels left of the panel at x " << x0;
        EXPECT_GT(whiteIn(x0 - 8, below + 4, x0 + 264, below + 34), 60) << "x axis labels below the panel at x " << x0;
        EXPECT_GT(whiteIn(x0, bars, x0 + 256, bars + 20), 60) << "colour bar labels under the bar at x " << x0;
    }
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

// specula bsdf drives a whole shading point: the differentials a filtered lobe reads change its filtered roughness
// matrix, the light distance changes a half-vector filter, lobes add up to the total, and --batch answers every line.
TEST(Cli, BsdfDrivesTheShadingPointAndBatches) {
    std::string dir = test::tempDir("cli-bsdf");
    test::writeFile(dir + "/m.json", R"({"materials": {
        "f": {"nodes": {"spec": {"type": "bsdf.ggx_filtered", "inputs": {"alpha": [0.05, 0.05], "filter": "projected_approx"}},
                        "d": {"type": "bsdf.diffuse", "inputs": {"color": 0.25}},
                        "sum": {"type": "closure.add", "inputs": {"a": "@d.bsdf", "b": "@spec.bsdf"}}},
              "output": "@sum.bsdf"}}})");
    auto bsdf = [&](const std::string& extra) {
        std::string out;
        EXPECT_EQ(test::runCli("bsdf " + q(dir + "/m.json") + " --wo 0.3,0,0.95 --wi -0.25,0.05,0.96 " + extra, &out), 0) << out;
        return nlohmann::json::parse(out);
    };
    auto filteredA = [](const nlohmann::json& j) {
        for (const auto& l : j["lobes"])
            if (l["model"] == "ggx_filtered") return l["parameters"]["filtered_roughness_matrix"][0].get<double>();
        return -1.0;
    };
    nlohmann::json plain = bsdf(""), curved = bsdf("--dndx 0.05,0,0 --dndy 0,0.05,0");
    EXPECT_NEAR(filteredA(plain), 0.05 * 0.05, 1e-6);  // no derivatives: A itself
    EXPECT_GT(filteredA(curved), 1.2 * filteredA(plain));  // curvature widens the lobe (measured 1.32x for dn = 0.05)
    nlohmann::json moving = bsdf("--dpdx 0.02,0,0 --dpdy 0,0.02,0 --light-distance 0.5"), far = bsdf("--dpdx 0.02,0,0 --dpdy 0,0.02,0");
    EXPECT_GT(filteredA(moving), filteredA(far));  // a near point light turns dP into dwi
    // Per-lobe f·cos times weight adds up to the total; the lobe list names its models.
    ASSERT_EQ(curved["lobes"].size(), 2u);
    for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (const auto& l : curved["lobes"]) sum += l["weight"][c].get<double>() * l["f"][c].get<double>();
        EXPECT_NEAR(sum, curved["f"][c].get<double>(), 1e-6);
    }
    EXPECT_EQ(curved["lobes"][0]["model"], "lambert");
    // --batch: one answer per line, in order, from one process; a bad line answers an error and the exit code is 1.
    test::writeFile(dir + "/q.jsonl", R"({"wo": [0.3, 0, 0.95], "wi": [-0.25, 0.05, 0.96]}
{"wo": [0.3, 0, 0.95], "wi": [-0.25, 0.05, 0.96], "dndx": [0.05, 0, 0], "dndy": [0, 0.05, 0]}
{"wo": [0.3, 0, 0.95], "wii": [1, 0, 0]}
)");
    std::string out;
    EXPECT_EQ(test::runCli("bsdf " + q(dir + "/m.json") + " --batch < " + q(dir + "/q.jsonl"), &out), 1) << out;
    std::istringstream lines(out);
    std::vector<nlohmann::json> answers;
    for (std::string l; std::getline(lines, l);)
        if (!l.empty() && l[0] == '{') answers.push_back(nlohmann::json::parse(l));
    ASSERT_EQ(answers.size(), 3u) << out;
    EXPECT_DOUBLE_EQ(filteredA(answers[0]), filteredA(plain));
    EXPECT_DOUBLE_EQ(filteredA(answers[1]), filteredA(curved));
    EXPECT_NE(answers[2]["error"].get<std::string>().find("did you mean 'wi'"), std::string::npos) << answers[2].dump();
}

// Issue 35 class 7: a bad --batch line (a key twice, a NUL byte, bytes that are not UTF-8, a number beyond float) gets
// its own error answer, valid JSON, and the lines after it are still answered, in order.
TEST(Cli, BsdfBatchAnswersEveryLineAfterBadOnes) {
    const std::string dir = test::tempDir("cli-batch");
    test::writeFile(dir + "/m.json",
                    R"({"materials": {"m": {"nodes": {"s": {"type": "bsdf.diffuse", "inputs": {"color": [0.5, 0.5, 0.5]}}}, "output": "@s.bsdf"}}})");
    const std::string good = R"({"wo": [0, 0, 1], "wi": [0, 0, 1]})";
    std::string lines = good + "\n" + R"({"wo": [0, 0, 1], "wo": [1, 0, 1], "wi": [0, 0, 1]})" + "\n";
    lines += std::string("{\"wo\": [0, 0") + '\0' + ", 1], \"wi\": [0, 0, 1]}\n";
    lines += "{\"wo\": \"\xff\xfe\", \"wi\": [0, 0, 1]}\n";
    lines += R"({"wo": [0, 0, 1], "wi": [0, 0, 1], "light_distance": 1e300})" "\n" + good + "\n";
    test::writeFile(dir + "/q.jsonl", lines);
    std::string out;
    EXPECT_EQ(test::runCli("bsdf " + q(dir + "/m.json") + " --batch < " + q(dir + "/q.jsonl"), &out), 1) << out;
    std::istringstream in(out);
    std::vector<nlohmann::json> answers;
    for (std::string l; std::getline(in, l);)  // each answer is valid JSON; the closing error line is on stderr
        if (l.rfind("specula: error:", 0) != 0) answers.push_back(nlohmann::json::parse(l));
    ASSERT_EQ(answers.size(), 6u) << out;
    for (size_t i : {size_t(0), size_t(5)}) EXPECT_NEAR(answers[i]["f"][0].get<double>(), 0.5 / M_PI, 1e-6) << answers[i];
    const char* why[] = {"duplicate key 'wo'", "malformed JSON", "UTF-8", "/light_distance"};
    for (size_t i = 1; i <= 4; ++i) {
        ASSERT_TRUE(answers[i].contains("error")) << answers[i];
        EXPECT_EQ(answers[i]["line"].get<int>(), int(i + 1));
        EXPECT_NE(answers[i]["error"].get<std::string>().find(why[i - 1]), std::string::npos) << answers[i];
    }
}

// Issue 35 class 4: outputs are compared with the inputs by identity, not by name: a hard link or a symbolic link to
// the scene or to a texture it reads is refused (exit 2) before anything is rendered, and the input keeps its bytes.
TEST(Cli, NoOutputReplacesAnInputUnderAnotherName) {
    const std::string dir = test::tempDir("cli-identity");
    ASSERT_EQ(test::runCli("normalmap --kind bumps --size 16 --quiet -o " + q(dir + "/t.png")), 0);
    test::writeFile(dir + "/s.json", R"({"render": {"width": 16, "height": 12, "spp": 1}, "camera": {"position": [0, -4, 1], "look_at": [0, 0, 0]},
 "materials": {"m": {"nodes": {"t": {"type": "texture.image", "inputs": {"file": "t.png", "colorspace": "raw"}},
                               "s": {"type": "bsdf.diffuse", "inputs": {"color": "@t.color"}}}, "output": "@s.bsdf"}},
 "shapes": [{"type": "quad", "size": [8, 8], "material": "m"}], "lights": [{"type": "point", "position": [0, 0, 3], "power": 50}]})");
    const std::string texture = test::readFile(dir + "/t.png"), scene = test::readFile(dir + "/s.json");
    fs::create_hard_link(dir + "/t.png", dir + "/hard.png");
    fs::create_symlink("t.png", dir + "/soft.png");
    fs::create_hard_link(dir + "/s.json", dir + "/scene_link.exr");
    std::string out;
    for (const char* target : {"hard.png", "soft.png"}) {
        EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " --progress none -o " + q(dir + "/" + target), &out), 2) << out;
        EXPECT_NE(out.find("t.png"), std::string::npos) << out;
        EXPECT_NE(out.find("is the input file"), std::string::npos) << out;
    }
    EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " --progress none -o " + q(dir + "/scene_link.exr"), &out), 2) << out;
    EXPECT_EQ(test::runCli("plot " + q(dir + "/s.json") + " --wo 0,0,1 -o " + q(dir + "/hard.png"), &out), 2) << out;
    EXPECT_EQ(test::readFile(dir + "/t.png"), texture);
    EXPECT_EQ(test::readFile(dir + "/s.json"), scene);
    // A name that is only similar is no input: the render is written.
    EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " --progress none -o " + q(dir + "/t2.png"), &out), 0) << out;
}

// Issue 35 class 6: a write that fails for lack of space is an I/O error (exit 3, docs/cli.md) for every command that
// writes, and leaves no file, whole or partial, in the full folder. A 64 KiB tmpfs, filled up, stands for the full
// disk; mounting one needs root (CI runs as root), so elsewhere the test is skipped.
TEST(Cli, WriteFailuresOnAFullDiskExitThreeAndLeaveNothing) {
    const std::string dir = test::tempDir("cli-full"), full = dir + "/full";
    fs::create_directories(full);
    if (std::system(("mount -t tmpfs -o size=64k tmpfs " + q(full) + " 2>/dev/null").c_str()) != 0)
        GTEST_SKIP() << "cannot mount a tmpfs here (not root?)";
    struct Unmount {
        std::string path;
        ~Unmount() { (void)std::system(("umount " + path).c_str()); }
    } unmount{q(full)};
    fs::create_directories(full + "/res");
    test::writeFile(dir + "/m.json",
                    R"({"materials": {"m": {"nodes": {"s": {"type": "bsdf.diffuse", "inputs": {"color": [0.5, 0.5, 0.5]}}}, "output": "@s.bsdf"}}})");
    ASSERT_EQ(std::system(("dd if=/dev/zero of=" + q(full + "/fill") + " bs=1k count=64 2>/dev/null").c_str()), 0);
    ASSERT_EQ(test::runCli("render " + q(test::sourcePath("examples/metals.json")) + " --resolution 32x24 --spp 1 --crop 0,0,16,24 " +
                           "--progress none -o " + q(dir + "/a.exr")), 0);
    ASSERT_EQ(test::runCli("render " + q(test::sourcePath("examples/metals.json")) + " --resolution 32x24 --spp 1 --crop 16,0,32,24 " +
                           "--progress none -o " + q(dir + "/b.exr")), 0);
    const std::vector<std::string> commands = {
        "glsl " + q(dir + "/m.json") + " -o " + q(dir + "/m.glsl") + " --resources " + q(full + "/res"),
        "glsl " + q(dir + "/m.json") + " -o " + q(full + "/m.glsl"),
        "render " + q(test::sourcePath("examples/metals.json")) + " --resolution 32x24 --spp 1 --progress none -o " + q(full + "/o.exr"),
        "normalmap --kind bumps --size 64 -o " + q(full + "/n.exr"),
        "plot " + q(dir + "/m.json") + " --wo 0,0,1 -o " + q(full + "/p.png"),
        "merge " + q(dir + "/a.exr") + " " + q(dir + "/b.exr") + " -o " + q(full + "/frame.exr"),
    };
    for (const std::string& c : commands) {
        std::string out;
        EXPECT_EQ(test::runCli(c, &out), 3) << c << "\n" << out;
        EXPECT_NE(out.find("cannot write"), std::string::npos) << c << "\n" << out;
    }
    std::vector<std::string> left;
    for (const auto& e : fs::recursive_directory_iterator(full)) left.push_back(e.path().filename().string());
    std::sort(left.begin(), left.end());
    EXPECT_EQ(left, (std::vector<std::string>{"fill", "res"}));
    EXPECT_FALSE(fs::exists(dir + "/m.glsl"));  // the module is not written when its resources could not be
}

// specula plot --raw writes the lobe panel's float values: a pixel equals specula bsdf for its direction.
TEST(Cli, PlotRawValuesEqualBsdfQueries) {
    std::string dir = test::tempDir("cli-plot");
    const std::string demo = test::sourcePath("examples/metals.json");
    std::string out;
    ASSERT_EQ(test::runCli("plot " + q(demo) + " --material copper_satin --wo 0.4,0,0.9 --size 64 -o " + q(dir + "/p.png") +
                               " --raw " + q(dir + "/p.exr"),
                           &out),
              0)
        << out;
    ImageSet raw = readImageSet(dir + "/p.exr");
    ASSERT_EQ(raw.width, 64);
    const AovBuffer* beauty = raw.find("beauty");
    ASSERT_NE(beauty, nullptr);
    ASSERT_NE(raw.find("ndf"), nullptr);
    const int x = 40, y = 20;
    float u = (x + 0.5f) / 64 * 2 - 1, v = 1 - (y + 0.5f) / 64 * 2;
    char wi[96];
    std::snprintf(wi, sizeof wi, "%.9g,%.9g,%.9g", u, v, std::sqrt(1.f - u * u - v * v));
    ASSERT_EQ(test::runCli("bsdf " + q(demo) + " --material copper_satin --wo 0.4,0,0.9 --wi " + wi, &out), 0) << out;
    nlohmann::json j = nlohmann::json::parse(out);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(beauty->pixels[(size_t(y) * 64 + x) * 3 + c], j["f"][c].get<float>(), 1e-5f * std::max(1.f, j["f"][c].get<float>()));
}

// specula plot --footprint: a glint lobe at a pixel footprint shows sparkles (a few bright cells, the rest dark),
// without one the converged, analytic lobe (smooth); the lobe's max/mean over the projected hemisphere tells them apart.
TEST(Cli, PlotFootprintShowsGlintSparkles) {
    std::string dir = test::tempDir("cli-plot-glint");
    test::writeFile(dir + "/g.json", R"({"materials": {"glint": {"nodes": {"g": {"type": "bsdf.glint", "inputs": {"ggaa": "off"}}},
                                                       "output": "@g.bsdf"}}})");
    auto plot = [&](const std::string& extra) {
        std::string out;
        EXPECT_EQ(test::runCli("plot " + q(dir + "/g.json") + " --material glint --wo 0.3,0,0.95 --size 96 -o " +
                                   q(dir + "/p.png") + extra,
                               &out),
                  0)
            << out;
        nlohmann::json j = nlohmann::json::parse(out.substr(out.find('{')));
        return j["lobe_max"].get<double>() / std::max(j["lobe_mean"].get<double>(), 1e-30);
    };
    const double converged = plot(""), sparkles = plot(" --footprint 0.002");
    // The same footprint through --duvdx/--duvdy gives the same plot.
    const double explicitDuv = plot(" --duvdx 0.002,0 --duvdy 0,0.002");
    std::printf("PLOT glint max/mean: converged %.3g, footprint 0.002 %.3g\n", converged, sparkles);
    EXPECT_LT(converged, 15.0);
    EXPECT_GT(sparkles, 4.0 * converged);
    EXPECT_DOUBLE_EQ(sparkles, explicitDuv);
    // A non-positive footprint is a usage error.
    EXPECT_NE(test::runCli("plot " + q(dir + "/g.json") + " --material glint --wo 0,0,1 -o " + q(dir + "/x.png") + " --footprint -1"), 0);
}

// Issue 16's hostile inputs, each with its exit code, a message naming the pointer or file, and no output written.
TEST(Cli, HostileInputsGetOneClearErrorAndWriteNothing) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    std::string out;
    // --crop with trailing junk: usage error.
    EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " --crop 0,0,4,4,99 -o " + q(dir + "/c.exr"), &out), 2) << out;
    EXPECT_NE(out.find("--crop expects x0,y0,x1,y1"), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir + "/c.exr"));
    // A duplicate key: last-one-wins would silently drop a value.
    std::string dup = kSmallScene;
    dup.replace(dup.find("\"spp\": 2"), 8, "\"spp\": 2, \"spp\": 64");
    test::writeFile(dir + "/dup.json", dup);
    EXPECT_EQ(test::runCli("render " + q(dir + "/dup.json") + " -o " + q(dir + "/d.exr"), &out), 1) << out;
    EXPECT_NE(out.find("/render/spp"), std::string::npos) << out;
    EXPECT_NE(out.find("duplicate key 'spp'"), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir + "/d.exr"));
    // 100k nested arrays as a shape type (200 KB): refused while parsing, before any recursion can overflow.
    std::string deep = kSmallScene;
    deep.replace(deep.find("\"sphere\""), 8, std::string(100000, '[') + "\"sphere\"" + std::string(100000, ']'));
    test::writeFile(dir + "/deep.json", deep);
    EXPECT_EQ(test::runCli("info " + q(dir + "/deep.json"), &out), 1) << out;
    EXPECT_NE(out.find("nested deeper than 64 levels"), std::string::npos) << out;
    EXPECT_NE(out.find("deep.json"), std::string::npos) << out;
    // compare of an image holding NaN: undefined metrics are an error, never "PSNR inf" or the JSON token nan.
    ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/a.exr") + " --progress none"), 0);
    ImageSet img = readImageSet(dir + "/a.exr");
    img.aovs[0].pixels[7] = std::numeric_limits<float>::quiet_NaN();
    writeExr(dir + "/nan.exr", img, *ColorConfig::load());
    EXPECT_EQ(test::runCli("compare " + q(dir + "/nan.exr") + " " + q(dir + "/a.exr") + " --json", &out), 1) << out;
    EXPECT_NE(out.find("1 NaN or infinite values"), std::string::npos) << out;
    EXPECT_NE(out.find("nan.exr"), std::string::npos) << out;
    EXPECT_EQ(out.find("\"rmse\""), std::string::npos) << out;
    // A zero direction for bsdf: usage error, no value printed.
    test::writeFile(dir + "/m.json", R"({"materials": {"m": {"nodes": {"d": {"type": "bsdf.diffuse"}}, "output": "@d.bsdf"}}})");
    EXPECT_EQ(test::runCli("bsdf " + q(dir + "/m.json") + " --wo 0,0,0 --wi 0,0,1", &out), 2) << out;
    EXPECT_NE(out.find("non-zero direction"), std::string::npos) << out;
    EXPECT_EQ(out.find("\"f\""), std::string::npos) << out;
    // The documented maximum power 1e12 is accepted; a camera at the documented position limit 1e8 is valid
    // (docs/scene-format.md "Float-safe bounds"; beyond it, hostile_catalogue_cache.json).
    std::string big = kSmallScene;
    big.replace(big.find("\"power\": 300"), 12, "\"power\": 1e12");
    big.replace(big.find("[0, -4, 1]"), 10, "[0, -1e8, 1]");
    test::writeFile(dir + "/big.json", big);
    EXPECT_EQ(test::runCli("info " + q(dir + "/big.json"), &out), 0) << out;
    // A folder as the scene: I/O error (3), not malformed JSON; /dev/zero: refused after 256 MiB, not read forever.
    fs::create_directories(dir + "/folder.json");
    EXPECT_EQ(test::runCli("info " + q(dir + "/folder.json"), &out), 3) << out;
    EXPECT_NE(out.find("is a folder"), std::string::npos) << out;
    EXPECT_EQ(test::runCli("info /dev/zero", &out), 1) << out;
    EXPECT_NE(out.find("larger than 256 MiB"), std::string::npos) << out;
}

// Issue 16: a render whose PNG cannot be written leaves the old EXR as it was (both files are committed together),
// and no command writes over one of its own inputs.
TEST(Cli, NoCommandClobbersAnOutputPairOrItsOwnInput) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    std::string out;
    // pair.exr holds an earlier result; a folder stands where pair.png would go.
    test::writeFile(dir + "/pair.exr", "an earlier render");
    fs::create_directories(dir + "/pair.png");
    EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/pair.exr") + " --progress none", &out), 3) << out;
    EXPECT_NE(out.find("pair.png"), std::string::npos) << out;
    EXPECT_EQ(test::readFile(dir + "/pair.exr"), "an earlier render");
    for (auto& e : fs::directory_iterator(dir))
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
    // compare --diff over one of the compared images; plot and glsl -o over the material file.
    ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/a.exr") + " --progress none"), 0);
    const std::string a = test::readFile(dir + "/a.exr");
    EXPECT_EQ(test::runCli("compare " + q(dir + "/a.exr") + " " + q(dir + "/a.exr") + " --diff " + q(dir + "/a.exr"), &out), 2) << out;
    EXPECT_NE(out.find("--diff"), std::string::npos) << out;
    EXPECT_EQ(test::readFile(dir + "/a.exr"), a);
    const std::string scene = test::readFile(dir + "/s.json");
    EXPECT_EQ(test::runCli("plot " + q(dir + "/s.json") + " --material m --wo 0,0,1 -o " + q(dir + "/s.json"), &out), 2) << out;
    EXPECT_NE(out.find("is the input file"), std::string::npos) << out;
    EXPECT_EQ(test::runCli("plot " + q(dir + "/s.json") + " --material m --wo 0,0,1 -o " + q(dir + "/p.png") + " --raw " +
                               q(dir + "/./s.json"), &out), 2) << out;
    EXPECT_FALSE(fs::exists(dir + "/p.png"));
    EXPECT_EQ(test::runCli("glsl " + q(dir + "/s.json") + " --material m -o " + q(dir + "/s.json"), &out), 2) << out;
    EXPECT_EQ(test::readFile(dir + "/s.json"), scene);
}

// Issue 16: a render too large for the memory this process may use is refused before anything is allocated (8192x8192
// under a 4 GB address-space limit ended in an uncaught std::bad_alloc, exit 134): exit 1, /render named, no file.
TEST(Cli, RendersBeyondTheMemoryLimitAreRefusedBeforeAllocating) {
    std::string dir = test::tempDir("cli");
    test::writeFile(dir + "/s.json", kSmallScene);
    std::string out;
    const std::string big = "render " + q(dir + "/s.json") + " --resolution 8192x8192 --spp 1 -o " + q(dir + "/big.exr");
    EXPECT_EQ(test::runCli(big + " --max-memory 4G", &out), 1) << out;
    EXPECT_NE(out.find("/render: a 8192x8192 image"), std::string::npos) << out;
    EXPECT_NE(out.find("needs about 16.0 GiB"), std::string::npos) << out;
    EXPECT_NE(out.find("--max-memory of 4.0 GiB"), std::string::npos) << out;
    // The same under ulimit -v (the process's own limit, found without an option). ASan reserves terabytes of
    // address space for its shadow and cannot start under ulimit -v: that half is left to the normal build.
#ifndef SPECULA_SANITIZED
    FILE* pipe = popen(("ulimit -v 4000000; \"" SPECULA_CLI "\" " + big + " 2>&1").c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string limited;
    char buf[512];
    while (size_t n = fread(buf, 1, sizeof buf, pipe)) limited.append(buf, n);
    int status = pclose(pipe);
    ASSERT_TRUE(WIFEXITED(status)) << limited;
    EXPECT_EQ(WEXITSTATUS(status), 1) << limited;
    EXPECT_NE(limited.find("address-space limit (ulimit -v)"), std::string::npos) << limited;
#endif
    EXPECT_FALSE(fs::exists(dir + "/big.exr"));
    EXPECT_FALSE(fs::exists(dir + "/big.png"));
    // A malformed size is a usage error; a small render fits a small limit.
    EXPECT_EQ(test::runCli(big + " --max-memory 4x", &out), 2) << out;
    EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " --max-memory 512M --progress none -o " + q(dir + "/ok.exr"), &out), 0)
        << out;
}

// Issue 16: a texture's header is checked before its pixels are allocated (a 300 KB PNG claiming 100000x100000 made
// OpenImageIO try 120 GB): exit 1 naming the file's pointer; a texture that exists but does not decode is an I/O
// error (exit 3, as docs/cli.md says), a missing one bad input (exit 1).
TEST(Cli, TextureHeadersAreCheckedAndTextureFailuresGetTheDocumentedCodes) {
    std::string dir = test::tempDir("cli");
    auto sceneWith = [&](const std::string& file) {
        std::string s = kSmallScene;
        const std::string diffuse = R"("g": {"nodes": {"d": {"type": "bsdf.diffuse"}}, "output": "@d.bsdf"})";
        s.replace(s.find(diffuse), diffuse.size(),
                  R"("g": {"nodes": {"t": {"type": "texture.image", "inputs": {"file": ")" + file +
                      R"(", "colorspace": "sRGB - Texture"}}, "d": {"type": "bsdf.diffuse", "inputs": {"color": "@t.color"}}}, "output": "@d.bsdf"})");
        test::writeFile(dir + "/scene.json", s);
        return "render " + q(dir + "/scene.json") + " --progress none -o " + q(dir + "/out.exr");
    };
    std::string out;
    test::writeFile(dir + "/huge.ppm", "P6\n100000 100000\n255\n" + std::string(300000, '\x7f'));
    EXPECT_EQ(test::runCli(sceneWith("huge.ppm"), &out), 1) << out;
    EXPECT_NE(out.find("/materials/g/nodes/t/inputs/file"), std::string::npos) << out;
    EXPECT_NE(out.find("header claims 100000x100000 pixels"), std::string::npos) << out;
    test::writeFile(dir + "/broken.png", "\x89PNG\r\n\x1a\n this is not a PNG");
    EXPECT_EQ(test::runCli(sceneWith("broken.png"), &out), 3) << out;
    EXPECT_NE(out.find("broken.png"), std::string::npos) << out;
    EXPECT_EQ(test::runCli(sceneWith("missing.png"), &out), 1) << out;
    EXPECT_NE(out.find("missing.png"), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir + "/out.exr"));
}

// Issue 17 item 1: `info` lists each mesh file's attributes and where they came from, counts a quad light's geometry
// with the light (not as a shape), and the loader names the shape and node that read uvs a mesh does not have.
TEST(Cli, InfoListsMeshAttributesAndWarnsAboutMissingUvs) {
    std::string dir = test::tempDir("cli-mesh-info");
    test::writeFile(dir + "/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    test::writeFile(dir + "/tri_uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
    test::writeFile(dir + "/s.json", R"({
      "camera": {"position": [0, -4, 1], "look_at": [0, 0, 0]},
      "materials": {
        "glint": {"nodes": {"g": {"type": "bsdf.glint"}}, "output": "@g.bsdf"},
        "aniso": {"nodes": {"g": {"type": "bsdf.ggx", "inputs": {"anisotropy": 0.6}}}, "output": "@g.bsdf"},
        "plain": {"nodes": {"g": {"type": "bsdf.ggx"}}, "output": "@g.bsdf"}},
      "shapes": [
        {"type": "mesh", "file": "tri.obj", "name": "no_uv_glint", "material": "glint"},
        {"type": "mesh", "file": "tri.obj", "name": "no_uv_aniso", "material": "aniso"},
        {"type": "mesh", "file": "tri.obj", "name": "no_uv_plain", "material": "plain", "shading": "flat"},
        {"type": "mesh", "file": "tri_uv.obj", "name": "with_uv", "material": "glint"},
        {"type": "sphere", "material": "plain"}],
      "lights": [{"type": "quad", "position": [0, 0, 3], "look_at": [0, 0, 0], "power": 100}]})");
    std::string out;
    ASSERT_EQ(test::runCli("info " + q(dir + "/s.json"), &out), 0) << out;
    EXPECT_NE(out.find("shapes: 5 ("), std::string::npos) << out;
    EXPECT_NE(out.find("mesh tri.obj: 3 vertices; normals computed, uvs none, tangents none"), std::string::npos) << out;
    EXPECT_NE(out.find("mesh tri_uv.obj: 3 vertices; normals computed, uvs from the file, tangents computed"),
              std::string::npos) << out;
    EXPECT_NE(out.find("lights: 1\n  - quad (2 triangles of light geometry)"), std::string::npos) << out;
    EXPECT_NE(out.find("/shapes/0: mesh 'tri.obj' ('no_uv_glint') has no uvs, but node 'g' (bsdf.glint)"), std::string::npos) << out;
    EXPECT_NE(out.find("/shapes/1: mesh 'tri.obj' ('no_uv_aniso') has no uvs, but node 'g' (bsdf.ggx)"), std::string::npos) << out;
    EXPECT_NE(out.find("(port 'anisotropy')"), std::string::npos) << out;
    EXPECT_EQ(out.find("/shapes/2:"), std::string::npos) << "an isotropic GGX needs no uvs\n" << out;
    EXPECT_EQ(out.find("/shapes/3:"), std::string::npos) << "the mesh has uvs\n" << out;
    // Bad shading keys are input errors at their pointer.
    std::string scene = test::readFile(dir + "/s.json");
    test::writeFile(dir + "/bad.json", std::regex_replace(scene, std::regex("\"shading\": \"flat\""), "\"shading\": \"flatt\""));
    EXPECT_EQ(test::runCli("info " + q(dir + "/bad.json"), &out), 1) << out;
    EXPECT_NE(out.find("/shapes/2/shading"), std::string::npos) << out;
    EXPECT_NE(out.find("'flat'"), std::string::npos) << out;
    test::writeFile(dir + "/bad.json", std::regex_replace(scene, std::regex("\"shading\": \"flat\""), "\"smooth_angle\": 200"));
    EXPECT_EQ(test::runCli("info " + q(dir + "/bad.json"), &out), 1) << out;
    EXPECT_NE(out.find("/shapes/2/smooth_angle"), std::string::npos) << out;
}

// Issue 17 item 5: `render -o OUT.png` writes the viewed PNG alone; the EXR carries OpenEXR's worldToCamera and
// worldToNDC. The matrices are checked against the renderer itself: a small emitting sphere's image centroid must
// sit where worldToNDC puts its centre, in the full frame and in a crop window.
TEST(Cli, PngOnlyOutputAndExrCameraMatricesMatchTheImage) {
    std::string dir = test::tempDir("cli-camera-matrices");
    const Vec3 centre(0.9f, 0.3f, 1.35f);
    test::writeFile(dir + "/s.json", R"({
      "render": {"width": 96, "height": 64, "spp": 4},
      "camera": {"position": [0.3, -4, 1.2], "look_at": [0, 0, 1], "fov": 50},
      "materials": {"e": {"nodes": {"e": {"type": "bsdf.emission", "inputs": {"strength": 5}}}, "output": "@e.bsdf"}},
      "shapes": [{"type": "sphere", "radius": 0.06, "transform": {"translate": [0.9, 0.3, 1.35]}, "material": "e"}]})");
    std::string out;
    ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/only.png") + " --progress none", &out), 0) << out;
    EXPECT_TRUE(fs::exists(dir + "/only.png"));
    EXPECT_FALSE(fs::exists(dir + "/only.exr")) << "-o OUT.png writes no EXR";
    EXPECT_NE(out.find("wrote " + dir + "/only.png\n"), std::string::npos) << out;
    EXPECT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/x.jpg") + " --progress none", &out), 2) << out;

    for (const std::string crop : {"", " --crop 40,8,96,40"}) {
        ASSERT_EQ(test::runCli("render " + q(dir + "/s.json") + " -o " + q(dir + "/m.exr") + crop + " --progress none", &out), 0) << out;
        ImageSet img = readImageSet(dir + "/m.exr");
        ASSERT_EQ(img.matrices.count("worldToCamera"), 1u) << crop;
        ASSERT_EQ(img.matrices.count("worldToNDC"), 1u) << crop;
        // Camera space: the camera at the origin, looking down +z, the look-at point straight ahead.
        const Mat4 toCamera = img.matrices["worldToCamera"];
        EXPECT_LT(glm::length(Vec3(toCamera * Vec4(0.3f, -4.f, 1.2f, 1.f))), 1e-5f);
        const Vec3 ahead = Vec3(toCamera * Vec4(0.f, 0.f, 1.f, 1.f));
        EXPECT_NEAR(ahead.x, 0.f, 1e-5f);
        EXPECT_NEAR(ahead.y, 0.f, 1e-5f);
        EXPECT_GT(ahead.z, 0.f);
        const Vec4 h = img.matrices["worldToNDC"] * Vec4(centre, 1.f);
        const Vec2 ndc(h.x / h.w, h.y / h.w);
        // The centroid of the sphere's light, in pixels of the written image.
        const AovBuffer* beauty = img.find("beauty");
        ASSERT_NE(beauty, nullptr);
        double sx = 0, sy = 0, sw = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                const float v = beauty->pixels[(size_t(y) * img.width + x) * size_t(beauty->channels())];
                sx += v * (x + 0.5), sy += v * (y + 0.5), sw += v;
            }
        ASSERT_GT(sw, 0.0) << crop;
        EXPECT_NEAR(ndc.x * img.width, sx / sw, 0.25) << crop;
        EXPECT_NEAR(ndc.y * img.height, sy / sw, 0.25) << crop;
    }
    // The file holds them under OpenEXR's standard names.
    const std::string bytes = test::readFile(dir + "/m.exr");
    EXPECT_NE(bytes.find(std::string("worldToCamera\0m44f", 18)), std::string::npos);
    EXPECT_NE(bytes.find(std::string("worldToNDC\0m44f", 15)), std::string::npos);
}

// Issue 17 item 5: an RGBA image against an RGB one compares the common channels by name and says which were left
// out; the metrics are those of the common channels alone (RMSE of a 0.1 offset in one of three channels).
TEST(Cli, CompareMatchesChannelsByNameAndSaysWhatItLeftOut) {
    std::string dir = test::tempDir("cli-compare-rgba");
    auto color = ColorConfig::load("builtin");
    const int w = 8, h = 4;
    ImageSet rgba, rgb;
    rgba.width = rgb.width = w;
    rgba.height = rgb.height = h;
    rgba.aovs.push_back({"beauty", {"R", "G", "B", "A"}, std::vector<float>(size_t(w * h * 4))});
    rgb.aovs.push_back({"beauty", {"R", "G", "B"}, std::vector<float>(size_t(w * h * 3))});
    for (int i = 0; i < w * h; ++i) {
        for (int c = 0; c < 3; ++c) rgb.aovs[0].pixels[size_t(3 * i + c)] = 0.25f * float(c + 1);
        for (int c = 0; c < 3; ++c) rgba.aovs[0].pixels[size_t(4 * i + c)] = 0.25f * float(c + 1) + (c == 0 ? 0.1f : 0.f);
        rgba.aovs[0].pixels[size_t(4 * i + 3)] = 1.f;
    }
    writeExr(dir + "/rgba.exr", rgba, *color);
    writeExr(dir + "/rgb.exr", rgb, *color);
    std::string out;
    ASSERT_EQ(test::runCli("compare " + q(dir + "/rgba.exr") + " " + q(dir + "/rgb.exr") + " --json", &out), 0) << out;
    auto j = nlohmann::json::parse(out);
    EXPECT_EQ(j["channels"], nlohmann::json({"R", "G", "B"}));
    ASSERT_EQ(j["ignored_channels"].size(), 1u) << out;
    EXPECT_NE(j["ignored_channels"][0].get<std::string>().find("A (only in '" + dir + "/rgba.exr')"), std::string::npos) << out;
    EXPECT_NEAR(j["rmse"].get<double>(), std::sqrt(0.01 / 3.0), 1e-6);
    EXPECT_NEAR(j["mae"].get<double>(), 0.1 / 3.0, 1e-6);
    ASSERT_EQ(test::runCli("compare " + q(dir + "/rgba.exr") + " " + q(dir + "/rgb.exr"), &out), 0) << out;
    EXPECT_NE(out.find("channels R,G,B"), std::string::npos) << out;
    EXPECT_NE(out.find("note  channel A (only in"), std::string::npos) << out;
    // Nothing in common is an error that lists both sides' channels.
    ImageSet z = rgb;
    z.aovs[0].channelNames = {"X", "Y", "Z"};
    writeExr(dir + "/xyz.exr", z, *color);
    EXPECT_EQ(test::runCli("compare " + q(dir + "/xyz.exr") + " " + q(dir + "/rgb.exr"), &out), 3) << out;
    EXPECT_NE(out.find("no channel in common"), std::string::npos) << out;
}

// Issue 17 item 3: "visible": false hides a quad light from camera rays (its black back no longer shows) while it
// still lights the scene exactly as before.
TEST(Cli, InvisibleQuadLightsLightTheSceneButCameraRaysPassThrough) {
    std::string dir = test::tempDir("cli-invisible-light");
    const std::string scene = R"({
      "render": {"width": 64, "height": 48, "spp": 4},
      "camera": {"position": [0, -4, 3], "look_at": [0, 0, 1.2]},
      "materials": {"g": {"nodes": {"d": {"type": "bsdf.diffuse"}}, "output": "@d.bsdf"}},
      "shapes": [{"type": "quad", "size": [30, 30], "material": "g"}],
      "lights": [{"type": "quad", "position": [0, 0, 1.5], "look_at": [0, 0, 0], "size": [1, 1], "power": 20VISIBLE}]})";
    auto render = [&](const std::string& name, const std::string& visible) {
        std::string s = scene;
        s.replace(s.find("VISIBLE"), 7, visible);
        test::writeFile(dir + "/" + name + ".json", s);
        std::string out;
        EXPECT_EQ(test::runCli("render " + q(dir + "/" + name + ".json") + " -o " + q(dir + "/" + name + ".exr") + " --progress none", &out), 0) << out;
        return readImageSet(dir + "/" + name + ".exr");
    };
    ImageSet shown = render("shown", ""), hidden = render("hidden", ", \"visible\": false");
    // The light's centre in pixels (its top, the unlit back, faces the camera).
    const Vec4 h = shown.matrices["worldToNDC"] * Vec4(0.f, 0.f, 1.5f, 1.f);
    const int cx = int(h.x / h.w * 64), cy = int(h.y / h.w * 48);
    auto beauty = [](const ImageSet& img, int x, int y) {
        const AovBuffer* b = img.find("beauty");
        return b->pixels[(size_t(y) * img.width + x) * size_t(b->channels())];
    };
    EXPECT_EQ(beauty(shown, cx, cy), 0.f) << "the back of a one-sided light is black";
    EXPECT_GT(beauty(hidden, cx, cy), 0.001f) << "the lit floor behind the hidden light";
    // Away from the light's outline the two images are the same (the light lights the floor as before).
    int same = 0, compared = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) {
            if (std::abs(x - cx) < 14 && std::abs(y - cy) < 14) continue;
            ++compared;
            same += beauty(shown, x, y) == beauty(hidden, x, y);
        }
    EXPECT_EQ(same, compared);
    EXPECT_GT(beauty(hidden, 32, 44), 0.01f) << "the floor is lit";
}

// Issue 17 item 3: an emissive mesh is sampled as a light (next-event estimation with MIS). A diffuse floor (albedo
// 0.8) under an emitting sphere (radiance 10, radius 0.25, centre 1.5 above it): the radiance leaving the floor point
// below is rho L sin^2(alpha) = 0.8 * 10 * (0.25 / 1.5)^2 = 0.2222 (the sphere subtends a cap of half-angle alpha). The
// direct-lighting and path integrators with mesh lights, and the path integrator finding the sphere only by BSDF
// hits ("mesh_lights": false), all give it; the mesh light cuts the pixel noise several times.
TEST(Cli, EmissiveMeshesAreSampledAsLights) {
    std::string dir = test::tempDir("cli-mesh-lights");
    auto render = [&](const std::string& integrator, bool meshLights, int spp, double& stddev) {
        const std::string name = integrator + (meshLights ? "_nee" : "_hits");
        test::writeFile(dir + "/" + name + ".json", R"({
          "render": {"width": 8, "height": 8, "spp": )" + std::to_string(spp) + R"(, "integrator": ")" + integrator +
                                                        R"(", "mesh_lights": )" + (meshLights ? "true" : "false") + R"(},
          "camera": {"position": [0, -3, 3], "look_at": [0, 0, 0], "fov": 2},
          "materials": {"e": {"nodes": {"e": {"type": "bsdf.emission", "inputs": {"strength": 10}}}, "output": "@e.bsdf"},
                        "g": {"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": 0.8}}}, "output": "@d.bsdf"}},
          "shapes": [{"type": "quad", "size": [20, 20], "material": "g"},
                     {"type": "sphere", "radius": 0.25, "transform": {"translate": [0, 0, 1.5]}, "material": "e"}]})");
        std::string out;
        EXPECT_EQ(test::runCli("render " + q(dir + "/" + name + ".json") + " -o " + q(dir + "/" + name + ".exr") + " --progress none", &out), 0) << out;
        ImageSet img = readImageSet(dir + "/" + name + ".exr");
        const AovBuffer* b = img.find("beauty");
        double sum = 0, sum2 = 0;
        const int n = img.width * img.height;
        for (int i = 0; i < n; ++i) {
            const double v = b->pixels[size_t(i) * size_t(b->channels())];
            sum += v, sum2 += v * v;
        }
        stddev = std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
        return sum / n;
    };
    const double expected = 0.8 * 10 * (0.25 / 1.5) * (0.25 / 1.5);
    double sdDirect = 0, sdPath = 0, sdHits = 0, sdHitsSameSpp = 0;
    const double direct = render("direct", true, 512, sdDirect), path = render("path", true, 512, sdPath);
    const double hits = render("path", false, 2048, sdHits);
    render("path", false, 512, sdHitsSameSpp);
    std::printf("mesh light: direct %.4f (pixel sd %.4f), path %.4f (%.4f), BSDF hits only %.4f (%.4f at 512 spp); "
                "expected %.4f\n", direct, sdDirect, path, sdPath, hits, sdHitsSameSpp, expected);
    EXPECT_NEAR(direct, expected, 0.03 * expected);
    EXPECT_NEAR(path, expected, 0.03 * expected);
    EXPECT_NEAR(hits, expected, 0.06 * expected);
    EXPECT_LT(sdPath, 0.5 * sdHitsSameSpp) << "next-event estimation of the mesh light reduces the noise";
    // Without mesh lights the direct integrator never sees the sphere's light.
    double sd = 0;
    EXPECT_EQ(render("direct", false, 16, sd), 0.0);
}

// Issue 17 item 2: a glTF file is a scene. tests/unit/data/gltf/scene.gltf (hand-written: a textured floor with a
// normal map, a gold cube, a camera, point, spot and directional lights) becomes a z-up scene document: one mesh shape
// per material, metallic-roughness graphs, lights at 683 lm/W, the camera turned with the geometry. The test then
// makes its own variants: without a camera (a framing camera sees the cube) and as a .glb.
TEST(Cli, GltfFilesRenderAsScenes) {
    const std::string file = test::sourcePath("tests/unit/data/gltf/scene.gltf");
    const nlohmann::json doc = gltfSceneDocument(file);
    ASSERT_EQ(doc["shapes"].size(), 2u) << doc.dump(1);
    EXPECT_EQ(doc["shapes"][1]["gltf_material"], 1);
    EXPECT_EQ(doc["shapes"][1]["material"], "gold");
    EXPECT_EQ(doc["shapes"][1]["transform"]["rotate"], nlohmann::json({90, 0, 0}));
    // Gold: metallic 1 -> no diffuse, F0 = base colour; roughness 0.3 as GGX's perceptual roughness.
    const nlohmann::json& gold = doc["materials"]["gold"]["nodes"];
    EXPECT_EQ(gold["diffuse"]["inputs"]["color"], nlohmann::json({0.0, 0.0, 0.0}));
    EXPECT_NEAR(gold["specular"]["inputs"]["f0"][1].get<double>(), 0.78, 1e-6);
    EXPECT_NEAR(gold["specular"]["inputs"]["roughness"].get<double>(), 0.3, 1e-6);
    // The floor: its base colour texture as sRGB, the normal map raw at strength 0.5.
    const nlohmann::json& floor = doc["materials"]["floor"]["nodes"];
    EXPECT_EQ(floor["base_image"]["inputs"]["colorspace"], "srgb_texture");
    EXPECT_EQ(floor["normal_image"]["inputs"]["colorspace"], "raw");
    EXPECT_EQ(floor["normal_map"]["inputs"]["strength"], 0.5);
    EXPECT_TRUE(fs::exists(floor["base_image"]["inputs"]["file"].get<std::string>()));
    // Camera at glTF (0, 2.5, 6) -> (0, -6, 2.5); yfov 0.7 rad; aspect 1.5 -> 810x540.
    EXPECT_NEAR(doc["camera"]["position"][1].get<double>(), -6.0, 1e-5);
    EXPECT_NEAR(doc["camera"]["position"][2].get<double>(), 2.5, 1e-5);
    EXPECT_NEAR(doc["camera"]["fov"].get<double>(), 0.7 * 180 / kPiD, 1e-4);
    EXPECT_EQ(doc["render"]["width"], 810);
    // Lights: 2000 cd -> 2000/683 W/sr at glTF (2, 4, 2) -> (2, -2, 4); the sun points down glTF's -y -> -z; the spot's
    // 0.6 rad outer cone is a 68.75-degree cone with blend 1 - 0.3/0.6.
    std::map<std::string, nlohmann::json> lights;
    for (const auto& l : doc["lights"]) lights[l["name"].get<std::string>()] = l;
    EXPECT_NEAR(lights["lamp"]["intensity"].get<double>(), 2000.0 / 683.0, 1e-6);
    EXPECT_NEAR(lights["lamp"]["position"][1].get<double>(), -2.0, 1e-5);
    EXPECT_NEAR(lights["lamp"]["position"][2].get<double>(), 4.0, 1e-5);
    EXPECT_NEAR(lights["sun"]["irradiance"].get<double>(), 0.1, 1e-9);
    EXPECT_NEAR(lights["sun"]["direction"][2].get<double>(), -1.0, 1e-5);
    EXPECT_NEAR(lights["spot"]["cone_angle"].get<double>(), 2 * 0.6 * 180 / kPiD, 1e-4);
    EXPECT_NEAR(lights["spot"]["blend"].get<double>(), 0.5, 1e-6);
    EXPECT_EQ(lights["environment"]["type"], "environment");

    // Rendered through the CLI: the gold cube's centre (glTF (0, 1, 0) -> (0, 0, 1)) is gold, not grey.
    std::string dir = test::tempDir("cli-gltf"), out;
    auto goldAt = [&](const std::string& path, const std::string& name, float& ratio) {
        ASSERT_EQ(test::runCli("render " + q(path) + " -o " + q(dir + "/" + name + ".exr") + " --spp 4 --resolution 96x64 --progress none", &out), 0) << out;
        ImageSet img = readImageSet(dir + "/" + name + ".exr");
        const Vec4 h = img.matrices["worldToNDC"] * Vec4(0.f, 0.f, 1.f, 1.f);
        const int x = int(h.x / h.w * float(img.width)), y = int(h.y / h.w * float(img.height));
        ASSERT_TRUE(x >= 0 && y >= 0 && x < img.width && y < img.height) << name << ": the cube is outside the frame";
        const AovBuffer* b = img.find("beauty");
        const float* p = &b->pixels[(size_t(y) * img.width + x) * size_t(b->channels())];
        ratio = p[0] / std::max(p[2], 1e-6f);
    };
    float ratio = 0.f;
    goldAt(file, "scene", ratio);
    EXPECT_GT(ratio, 1.5f) << "red over blue at the gold cube";
    // Made by the test: no camera (the framing camera must see the cube), and a primitive without a material.
    nlohmann::json g = nlohmann::json::parse(test::readFile(file));
    for (auto& n : g["nodes"]) n.erase("camera");
    g["meshes"][0]["primitives"][0].erase("material");
    for (auto& img : g["images"]) img["uri"] = test::sourcePath("tests/unit/data/gltf/") + img["uri"].get<std::string>();
    test::writeFile(dir + "/nocamera.gltf", g.dump());
    // The images' absolute paths lie outside the glTF's folder: refused unless SPECULA_RESOURCE_PATH lists theirs.
    EXPECT_NE(test::runCli("info " + q(dir + "/nocamera.gltf"), &out), 0) << out;
    setenv("SPECULA_RESOURCE_PATH", test::sourcePath("tests/unit/data/gltf").c_str(), 1);
    ASSERT_EQ(test::runCli("info " + q(dir + "/nocamera.gltf"), &out), 0) << out;
    EXPECT_NE(out.find("material 'default'"), std::string::npos) << out;
    goldAt(dir + "/nocamera.gltf", "nocamera", ratio);
    EXPECT_GT(ratio, 1.5f) << "the framing camera sees the gold cube";
    // The same document as a binary glTF (a GLB of one JSON chunk; its buffer stays a data URI).
    std::string json = g.dump();
    while (json.size() % 4) json += ' ';
    auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
    test::writeFile(dir + "/nocamera.glb", "glTF" + u32(2) + u32(uint32_t(12 + 8 + json.size())) + u32(uint32_t(json.size())) +
                                               "JSON" + json);
    goldAt(dir + "/nocamera.glb", "glb", ratio);
    // KHR_materials_transmission + KHR_materials_ior: the gold material made a 90 % transmissive dielectric of IOR 1.45.
    nlohmann::json t = nlohmann::json::parse(test::readFile(file));
    for (auto& img : t["images"]) img["uri"] = test::sourcePath("tests/unit/data/gltf/") + img["uri"].get<std::string>();
    for (auto& mat : t["materials"])
        if (mat["name"] == "gold") {
            mat["pbrMetallicRoughness"]["metallicFactor"] = 0.0;
            mat["extensions"] = {{"KHR_materials_transmission", {{"transmissionFactor", 0.9}}},
                                 {"KHR_materials_ior", {{"ior", 1.45}}}};
        }
    test::writeFile(dir + "/glass.gltf", t.dump());
    const nlohmann::json glassDoc = gltfSceneDocument(dir + "/glass.gltf");
    const nlohmann::json& glass = glassDoc["materials"]["gold"];
    EXPECT_EQ(glass["output"], "@surface_with_transmission.bsdf");
    EXPECT_EQ(glass["nodes"]["glass"]["type"], "bsdf.dielectric");
    EXPECT_NEAR(glass["nodes"]["glass"]["inputs"]["ior"].get<double>(), 1.45, 1e-6);
    EXPECT_NEAR(glass["nodes"]["surface_with_transmission"]["inputs"]["t"].get<double>(), 0.9, 1e-6);
    ASSERT_EQ(test::runCli("render " + q(dir + "/glass.gltf") + " -o " + q(dir + "/glass.exr") +
                               " --spp 2 --resolution 48x32 --progress none", &out), 0) << out;
    unsetenv("SPECULA_RESOURCE_PATH");
    EXPECT_GT(ratio, 1.5f) << "the .glb renders as the .gltf";
    // Not a glTF: a clear I/O error naming the file.
    test::writeFile(dir + "/broken.gltf", "{\"asset\": ");
    EXPECT_EQ(test::runCli("info " + q(dir + "/broken.gltf"), &out), 3) << out;
    EXPECT_NE(out.find("broken.gltf"), std::string::npos) << out;
}
