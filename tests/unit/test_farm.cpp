// Farm pieces and scene animation (issue 18): keyframe evaluation and its errors, sample splits and crop tiles merged
// bit for bit into the single-process render, and the merge's refusals (core/farm/farm.h, core/scene/animation.h).
#include "core/farm/farm.h"
#include "core/io/image_io.h"
#include "core/render/renderer.h"
#include "core/scene/animation.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "core/color/color_config.h"
#include "core/util/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace specula;
namespace fs = std::filesystem;

namespace {

const char* kScene = R"({
  "render": {"width": 40, "height": 30, "spp": 12, "seed": 5, "max_depth": 4},
  "camera": {"position": [0, -6, 2.5], "look_at": [0, 0, 1], "fov": 40},
  "materials": {
    "metal": {"nodes": {"s": {"type": "bsdf.ggx", "inputs": {"roughness": 0.2, "f0": [0.9, 0.6, 0.5], "fresnel": "schlick"}}},
              "output": "@s.bsdf"},
    "grey": {"nodes": {"s": {"type": "bsdf.diffuse", "inputs": {"color": 0.5}}}, "output": "@s.bsdf"}
  },
  "shapes": [{"type": "sphere", "radius": 1, "transform": {"translate": [0, 0, 1]}, "material": "metal"},
             {"type": "quad", "size": [20, 20], "material": "grey"}],
  "lights": [{"type": "point", "position": [4, -4, 6], "power": 1500}],
  "animation": {"frame_start": 1, "frame_end": 5, "tracks": [
    {"target": "/camera/position", "keys": [{"frame": 1, "value": [0, -6, 2.5]}, {"frame": 5, "value": [4, -6, 2.5]}]},
    {"target": "/materials/metal/nodes/s/inputs/roughness", "interpolation": "smooth",
     "keys": [{"frame": 1, "value": 0.2}, {"frame": 3, "value": 0.4}]},
    {"target": "/lights/0/power", "interpolation": "constant", "keys": [{"frame": 1, "value": 1500}, {"frame": 4, "value": 100}]}
  ]}
})";

Json animatedAt(const std::string& text, std::optional<int> frame) {
    Json j = Json::parse(text);
    applyAnimation(j, frame);
    return j;
}

struct TempDir {
    fs::path path;
    TempDir() {
        path = fs::temp_directory_path() / ("specula_farm_" + std::to_string(::getpid()));
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
    std::string file(const std::string& name) const { return (path / name).string(); }
};

void expectBitIdentical(const ImageSet& a, const ImageSet& b) {
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    for (const AovBuffer& x : a.aovs) {
        if (x.name == "samples") continue;
        const AovBuffer* y = b.find(x.name);
        ASSERT_NE(y, nullptr) << x.name;
        ASSERT_EQ(x.pixels.size(), y->pixels.size()) << x.name;
        EXPECT_EQ(std::memcmp(x.pixels.data(), y->pixels.data(), x.pixels.size() * sizeof(float)), 0) << x.name;
    }
}

ImageSet renderWith(const SceneOverrides& ov) {
    Scene s = loadSceneFromString(kScene, ".", ov);
    return renderScene(s).images;
}

}  // namespace

// Linear, smooth (smoothstep) and constant keys; hold before the first and after the last key.
TEST(Animation, TracksInterpolateAndHold) {
    Json f1 = animatedAt(kScene, 1), f2 = animatedAt(kScene, 2), f3 = animatedAt(kScene, 3), f5 = animatedAt(kScene, 5);
    EXPECT_DOUBLE_EQ(f2["camera"]["position"][0].get<double>(), 1.0);  // linear: 1/4 of 4
    EXPECT_DOUBLE_EQ(f5["camera"]["position"][0].get<double>(), 4.0);
    EXPECT_DOUBLE_EQ(f1["materials"]["metal"]["nodes"]["s"]["inputs"]["roughness"].get<double>(), 0.2);
    EXPECT_NEAR(f2["materials"]["metal"]["nodes"]["s"]["inputs"]["roughness"].get<double>(), 0.2 + 0.2 * 0.5, 1e-12);  // t = 1/2
    EXPECT_DOUBLE_EQ(f5["materials"]["metal"]["nodes"]["s"]["inputs"]["roughness"].get<double>(), 0.4);  // held
    EXPECT_DOUBLE_EQ(f3["lights"][0]["power"].get<double>(), 1500.0);  // constant until the next key
    EXPECT_DOUBLE_EQ(f5["lights"][0]["power"].get<double>(), 100.0);
    EXPECT_FALSE(f1.contains("animation"));
    // The default frame is frame_start, and the scene records it.
    Scene s = loadSceneFromString(kScene, ".");
    EXPECT_EQ(s.render.frame, 1);
    SceneOverrides ov;
    ov.frame = 4;
    EXPECT_EQ(loadSceneFromString(kScene, ".", ov).render.frame, 4);
}

