// Farm pieces and scene animation (issue 18): keyframe evaluation and its errors, sample splits and crop tiles merged
// bit for bit into the single-process render, and the merge's refusals (core/farm/farm.h, core/scene/animation.h).
#include "core/farm/farm.h"
#include "core/io/image_io.h"
#include "core/render/renderer.h"
#include "core/scene/animation.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "core/util/error.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

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
