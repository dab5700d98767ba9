// Issue 35 (glTF parts of classes 3 and 5): hostile glTF files. A deep or cyclic node hierarchy is refused without
// recursion; a value out of its range (glTF 2.0 specification, KHR_lights_punctual, KHR_materials_ior/_transmission)
// is one error naming the file, the JSON pointer into the glTF and the valid range: an InputError at
// "<file>#<pointer>" from the scene import, a GltfValueError (a MeshLoadError) from the mesh loader.
#include "core/geometry/mesh_io.h"
#include "core/scene/gltf_scene.h"
#include "core/util/error.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

using namespace specula;
namespace fs = std::filesystem;

namespace {

// tests/unit/data/gltf/triangle.gltf: one triangle (data URI buffer), a perspective camera, a point light, a glass
// material with KHR_materials_ior and _transmission.
nlohmann::json triangle() { return nlohmann::json::parse(test::readFile(test::sourcePath("tests/unit/data/gltf/triangle.gltf"))); }

class GltfHostile : public ::testing::Test {
protected:
    std::string dir = test::tempDir("gltf-hostile");

    std::string write(const std::string& name, const nlohmann::json& doc) {
        const std::string path = dir + "/" + name;
        test::writeFile(path, doc.dump());
        return path;
    }
    // triangle.gltf with 'pointer' set to 'value'.
    std::string patched(const std::string& pointer, const nlohmann::json& value) {
        nlohmann::json doc = triangle();
        doc[nlohmann::json::json_pointer(pointer)] = value;
        return write("patched.gltf", doc);
    }
    // The scene import's error: an InputError (exit 1) whose text names the file and the pointer and holds 'fragment'.
    void expectSceneError(const std::string& path, const std::string& pointer, const std::string& fragment) {
        try {
            gltfSceneDocument(path);
            ADD_FAILURE() << "no error for " << pointer;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_EQ(e.exitCode(), 1);
            EXPECT_EQ(e.pointer(), path + "#" + pointer) << what;
            EXPECT_NE(what.find(fragment), std::string::npos) << what;
            EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
        }
    }
    // The mesh loader's error for the same file: a GltfValueError with the pointer.
    void expectMeshError(const std::string& path, const std::string& pointer, const std::string& fragment) {
        try {
            loadMesh(path);
            ADD_FAILURE() << "no error for " << pointer;
        } catch (const GltfValueError& e) {
            EXPECT_EQ(e.pointer, pointer) << e.what();
            EXPECT_NE(std::string(e.what()).find("cannot load mesh '" + path + "': " + pointer + ": "), std::string::npos) << e.what();
            EXPECT_NE(e.reason.find(fragment), std::string::npos) << e.what();
        }
    }
    void expectBoth(const std::string& pointer, const nlohmann::json& value, const std::string& fragment) {
        SCOPED_TRACE(pointer + " = " + value.dump());
        const std::string path = patched(pointer, value);
        expectSceneError(path, pointer, fragment);
        expectMeshError(path, pointer, fragment);
    }
};

TEST_F(GltfHostile, TheFixtureImports) {
    const nlohmann::json doc = gltfSceneDocument(test::sourcePath("tests/unit/data/gltf/triangle.gltf"));
    EXPECT_EQ(doc["render"]["width"], 810);  // aspectRatio 1.5 x 540 rows
    EXPECT_NEAR(doc["camera"]["fov"].get<double>(), 0.8 * 180.0 / 3.14159265358979, 1e-4);
    EXPECT_EQ(doc["materials"]["glass"]["nodes"]["glass"]["inputs"]["ior"], 1.5);
    EXPECT_EQ(loadMesh(test::sourcePath("tests/unit/data/gltf/triangle_external.gltf")).triangleCount(), 1u);
    // ior 0 is the extension's "no refraction" and stays valid; 1 is the lowest index.
    EXPECT_NO_THROW(gltfSceneDocument(patched("/materials/0/extensions/KHR_materials_ior/ior", 0)));
    EXPECT_NO_THROW(gltfSceneDocument(patched("/materials/0/extensions/KHR_materials_ior/ior", 1)));
}

TEST_F(GltfHostile, CameraValuesOutOfRange) {
    expectBoth("/cameras/0/perspective/yfov", 0, "0 is outside (0, 3.14159) (the vertical field of view in radians)");
    expectBoth("/cameras/0/perspective/yfov", 1e308, "1e+308 is outside (0, 3.14159)");
    expectBoth("/cameras/0/perspective/yfov", -0.5, "-0.5 is outside (0, 3.14159)");
    // aspectRatio 1e9 would be a 5.4e11-pixel-wide image: 16 to 8192 columns of 540 rows are allowed.
    expectBoth("/cameras/0/perspective/aspectRatio", 1e9, "1e+09 is outside [0.0296296, 15.1704]");
    expectBoth("/cameras/0/perspective/aspectRatio", 0.001, "0.001 is outside [0.0296296, 15.1704]");
    expectBoth("/cameras/0/perspective/znear", 0, "0 is outside (0, 1e+12]");
    expectBoth("/cameras/0/perspective/zfar", 0.05, "0.05 is outside (0.1, 1e+12]");
    expectBoth("/cameras/0/perspective/yfov", "wide", "expected a number in (0, 3.14159)");
    // The widest and narrowest images still import, at their bounds.
    EXPECT_EQ(gltfSceneDocument(patched("/cameras/0/perspective/aspectRatio", 15.17))["render"]["width"], 8192);
    EXPECT_EQ(gltfSceneDocument(patched("/cameras/0/perspective/aspectRatio", 0.03))["render"]["width"], 16);
}

TEST_F(GltfHostile, LightAndMaterialValuesOutOfRange) {
    const std::string light = "/extensions/KHR_lights_punctual/lights/0";
    expectBoth(light + "/intensity", -5, "-5 is outside [0, 1e+12] (luminous intensity in candela)");
    expectBoth(light + "/intensity", 1e300, "1e+300 is outside [0, 1e+12]");
    expectBoth(light + "/range", 0, "0 is outside (0, 1e+12]");
    expectBoth(light + "/color/1", -0.1, "-0.1 is outside [0, 1]");
    expectBoth(light + "/type", "laser", "\"laser\" is not one of \"directional\", \"point\", \"spot\"");
    nlohmann::json spot = {{"type", "spot"}, {"intensity", 10}, {"spot", {{"innerConeAngle", 0.6}, {"outerConeAngle", 0.3}}}};
    expectSceneError(patched(light, spot), light + "/spot/innerConeAngle", "0.6 is not below outerConeAngle 0.3");
    spot["spot"]["outerConeAngle"] = 2.0;
    expectSceneError(patched(light, spot), light + "/spot/outerConeAngle", "2 is outside (0, 1.5708]");

    const std::string ior = "/materials/0/extensions/KHR_materials_ior/ior";
    expectBoth(ior, -1.5, "-1.5 is outside [1, 10] (index of refraction: 0 or [1, 10])");
    expectBoth(ior, 0.5, "0.5 is outside [1, 10]");
    expectBoth(ior, 1e308, "1e+308 is outside [1, 10]");
    expectBoth("/materials/0/extensions/KHR_materials_transmission/transmissionFactor", 1.5, "1.5 is outside [0, 1]");
    expectBoth("/materials/0/pbrMetallicRoughness/metallicFactor", 2, "2 is outside [0, 1] (metalness)");
    expectBoth("/materials/0/pbrMetallicRoughness/roughnessFactor", -1, "-1 is outside [0, 1]");
    expectBoth("/materials/0/pbrMetallicRoughness/baseColorFactor/3", 7, "7 is outside [0, 1] (linear RGBA)");
}

TEST_F(GltfHostile, IndicesOutOfRange) {
    expectBoth("/nodes/1/camera", 5, "5 is not an index into cameras (valid: [0, 0], the file has 1)");
    expectBoth("/nodes/2/extensions/KHR_lights_punctual/light", 3,
               "3 is not an index into /extensions/KHR_lights_punctual/lights (valid: [0, 0])");
    expectBoth("/scene", 2, "2 is not an index into scenes (valid: [0, 0], the file has 1)");
    expectBoth("/scenes/0/nodes/1", -1, "-1 is not an index into nodes (valid: [0, 2]");
    expectBoth("/nodes/0/mesh", 9, "9 is not an index into meshes");
    expectBoth("/meshes/0/primitives/0/material", 4, "4 is not an index into materials");
    expectBoth("/meshes/0/primitives/0/attributes/POSITION", 2, "2 is not an index into accessors (valid: [0, 1]");
    expectSceneError(patched("/materials/0/pbrMetallicRoughness/baseColorTexture", {{"index", 0}}),
                     "/materials/0/pbrMetallicRoughness/baseColorTexture/index", "the file has no textures");
    expectBoth("/accessors/0/bufferView", 7, "7 is not an index into bufferViews (valid: [0, 1]");
    expectBoth("/bufferViews/0/buffer", 1, "1 is not an index into buffers (valid: [0, 0]");
}

TEST_F(GltfHostile, BufferValuesOutOfRange) {
    // tinygltf reads a negative byteOffset as 0: the triangle would load from the wrong bytes without the check.
    expectBoth("/accessors/0/byteOffset", -4, "-4 is outside [0, 9007199254740992] (a byte offset into the bufferView)");
    expectBoth("/accessors/0/byteOffset", 1.5, "expected an integer in [0, 9007199254740992]");
    expectBoth("/accessors/0/count", 0, "0 is outside [1, ");
    expectBoth("/accessors/1/componentType", 5130, "5130 is not a glTF component type");
    // 3 elements of 12 bytes from byte 4 end at byte 40 of a 36-byte view.
    expectMeshError(patched("/accessors/0/byteOffset", 4), "/accessors/0",
                    "accessor exceeds its bufferView 0: byteOffset 4 + (count 3 - 1) x stride 12 + 12 bytes must be at most its byteLength 36");
    expectMeshError(patched("/bufferViews/1/byteLength", 16), "/bufferViews/1/byteLength",
                    "byteOffset 36 + byteLength 16 = 52 is beyond buffer 0's byteLength 44");
    expectMeshError(patched("/bufferViews/0/byteStride", 6), "/bufferViews/0/byteStride", "6 is not a multiple of 4 in [4, 252]");
    // An image in a bufferView beyond its buffer (tinygltf would copy byteLength bytes from &data[byteOffset]).
    nlohmann::json doc = triangle();
    doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 40}, {"byteLength", 4096}});
    doc["images"] = {{{"bufferView", 2}, {"mimeType", "image/png"}}};
    doc["textures"] = {{{"source", 0}}};
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
    expectSceneError(write("image.gltf", doc), "/bufferViews/2/byteLength", "= 4136 is beyond buffer 0's byteLength 44");
}