TEST(Animation, BadTracksNameTheirPointer) {
    auto errorOf = [](const std::string& text, std::optional<int> frame = std::nullopt) -> std::string {
        try {
            Json j = Json::parse(text);
            applyAnimation(j, frame);
        } catch (const InputError& e) {
            return e.what();
        }
        return "";
    };
    const std::string base = R"({"camera": {"position": [0, 0, 1], "fov": 40}, "animation": {"frame_start": 1, "frame_end": 3, "tracks": [)";
    EXPECT_NE(errorOf(base + R"({"target": "/camera/postion", "keys": [{"frame": 1, "value": [0,0,0]}]}]}})")
                  .find("/animation/tracks/0/target: target '/camera/postion' is not in the scene"),
              std::string::npos);
    EXPECT_NE(errorOf(base + R"({"target": "/camera/postion", "keys": [{"frame": 1, "value": [0,0,0]}]}]}})").find("did you mean 'position'"),
              std::string::npos);
    EXPECT_NE(errorOf(base + R"({"target": "/camera/position", "keys": [{"frame": 1, "value": 3}]}]}})")
                  .find("/animation/tracks/0/keys/0/value: the target holds an array of 3 numbers, this key is a number"),
              std::string::npos);
    EXPECT_NE(errorOf(base + R"({"target": "/camera/fov", "keys": [{"frame": 2, "value": 3}, {"frame": 2, "value": 4}]}]}})")
                  .find("/animation/tracks/0/keys/1/frame: key frames must increase"),
              std::string::npos);
    EXPECT_NE(errorOf(base + R"({"target": "/camera/fov", "keys": [{"frame": 2, "value": 3}]}]}})", 7).find("frame 7 is outside the animation's frames 1-3"),
              std::string::npos);
    EXPECT_NE(errorOf(base + R"({"target": "/camera/fov", "interpolation": "cubic", "keys": [{"frame": 2, "value": 3}]}]}})").find("interpolation"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"camera": {}})", 5).find("without an \"animation\" block"), std::string::npos);
}

// Sample splits (each one block of the film) and crop tiles merge bit for bit into the single-process render with the
// same sample block; the block size changes only the last bits of the plain render.
TEST(FarmMerge, SplitsAndTilesMergeBitForBit) {
    TempDir tmp;
    SceneOverrides whole;
    whole.frame = 2;
    whole.sampleBlock = 4;  // 12 spp in 3 blocks
    ImageSet reference = renderWith(whole);
    std::vector<std::string> pieces;
    const CropWindow tiles[] = {{0, 0, 17, 13}, {17, 0, 40, 13}, {0, 13, 40, 30}};
    for (const CropWindow& c : tiles)
        for (int k = 0; k < 3; ++k) {
            SceneOverrides ov;
            ov.frame = 2;
            ov.crop = c;
            ov.sampleSplitIndex = k;
            ov.sampleSplitCount = 3;
            Scene s = loadSceneFromString(kScene, ".", ov);
            const std::string path = tmp.file("piece_" + std::to_string(c.x0) + "_" + std::to_string(c.y0) + "_" + std::to_string(k) + ".exr");
            writeExr(path, renderScene(s).images, *s.colorConfig);
            pieces.push_back(path);
        }
    // Any order of the pieces on the command line.
    std::reverse(pieces.begin(), pieces.end());
    farm::MergeSummary m = farm::mergePieces(pieces, tmp.file("merged.exr"));
    EXPECT_EQ(m.tiles, 3);
    EXPECT_EQ(m.sampleSplits, 3);
    EXPECT_EQ(m.frame, 2);
    expectBitIdentical(readImageSet(tmp.file("merged.exr")), reference);
    // Whole-tile pieces (no split) of the default render.
    SceneOverrides plain;
    plain.frame = 2;
    ImageSet plainRef = renderWith(plain);
    std::vector<std::string> tilePieces;
    for (const CropWindow& c : tiles) {
        SceneOverrides ov = plain;
        ov.crop = c;
        Scene s = loadSceneFromString(kScene, ".", ov);
        tilePieces.push_back(tmp.file("tile_" + std::to_string(c.x0) + "_" + std::to_string(c.y0) + ".exr"));
        writeExr(tilePieces.back(), renderScene(s).images, *s.colorConfig);
    }
    farm::mergePieces(tilePieces, tmp.file("merged_tiles.exr"));
    expectBitIdentical(readImageSet(tmp.file("merged_tiles.exr")), plainRef);
    // The block size is a real setting: blocks of 4 differ from one block of 12 in the last bits, not more.
    const AovBuffer* a = reference.find("beauty");
    const AovBuffer* b = plainRef.find("beauty");
    double worst = 0;
    for (size_t i = 0; i < a->pixels.size(); ++i)
        worst = std::max(worst, double(std::abs(a->pixels[i] - b->pixels[i])) / std::max(1e-3, double(std::abs(b->pixels[i]))));
    EXPECT_LT(worst, 1e-5);

    // Refusals: an incomplete split set, a piece of another frame, an overlap, an existing output.
    auto errorOf = [&](const std::vector<std::string>& list, const std::string& out) -> std::string {
        try {
            farm::mergePieces(list, out);
        } catch (const Error& e) {
            return e.what();
        }
        return "";
    };
    std::vector<std::string> incomplete(pieces.begin() + 1, pieces.end());
    EXPECT_NE(errorOf(incomplete, tmp.file("x.exr")).find("lacks sample splits"), std::string::npos);
    EXPECT_FALSE(fs::exists(tmp.file("x.exr")));
    SceneOverrides other = whole;
    other.frame = 3;
    other.crop = tiles[0];
    Scene s3 = loadSceneFromString(kScene, ".", other);
    writeExr(tmp.file("frame3.exr"), renderScene(s3).images, *s3.colorConfig);
    std::vector<std::string> mixed = tilePieces;
    mixed[0] = tmp.file("frame3.exr");
    EXPECT_NE(errorOf(mixed, tmp.file("x.exr")).find("belongs to another render"), std::string::npos);
    std::vector<std::string> twice = tilePieces;
    twice.push_back(tilePieces[0]);
    EXPECT_NE(errorOf(twice, tmp.file("x.exr")).find("is given more than once"), std::string::npos);
    SceneOverrides across = plain;
    across.crop = CropWindow{10, 0, 20, 13};
    Scene sAcross = loadSceneFromString(kScene, ".", across);
    writeExr(tmp.file("across.exr"), renderScene(sAcross).images, *sAcross.colorConfig);
    std::vector<std::string> overlap = tilePieces;
    overlap.push_back(tmp.file("across.exr"));
    EXPECT_NE(errorOf(overlap, tmp.file("x.exr")).find("overlaps another tile"), std::string::npos);
    std::vector<std::string> gap(tilePieces.begin(), tilePieces.end() - 1);
    EXPECT_NE(errorOf(gap, tmp.file("x.exr")).find("no piece covers pixel"), std::string::npos);
    EXPECT_NE(errorOf(tilePieces, tmp.file("merged_tiles.exr")).find("never overwrites a finished frame"), std::string::npos);
    EXPECT_FALSE(fs::exists(tmp.file("x.exr")));
}

// ---- issue 35: the farm's scripts, plans and merge under hostile input --------------------------------------------

namespace {

const char* kStillScene = R"({"render": {"width": 8, "height": 6, "spp": 4, "seed": 1},
  "camera": {"position": [0, -4, 1], "look_at": [0, 0, 0.5]},
  "materials": {"g": {"nodes": {"d": {"type": "bsdf.diffuse"}}, "output": "@d.bsdf"}},
  "shapes": [{"type": "sphere", "radius": 0.5, "material": "g"}],
  "lights": [{"type": "point", "position": [2, -2, 3], "power": 300}]})";

std::vector<std::string> linesOf(const std::string& text) {
    std::vector<std::string> lines;
    std::stringstream ss(text);
    for (std::string l; std::getline(ss, l);) lines.push_back(l);
    return lines;
}

// Runs a shell command line; returns its exit status and (optionally) its standard output.
int shell(const std::string& cmd, std::string* out = nullptr) {
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return -1;
    std::string text;
    char buf[4096];
    for (size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) text.append(buf, n);
    const int st = pclose(p);
    if (out) *out = text;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string shQuote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// The words bash makes of the exec line of 'script' (run in 'cwd' with SLURM_ARRAY_TASK_ID=7), NUL-separated so that
// any word survives: `exec` replaced by printf, so nothing runs but printf.
std::vector<std::string> execWords(const std::string& scriptPath, const std::string& cwd) {
    std::string line;
    for (const std::string& l : linesOf(test::readFile(scriptPath)))
        if (l.rfind("exec ", 0) == 0) line = l;
    const std::string probe = cwd + "/probe.sh";
    test::writeFile(probe, "printf '%s\\0' " + line.substr(5) + "\n");
    std::string out;
    EXPECT_EQ(shell("cd " + shQuote(cwd) + " && SLURM_ARRAY_TASK_ID=7 bash " + shQuote(probe), &out), 0);
    std::vector<std::string> words;
    size_t start = 0;
    for (size_t i = 0; i < out.size(); ++i)
        if (out[i] == '\0') words.push_back(out.substr(start, i - start)), start = i + 1;
    return words;
}

// An #SBATCH line as sbatch reads it: one word (sbatch splits these lines at blanks, honours quotes and backslashes,
// and stops at '#'), so a value must hold none of those to be read as written.
bool oneSbatchWord(const std::string& line, std::string& key, std::string& value) {
    const std::string prefix = "#SBATCH --";
    if (line.rfind(prefix, 0) != 0) return false;
    const std::string word = line.substr(prefix.size());
    if (word.find_first_of(" \t\"'\\#") != std::string::npos) return false;
    const size_t eq = word.find('=');
    key = word.substr(0, eq);
    value = eq == std::string::npos ? "" : word.substr(eq + 1);
    return true;
}

std::string errorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return std::string(e.code() == ErrorCode::Io ? "[io] " : "[input] ") + e.what();
    }
    return "";
}

}  // namespace