TEST_F(GltfHostile, NodeTransformsOutOfRange) {
    expectMeshError(patched("/nodes/0/scale", {1e30, 1, 1}), "/nodes/0/scale/0", "1e+30 is outside [-1e+06, 1e+06] (a scale factor)");
    expectSceneError(patched("/nodes/0/translation", {0, -1e12, 0}), "/nodes/0/translation/1", "-1e+12 is outside [-1e+09, 1e+09]");
    expectSceneError(patched("/nodes/0/rotation", {0, 0, 0, 0}), "/nodes/0/rotation", "a quaternion of length 0 is not a rotation");
    expectSceneError(patched("/nodes/0/matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 2}), "/nodes/0/matrix/15",
                     "2 must be 1 (the last row of an affine transform is 0, 0, 0, 1)");
    // Each level scales by 1e3 (valid alone); composed, the triangle's node is at 1e9, past the bound on any node's scale.
    nlohmann::json doc = triangle();
    doc["scenes"][0]["nodes"] = {3, 1, 2};
    doc["nodes"][0]["scale"] = {1e3, 1e3, 1e3};
    doc["nodes"].push_back({{"scale", {1e3, 1e3, 1e3}}, {"children", {4}}});
    doc["nodes"].push_back({{"scale", {1e3, 1e3, 1e3}}, {"children", {0}}});
    const std::string path = write("composed.gltf", doc);
    const std::string message = "the transform composed with its ancestors' scales by 1e+09, outside [-1e+06, 1e+06]";
    expectSceneError(path, "/nodes/0", message);
    expectMeshError(path, "/nodes/0", message);
}

// A chain of 'levels' nodes from the scene's root down to the triangle (scene root = node 'levels' - 1).
nlohmann::json chain(size_t levels) {
    nlohmann::json doc = triangle();
    doc["scenes"][0]["nodes"] = {levels};
    nlohmann::json nodes = nlohmann::json::array();
    nodes.push_back(doc["nodes"][0]);  // node 0: the triangle
    for (size_t i = 1; i <= levels; ++i) nodes.push_back({{"translation", {0.001, 0, 0}}, {"children", {i - 1}}});
    doc["nodes"] = nodes;
    doc.erase("cameras");
    return doc;
}

TEST_F(GltfHostile, DeepAndCyclicHierarchiesAreRefusedWithoutRecursion) {
    // 1023 ancestors + the triangle: 1024 levels, the bound, loads (translated by 1023 x 0.001 along x).
    const TriangleMesh deep = loadMesh(write("deep.gltf", chain(1023)));
    ASSERT_EQ(deep.positions.size(), 3u);
    EXPECT_NEAR(deep.positions[0].x, -1.0 + 1.023, 1e-4);
    // 100000 levels overflowed the call stack of the recursive walk; now node 0 is 1025 levels deep in a 1025 chain.
    expectMeshError(write("deeper.gltf", chain(1024)), "/nodes/0", "node 0 is 1025 levels deep; the node hierarchy may be at most 1024 deep");
    expectSceneError(write("deepest.gltf", chain(100000)), "/nodes/98976",
                     "node 98976 is 1025 levels deep; the node hierarchy may be at most 1024 deep");
    // A cycle 1 -> 2 -> 1 that no scene lists, beside the scene's triangle.
    nlohmann::json doc = triangle();
    doc["nodes"].push_back({{"children", {4}}});
    doc["nodes"].push_back({{"children", {3}}, {"mesh", 0}});
    expectSceneError(write("cycle.gltf", doc), "/nodes/3", "node 3 is in a cycle of children (glTF nodes form trees; its parent is node 4)");
    // A scene root inside a cycle: the root has a parent.
    doc["scenes"][0]["nodes"].push_back(3);
    expectMeshError(write("rooted_cycle.gltf", doc), "/scenes/0/nodes/3", "node 3 is a child of node 4 (a scene lists root nodes only)");
    // A node with two parents (a diamond doubles the instances at every level: 2^n visits without the check).
    doc = triangle();
    doc["nodes"][1]["children"] = {0};
    doc["nodes"][2]["children"] = {0};
    doc["scenes"][0]["nodes"] = {1, 2};
    expectSceneError(write("two_parents.gltf", doc), "/nodes/2/children/0",
                     "node 0 is already a child of node 1 (glTF nodes form disjoint trees: one parent at most)");
    doc["nodes"][0]["children"] = {0};
    expectMeshError(write("self.gltf", doc), "/nodes/0/children/0", "node 0 is its own child");
}

TEST_F(GltfHostile, DeepJsonAndLargeFilesAreRefusedBeforeParsing) {
    // tinygltf copies "extras" by recursion: 100000 nested arrays would overflow its stack.
    std::string text = test::readFile(test::sourcePath("tests/unit/data/gltf/triangle.gltf"));
    const std::string deep = "\"extras\": " + std::string(100000, '[') + std::string(100000, ']') + ", ";
    text.insert(text.find("\"asset\""), deep);
    const std::string path = dir + "/deep_json.gltf";
    test::writeFile(path, text);
    try {
        loadMesh(path);
        ADD_FAILURE() << "deep JSON loaded";
    } catch (const MeshLoadError& e) {
        EXPECT_NE(std::string(e.what()).find("the JSON nests deeper than 64 levels (at byte "), std::string::npos) << e.what();
    }
    // Brackets inside strings do not count.
    nlohmann::json doc = triangle();
    doc["asset"]["generator"] = std::string(200, '[');
    EXPECT_EQ(loadMesh(write("brackets.gltf", doc)).triangleCount(), 1u);
    // A .gltf over 256 MiB is not read (a sparse file: no disk is used).
    const std::string big = dir + "/big.gltf";
    { std::ofstream(big) << "{}"; }
    fs::resize_file(big, (uintmax_t(256) << 20) + 1);
    try {
        loadMesh(big);
        ADD_FAILURE() << "a 256 MiB .gltf loaded";
    } catch (const MeshLoadError& e) {
        EXPECT_NE(std::string(e.what()).find("268435457 bytes is larger than a .gltf (JSON text) may be (256 MiB)"), std::string::npos) << e.what();
    }
}

}  // namespace