// Scene names, farm folders and executable paths full of shell syntax give scripts whose every line is the intended
// one: bash -n passes, each #SBATCH line is one sbatch word with an expected key, and the exec line's words are exactly
// the intended argv (nothing ran: no file 'PWNED' appears). Values with control characters are refused.
TEST(FarmScripts, HostileNamesGiveExactlyTheIntendedLines) {
    const std::string tmp = test::tempDir("farm_scripts");
    const std::vector<std::string> hostile = {"a$(touch PWNED)b", "q`touch PWNED`q", "it's \"x\"; touch PWNED; #",
                                              "sp ace  two", "\xc3\xbcn\xc3\xaf \xe2\x98\x83", "semi;amp&pipe|lt<gt>",
                                              "#hash", "back\\slash\\", "percent%j%A%%", "star*?[x]{a,b}~", "$HOME ${PATH}",
                                              "-rf --partition=evil"};
    int n = 0;
    for (const std::string& v : hostile) {
        SCOPED_TRACE(v);
        const std::string base = tmp + "/case" + std::to_string(n++);
        fs::create_directories(base + "/scenes");
        const std::string scene = base + "/scenes/" + v + ".json";
        test::writeFile(scene, kStillScene);
        farm::SubmitOptions o;
        o.scene = scene;
        o.farmDir = base + "/farm " + v;
        o.executable = base + "/bin " + v + "/specula";
        o.partition = "gpu,long-queue_1.x";
        o.account = "proj.render-1";
        o.threadsPerTask = 3;
        o.tilesX = 2;
        o.sppSplit = 2;
        o.extraRenderArgs = {v, "--seed", "$(touch PWNED)"};
        o.dryRun = true;
        if (v.find_first_of("%\\") != std::string::npos) {
            // Slurm reads '%' and '\\' in a log path as patterns, the working folder included: refused for the folder.
            const std::string e = errorOf([&] { farm::submit(o); });
            EXPECT_EQ(e.rfind("[input] --dir: the farm folder ", 0), 0u) << e;
            EXPECT_NE(e.find("which Slurm reads as file-name patterns"), std::string::npos) << e;
            EXPECT_FALSE(fs::exists(o.farmDir));
            o.farmDir = base + "/farm";
        }
        const farm::SubmitResult r = farm::submit(o);
        EXPECT_EQ(r.tasks, 4);
        const std::string dir = fs::path(o.farmDir).lexically_normal().string();
        for (const std::string script : {"render.sbatch", "finish.sbatch"}) {
            const std::string path = dir + "/" + script;
            EXPECT_EQ(shell("bash -n " + shQuote(path) + " 2>&1"), 0) << test::readFile(path);
            const std::vector<std::string> lines = linesOf(test::readFile(path));
            const bool render = script == "render.sbatch";
            std::map<std::string, std::string> expected = {{"job-name", farm::slurmJobName(v)},
                                                           {"partition", "gpu,long-queue_1.x"},
                                                           {"account", "proj.render-1"},
                                                           {"cpus-per-task", render ? "3" : "1"},
                                                           {"output", render ? "logs/task_%A_%a.log" : "logs/finish_%j.log"}};
            if (render) expected["requeue"] = "";
            ASSERT_EQ(lines.size(), expected.size() + 3) << test::readFile(path);
            EXPECT_EQ(lines.front(), "#!/bin/bash");
            std::map<std::string, std::string> got;
            for (size_t i = 1; i + 2 < lines.size(); ++i) {
                std::string key, value;
                ASSERT_TRUE(oneSbatchWord(lines[i], key, value)) << lines[i];
                EXPECT_TRUE(got.emplace(key, value).second) << key;
            }
            EXPECT_EQ(got, expected);
            EXPECT_EQ(lines[lines.size() - 2].rfind("# ", 0), 0u) << lines[lines.size() - 2];
            ASSERT_EQ(lines.back().rfind("exec ", 0), 0u);
            const std::vector<std::string> want = render ? std::vector<std::string>{o.executable, "farm", "task", dir, "7"}
                                                         : std::vector<std::string>{o.executable, "farm", "finish", dir};
            EXPECT_EQ(execWords(path, base), want);
        }
        // The job name is the stem reduced to Slurm's characters.
        const std::string job = farm::slurmJobName(v);
        EXPECT_TRUE(std::all_of(job.begin(), job.end(), [](char c) { return std::isalnum((unsigned char)c) || std::strchr("._-", c); })) << job;
        // extraRenderArgs reach the task's argv word for word (the plan carries them; no shell on the way).
        const std::vector<std::string> argv = farm::taskCommand(dir, 3);
        ASSERT_GE(argv.size(), 8u);
        EXPECT_EQ(argv[0], o.executable);
        EXPECT_NE(std::search(argv.begin(), argv.end(), o.extraRenderArgs.begin(), o.extraRenderArgs.end()), argv.end());
        EXPECT_EQ(argv.back(), dir + "/pieces/f0000_x01_y00_s01.exr");
        // The dry run's commands name the folder in --chdir, quoted for a shell.
        ASSERT_EQ(r.commands.size(), 2u);
        EXPECT_NE(r.commands[0].find("--array=0-3"), std::string::npos) << r.commands[0];
    }
    std::string found;
    shell("find " + shQuote(tmp) + " -name 'PWNED*'", &found);
    EXPECT_EQ(found, "");
    EXPECT_FALSE(fs::exists("PWNED"));

    // Refused, naming the option and the allowed characters: nothing is written.
    const std::string scene = tmp + "/plain.json";
    test::writeFile(scene, kStillScene);
    auto submitWith = [&](const std::function<void(farm::SubmitOptions&)>& change) {
        farm::SubmitOptions o;
        o.scene = scene;
        o.farmDir = tmp + "/refused";
        o.executable = "/usr/bin/specula";
        o.dryRun = true;
        change(o);
        return errorOf([&] { farm::submit(o); });
    };
    for (const std::string& bad : std::vector<std::string>{"gpu\n#SBATCH --wrap=touch PWNED", "a;b", "$(id)", "`id`", "a b", "it's", "x#y", "a,,b", ",a", "a,",
                                  "\xc3\xbc", "a\\b", "a\"b", std::string(300, 'p')}) {
        const std::string e = submitWith([&](farm::SubmitOptions& o) { o.partition = bad; });
        EXPECT_EQ(e.rfind("[input] --partition: ", 0), 0u) << e;
        EXPECT_NE(e.find("letters, digits, '.', '_' and '-'"), std::string::npos) << e;
        EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 0) << e;
        const std::string a = submitWith([&](farm::SubmitOptions& o) { o.account = bad; });
        EXPECT_EQ(a.rfind("[input] --account: ", 0), 0u) << a;
    }
    EXPECT_NE(submitWith([](farm::SubmitOptions& o) { o.account = "a,b"; }).find("--account"), std::string::npos);
    EXPECT_NE(submitWith([&](farm::SubmitOptions& o) { o.farmDir = tmp + "/new\nline"; }).find("[input] --dir: "), std::string::npos);
    EXPECT_NE(submitWith([&](farm::SubmitOptions& o) { o.executable = "/opt/spec\nula"; }).find("absolute path without control"),
              std::string::npos);
    EXPECT_NE(submitWith([&](farm::SubmitOptions& o) { o.executable = "specula"; }).find("absolute path"), std::string::npos);
    const std::string newlineScene = tmp + "/new\nline.json";
    test::writeFile(newlineScene, kStillScene);
    EXPECT_NE(submitWith([&](farm::SubmitOptions& o) { o.scene = newlineScene; }).find("control character"), std::string::npos);
    EXPECT_FALSE(fs::exists(tmp + "/refused"));
    // A scene that is a device is refused after a bounded read, not read forever.
    EXPECT_NE(submitWith([&](farm::SubmitOptions& o) { o.scene = "/dev/zero"; }).find("/dev/zero"), std::string::npos);
}

namespace {

// A dry-run farm of the still scene (2 tiles), its plan as JSON, and a way to write the plan back.
struct DryFarm {
    std::string dir;
    explicit DryFarm(const std::string& root) {
        const std::string scene = root + "/still.json";
        test::writeFile(scene, kStillScene);
        farm::SubmitOptions o;
        o.scene = scene;
        o.farmDir = root + "/farm dir";
        o.executable = "/usr/bin/true";
        o.tilesX = 2;
        o.dryRun = true;
        dir = farm::submit(o).farmDir;
    }
    Json plan() const { return Json::parse(test::readFile(dir + "/plan.json")); }
    void write(const Json& j) const { test::writeFile(dir + "/plan.json", j.dump(1)); }
};

// Sets the plan's value at 'pointer', checks the farm commands refuse it naming 'pointer', then restores the plan.
std::string planError(const DryFarm& f, const std::string& pointer, const Json& value) {
    const Json good = f.plan();
    Json bad = good;
    bad[Json::json_pointer(pointer)] = value;
    f.write(bad);
    const std::string e = errorOf([&] { farm::checkPlan(f.dir); });
    // Every command reads the plan the same way.
    EXPECT_EQ(errorOf([&] { farm::taskCommand(f.dir, 0); }), e);
    EXPECT_EQ(errorOf([&] { farm::status(f.dir); }), e);
    f.write(good);
    return e;
}

}  // namespace

// plan.json is input: wrong types and ranges name their JSON pointer, and no piece path leaves the farm folder (absolute,
// '..', a symlinked folder or file); a plan that is a device or a folder is an IoError.
TEST(FarmPlan, EveryValueIsCheckedAndPathsStayInside) {
    const std::string tmp = test::tempDir("farm_plan");
    DryFarm f(tmp);
    EXPECT_EQ(farm::checkPlan(f.dir), 2);
    struct Case {
        std::string pointer;
        Json value;
        std::string fragment;
    };
    const std::vector<Case> cases = {
        {"/tasks/1/piece", "../escape.exr", "'..' component"},
        {"/tasks/1/piece", "pieces/../../escape.exr", "'..' component"},
        {"/tasks/1/piece", "/tmp/escape.exr", "absolute path"},
        {"/tasks/1/piece", "pieces/a\nb.exr", "control character"},
        {"/tasks/1/piece", 7, "expected a string, got a number"},
        {"/tasks/1/piece", "pieces/f0000_x00_y00_s00.exr", "earlier task"},
        {"/tasks/1/piece", "pieces/x.png", "does not end in .exr"},
        {"/tasks/1/frame", "0", "expected an integer"},
        {"/tasks/1/frame", 5, "expected an integer in 0 … 0"},
        {"/tasks/1/frame", 1.5, "expected an integer"},
        {"/tasks/1/crop/2", 9, "expected an integer in 0 … 8"},
        {"/tasks/1/crop", Json::array({4, 0, 4, 6}), "x0 < x1"},
        {"/tasks/1/split/0", 1, "expected an integer in 0 … 0"},
        {"/tasks/1", Json::array(), "expected an object"},
        {"/tasks", Json::object(), "expected an array"},
        {"/spp", -1, "/spp"},
        {"/spp", 1e30, "/spp"},
        {"/attempts", 3, "expected an integer in 0 … 2"},
        {"/retries", "2", "/retries"},
        {"/name", "../x", "not a file name"},
        {"/scene", "relative.json", "not an absolute path"},
        {"/specula", "/bin/sh\n", "control character"},
        {"/render_args/0", 3, "expected a string"},
        {"/dir", "/elsewhere", "written for the farm folder"},
        {"/frames/1", 100000000, "/frames/1"},
        {"/version", 2, "/version"},
    };
    for (const Case& c : cases) {
        Json value = c.value;
        if (c.pointer == "/render_args/0") {
            Json p = f.plan();
            p["render_args"] = Json::array({3});
            f.write(p);
            const std::string e = errorOf([&] { farm::checkPlan(f.dir); });
            EXPECT_NE(e.find("[input] /render_args/0: "), std::string::npos) << e;
            p["render_args"] = Json::array();
            f.write(p);
            continue;
        }
        const std::string e = planError(f, c.pointer, value);
        SCOPED_TRACE(c.pointer + " = " + value.dump());
        EXPECT_EQ(e.rfind("[input] " + c.pointer + ": ", 0), 0u) << e;
        EXPECT_NE(e.find(c.fragment), std::string::npos) << e;
        EXPECT_NE(e.find(f.dir + "/plan.json"), std::string::npos) << e;
        EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 0) << e;
    }
    EXPECT_EQ(farm::checkPlan(f.dir), 2);
    // A pieces folder that is a symlink out of the farm, and a piece that is a symlink.
    const std::string outside = tmp + "/outside";
    fs::create_directories(outside);
    fs::rename(f.dir + "/pieces", f.dir + "/pieces.real");
    fs::create_directory_symlink(outside, f.dir + "/pieces");
    std::string e = errorOf([&] { farm::checkPlan(f.dir); });
    EXPECT_EQ(e.rfind("[input] /tasks/0/piece: ", 0), 0u) << e;
    EXPECT_NE(e.find("leads out of the farm folder"), std::string::npos) << e;
    fs::remove(f.dir + "/pieces");
    fs::rename(f.dir + "/pieces.real", f.dir + "/pieces");
    fs::create_symlink(outside + "/x.exr", f.dir + "/pieces/f0000_x01_y00_s00.exr");
    e = errorOf([&] { farm::checkPlan(f.dir); });
    EXPECT_EQ(e.rfind("[input] /tasks/1/piece: ", 0), 0u) << e;
    EXPECT_NE(e.find("is a symlink"), std::string::npos) << e;
    fs::remove(f.dir + "/pieces/f0000_x01_y00_s00.exr");
    // The frames folder leading out of the farm.
    fs::rename(f.dir + "/frames", f.dir + "/frames.real");
    fs::create_directory_symlink(outside, f.dir + "/frames");
    e = errorOf([&] { farm::checkPlan(f.dir); });
    EXPECT_EQ(e.rfind("[input] /name: ", 0), 0u) << e;
    fs::remove(f.dir + "/frames");
    fs::rename(f.dir + "/frames.real", f.dir + "/frames");
    EXPECT_EQ(farm::checkPlan(f.dir), 2);
    // Not JSON, not an object, a device, a folder.
    const std::string good = test::readFile(f.dir + "/plan.json");
    test::writeFile(f.dir + "/plan.json", "{\"version\": 1,");
    EXPECT_EQ(errorOf([&] { farm::checkPlan(f.dir); }).rfind("[input] ", 0), 0u);
    test::writeFile(f.dir + "/plan.json", "[1, 2]");
    EXPECT_NE(errorOf([&] { farm::checkPlan(f.dir); }).find("expected an object"), std::string::npos);
    fs::remove(f.dir + "/plan.json");
    fs::create_symlink("/dev/zero", f.dir + "/plan.json");
    e = errorOf([&] { farm::checkPlan(f.dir); });
    EXPECT_EQ(e.rfind("[io] ", 0), 0u) << e;
    EXPECT_NE(e.find("not a regular file"), std::string::npos) << e;
    fs::remove(f.dir + "/plan.json");
    fs::create_directory(f.dir + "/plan.json");
    EXPECT_EQ(errorOf([&] { farm::checkPlan(f.dir); }).rfind("[io] ", 0), 0u);
    fs::remove(f.dir + "/plan.json");
    test::writeFile(f.dir + "/plan.json", good);
    EXPECT_EQ(farm::checkPlan(f.dir), 2);
}

namespace {

// A fake sbatch first in PATH: it appends its argv (one word a line, then "--") to calls.txt and answers as
// 'behaviour' says: "ok" prints job ids 41, 42, ...; "fail" exits 1; "finish-fails" refuses only the finish job.
struct FakeSbatch {
    std::string bin, calls, oldPath;
    FakeSbatch(const std::string& root, const std::string& behaviour) {
        bin = root + "/fake bin";
        calls = root + "/calls.txt";
        fs::create_directories(bin);
        test::writeFile(bin + "/sbatch", "#!/bin/sh\nfor a in \"$@\"; do printf '%s\\n' \"$a\" >> " + shQuote(calls) +
                                             "; done\necho -- >> " + shQuote(calls) + "\n"
                                             "n=$(grep -c -- '^--$' " + shQuote(calls) + ")\n"
                                             "case " + behaviour + " in fail) echo 'sbatch: error: Batch job submission failed: Unable to contact slurm controller' >&2; exit 1;;\n"
                                             "finish-fails) case \"$*\" in *--dependency*) echo 'sbatch: error: QOSMaxSubmitJobPerUserLimit' >&2; exit 1;; esac;;\n"
                                             "esac\necho $((40 + n))\n");
        fs::permissions(bin + "/sbatch", fs::perms::owner_all);
        oldPath = std::getenv("PATH") ? std::getenv("PATH") : "";
        setenv("PATH", (bin + ":" + oldPath).c_str(), 1);
    }
    ~FakeSbatch() { setenv("PATH", oldPath.c_str(), 1); }
    std::vector<std::string> words() const { return fs::exists(calls) ? linesOf(test::readFile(calls)) : std::vector<std::string>{}; }
};

}  // namespace

// A resubmission counts against the retries only once sbatch queued it; sbatch gets its arguments as an argv (the
// folder with a space is one word), the array as ranges, and --chdir for the scripts' relative log paths.
TEST(FarmFinish, RefusedSbatchDoesNotUseAnAttempt) {
    const std::string tmp = test::tempDir("farm_finish");
    DryFarm f(tmp);
    {
        FakeSbatch sb(tmp + "/a", "fail");
        const std::string e = errorOf([&] { farm::finish(f.dir); });
        EXPECT_EQ(e.rfind("[io] sbatch failed: ", 0), 0u) << e;
        EXPECT_NE(e.find("Unable to contact slurm controller"), std::string::npos) << e;
        EXPECT_EQ(f.plan()["attempts"], 0);
        EXPECT_EQ(errorOf([&] { farm::finish(f.dir); }), e);
        EXPECT_EQ(f.plan()["attempts"], 0);
    }
    {
        FakeSbatch sb(tmp + "/b", "ok");
        const std::string report = farm::finish(f.dir);
        EXPECT_NE(report.find("resubmitted 2 missing piece(s)"), std::string::npos) << report;
        EXPECT_NE(report.find("as job 41, attempt 1 of 2"), std::string::npos) << report;
        EXPECT_EQ(f.plan()["attempts"], 1);
        const std::vector<std::string> want = {"--parsable", "--chdir=" + f.dir, "--array=0-1", f.dir + "/render.sbatch", "--",
                                               "--parsable", "--chdir=" + f.dir, "--dependency=afterany:41", f.dir + "/finish.sbatch", "--"};
        EXPECT_EQ(sb.words(), want);
        EXPECT_EQ(test::readFile(f.dir + "/jobs.txt"), "41 render 0-1\n42 finish\n");
    }
    {
        // The array queued, the finish job refused: that attempt happened and counts.
        FakeSbatch sb(tmp + "/c", "finish-fails");
        const std::string e = errorOf([&] { farm::finish(f.dir); });
        EXPECT_NE(e.find("the render job 41 is queued"), std::string::npos) << e;
        EXPECT_EQ(f.plan()["attempts"], 2);
        // No retries left: exit 3 naming the missing pieces.
        const std::string last = errorOf([&] { farm::finish(f.dir); });
        EXPECT_NE(last.find("[io] merged 0 frame(s), 0 already written; 2 piece(s) still missing after 2 resubmission(s)"), std::string::npos)
            << last;
    }
    // status reads jobs.txt as untrusted: a line that is not a job id never reaches squeue.
    test::writeFile(f.dir + "/jobs.txt", "41 render 0-1\n$(touch PWNED) finish\n`touch PWNED`\n");
    FakeSbatch sb(tmp + "/d", "ok");
    test::writeFile(sb.bin + "/squeue", "#!/bin/sh\nprintf '%s|' \"$@\"\n");
    fs::permissions(sb.bin + "/squeue", fs::perms::owner_all);
    const std::string st = farm::status(f.dir);
    EXPECT_NE(st.find("-h|-j|41|-o|%i %T %R|"), std::string::npos) << st;
    EXPECT_FALSE(fs::exists(f.dir + "/PWNED"));
}

namespace {

// One real sample-split piece (split 0/2 of the still scene's 4 spp), whose attributes and counts the cases change.
ImageSet splitPiece() {
    SceneOverrides ov;
    ov.sampleSplitIndex = 0;
    ov.sampleSplitCount = 2;
    Scene s = loadSceneFromString(kStillScene, ".", ov);
    return renderScene(s).images;
}

}  // namespace

// Piece files are read only when they are regular files; every attribute and sample count is checked with its range;
// a failed write is an IoError (exit 3).
TEST(FarmMerge, HostilePiecesAreClearErrors) {
    const std::string tmp = test::tempDir("farm_merge_hostile");
    const ImageSet piece = splitPiece();
    const auto color = ColorConfig::load("builtin");
    auto mergeError = [&](const std::vector<std::string>& list, const std::string& out = "") {
        return errorOf([&] { farm::mergePieces(list, out.empty() ? tmp + "/out.exr" : out); });
    };
    // Not regular files: refused at once (a read of /dev/zero or a FIFO would never return).
    std::string e = mergeError({"/dev/zero"});
    EXPECT_EQ(e.rfind("[io] merge: the piece '/dev/zero' is not a regular file", 0), 0u) << e;
    fs::create_directories(tmp + "/folder.exr");
    EXPECT_NE(mergeError({tmp + "/folder.exr"}).find("is a folder"), std::string::npos);
    ASSERT_EQ(mkfifo((tmp + "/fifo.exr").c_str(), 0600), 0);
    EXPECT_NE(mergeError({tmp + "/fifo.exr"}).find("not a regular file"), std::string::npos);
    EXPECT_EQ(mergeError({tmp + "/gone.exr"}).rfind("[io] merge: cannot read the piece", 0), 0u);
    test::writeFile(tmp + "/text.exr", "not an exr");
    EXPECT_EQ(mergeError({tmp + "/text.exr"}).rfind("[input] merge: '" + tmp + "/text.exr' is not a Specula render piece", 0), 0u);

    struct Case {
        std::string attribute, value, fragment;
    };
    const std::vector<Case> cases = {
        {"frame", "abc", "specula:frame 'abc', not an integer in -2147483648 … 2147483647"},
        {"frame", "99999999999", "specula:frame '99999999999', not an integer"},
        {"frame", " 1", "not an integer"},
        {"spp", "1e30", "specula:spp '1e30', not an integer in 1 … 1048576"},
        {"spp", "-4", "specula:spp '-4'"},
        {"seed", "x", "specula:seed 'x'"},
        {"sample_block", "0", "specula:sample_block '0', not an integer in 1 … 4"},
        {"frame_size", "0x6", "specula:frame_size '0x6', not WxH"},
        {"frame_size", "8x6x1", "specula:frame_size"},
        {"crop", "0,0,8", "specula:crop '0,0,8'"},
        {"crop", "0,0,8,6\n", "specula:crop '0,0,8,6\\x0a'"},
        {"sample_split", "0/3", "a split's block is spp / K"},
        {"sample_split", "-1/2", "specula:sample_split '-1/2', not I/K"},
        {"sample_split", "1e30/2", "specula:sample_split"},
    };
    int n = 0;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.attribute + " = " + c.value);
        ImageSet bad = piece;
        bad.metadata["specula:" + c.attribute] = c.value;
        const std::string path = tmp + "/bad" + std::to_string(n++) + ".exr";
        writeExr(path, bad, *color);
        e = mergeError({path});
        EXPECT_EQ(e.rfind("[input] merge: '" + path + "' has ", 0), 0u) << e;
        EXPECT_NE(e.find(c.fragment), std::string::npos) << e;
        EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 0) << e;
        EXPECT_FALSE(fs::exists(tmp + "/out.exr"));
    }
    // Sample counts: whole numbers in 0 … spp/K = 2.
    for (float count : {-1.f, 1e30f, std::nanf(""), 2.5f, 3.f, INFINITY}) {
        ImageSet bad = piece;
        for (AovBuffer& b : bad.aovs)
            if (b.name == "samples") b.pixels[9] = count;  // pixel 1,1 of the 8-wide piece
        const std::string path = tmp + "/count" + std::to_string(n++) + ".exr";
        writeExr(path, bad, *color);
        e = mergeError({path});
        EXPECT_EQ(e.rfind("[input] merge: '" + path + "' has a sample count of ", 0), 0u) << e;
        EXPECT_NE(e.find("at pixel 1,1 of its 'samples' layer; counts are whole numbers in 0 … 2"), std::string::npos) << e;
    }
    // The real pieces merge; a missing output folder is an IoError before any piece is read.
    ImageSet second = splitPiece();
    {
        SceneOverrides ov;
        ov.sampleSplitIndex = 1;
        ov.sampleSplitCount = 2;
        Scene s = loadSceneFromString(kStillScene, ".", ov);
        second = renderScene(s).images;
    }
    writeExr(tmp + "/s0.exr", piece, *color);
    writeExr(tmp + "/s1.exr", second, *color);
    e = mergeError({tmp + "/s0.exr", tmp + "/s1.exr"}, tmp + "/no such folder/out.exr");
    EXPECT_EQ(e.rfind("[io] merge: the output folder '" + tmp + "/no such folder' of ", 0), 0u) << e;
    EXPECT_EQ(mergeError({"/dev/zero"}, tmp + "/no such folder/out.exr").rfind("[io] merge: the output folder", 0), 0u);
    // A full disk (a file size limit of 512 bytes, as a quota gives): the CLI's write fails with exit 3. A child
    // process of its own (fork here would inherit OpenEXR's thread pool without its threads).
    std::string out;
    EXPECT_EQ(shell("cd " + shQuote(tmp) + " && trap '' XFSZ && ulimit -f 1 && exec " + shQuote(SPECULA_CLI) +
                    " merge s0.exr s1.exr -o full.exr 2>&1", &out), 3) << out;
    EXPECT_NE(out.find("merge: cannot write EXR 'full.exr': the file written is incomplete (is the disk full?)"), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(tmp + "/full.exr"));
    const farm::MergeSummary m = farm::mergePieces({tmp + "/s0.exr", tmp + "/s1.exr"}, tmp + "/out.exr");
    EXPECT_EQ(m.sampleSplits, 2);
}
