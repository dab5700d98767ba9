// glTF 2.0 geometry import via tinygltf: triangles of every mesh instanced by the scene's node tree,
// with node transforms baked in and texture coordinates converted to Specula's v-up convention.
//
// Debian's libtinygltf-dev ships the header plus a shared library that specula_core does not link,
// so the implementation is compiled here, in exactly one TU (no other file may define
// TINYGLTF_IMPLEMENTATION). Images are not needed for geometry, and Debian has no stb headers in
// /usr/include, so stb is disabled and a no-op image loader is installed.
#include "core/geometry/mesh_io_detail.h"

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include "core/util/error.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

namespace specula {

GltfValueError::GltfValueError(const std::string& file_, const std::string& pointer_, const std::string& reason_)
    : MeshLoadError("cannot load mesh '" + file_ + "': " + pointer_ + ": " + reason_), file(file_), pointer(pointer_),
      reason(reason_) {}

}  // namespace specula

namespace specula::detail {

namespace {

bool ignoreImage(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                 void*) {
    return true;
}
// Scene import keeps each image's encoded bytes (embedded, in a GLB buffer or an external file read through the
// confined file callbacks below) so that they can be written for the texture store; nothing is decoded here.
bool keepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int, const unsigned char* bytes,
                    int size, void*) {
    if (image && bytes && size > 0) image->image.assign(bytes, bytes + size);
    return true;
}

std::string trimmed(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
    return s;
}

// External buffers: a URI such as "../../../../etc/passwd" must not be followed (issue 16). A buffer file is read only
// if it resolves (links included) inside the glTF file's folder or one of the folders listed in SPECULA_RESOURCE_PATH
// (':'-separated), is a regular file and is at most kMaxBufferBytes; the error never tells anything about a refused file.
constexpr uintmax_t kMaxBufferBytes = uintmax_t(4) << 30;

struct BufferAccess {
    std::vector<std::filesystem::path> roots;
    std::string baseDir;  // the glTF's folder as tinygltf spells it (the prefix of the URI's candidate path)
    std::string refused;  // the first URI refused, for the error message
    uintmax_t bytesRead = 0;  // all external buffers together are bounded by kMaxBufferBytes too (issue 35)
    bool inside(const std::string& file) const {
        std::error_code ec;
        std::filesystem::path p = std::filesystem::weakly_canonical(file, ec);
        if (ec) return false;
        for (const auto& root : roots) {
            auto [r, q] = std::mismatch(root.begin(), root.end(), p.begin(), p.end());
            if (r == root.end()) return true;
        }
        return false;
    }
};

bool bufferExists(const std::string& file, void* user) {
    auto* access = static_cast<BufferAccess*>(user);
    std::error_code ec;
    if (!access->inside(file)) {
        // tinygltf also tries the URI against the working folder ("./uri"): only the glTF's own folder's candidate
        // is the user's URI, and only that one is reported.
        if (access->refused.empty() && file.rfind(access->baseDir, 0) == 0) access->refused = file;
        return false;
    }
    return std::filesystem::is_regular_file(file, ec);
}

bool readBuffer(std::vector<unsigned char>* out, std::string* err, const std::string& file, void* user) {
    auto* access = static_cast<BufferAccess*>(user);
    std::error_code ec;
    if (!access->inside(file) || !std::filesystem::is_regular_file(file, ec)) {
        if (err) *err = "not a file inside the allowed folders";
        return false;
    }
    uintmax_t size = std::filesystem::file_size(file, ec);
    if (ec || size > kMaxBufferBytes - std::min(access->bytesRead, kMaxBufferBytes)) {
        if (err) *err = "larger than 4 GiB (with the buffers read before it)";
        return false;
    }
    access->bytesRead += size;
    std::ifstream in(file, std::ios::binary);
    out->resize(size_t(size));
    if (size > 0 && !in.read(reinterpret_cast<char*>(out->data()), std::streamsize(size))) {
        if (err) *err = "read failed";
        return false;
    }
    return true;
}

std::string expandNothing(const std::string& path, void*) { return path; }  // no ~ or $VAR expansion in URIs

// ---- The glTF JSON checked before tinygltf reads it (issue 35) -------------------------------------------------------
// tinygltf reads what it understands and silently defaults the rest: a negative byteOffset becomes 0, an index past
// the end is kept and skipped later, yfov 0 or a scale of 1e30 pass through. So the JSON itself is checked first, with
// a JSON pointer and the valid range in every error (glTF 2.0 specification §5 and the schemas of
// KHR_lights_punctual, KHR_materials_ior, _transmission and _emissive_strength). It also keeps tinygltf from reading an
// image's bufferView past its buffer (tinygltf passes &buffer.data[byteOffset] with byteLength unchecked).

using Json = nlohmann::json;

constexpr double kPi = 3.14159265358979323846;
// A .gltf is JSON text: beyond this it is a wrong file, as a JSON scene is (scene_loader.cpp kMaxSceneBytes).
constexpr uintmax_t kMaxGltfJsonBytes = uintmax_t(256) << 20;
// tinygltf takes a GLB's length as an unsigned int.
constexpr uintmax_t kMaxGlbBytes = (uintmax_t(1) << 32) - 1;
// tinygltf copies "extras" and "extensions" by recursion (ParseJsonAsValue): deeper text would overflow the stack.
// glTF's own structure is at most 7 levels deep; 64 is the scene loader's bound (scene_loader.cpp kMaxJsonDepth).
constexpr int kMaxGltfJsonDepth = 64;
// Node hierarchy depth (the importers walk it with an explicit stack; this bounds the composed transform's error too).
constexpr size_t kMaxNodeDepth = 1024;
// A node's transform, alone and composed with its ancestors', scales by at most 1e6 and translates by at most 1e9 (in
// metres: a float position keeps millimetres there): beyond, triangles collapse or overflow float.
constexpr double kMaxNodeScale = 1e6, kMaxNodeTranslation = 1e9;
constexpr double kMaxLightIntensity = 1e12;  // the scene loader's bound on intensity and power (scene_loader.cpp)
constexpr double kMaxDistance = 1e12;         // znear, zfar, light range, orthographic magnification
constexpr double kMaxIor = 10.0;              // bsdf.dielectric's hard ior range is [1.0001, 10]
constexpr uint64_t kMaxByteSize = uint64_t(1) << 53;  // byte offsets and lengths: exact as JSON numbers
// Vertices (and indices) of all node instances together: 2^26 vertices with normals, uvs and tangents are 3 GiB.
constexpr size_t kMaxInstancedElements = size_t(1) << 26;

std::string showNumber(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", v);
    return b;
}

std::string showJson(const Json& j) {
    std::string s = j.dump();
    return s.size() > 40 ? s.substr(0, 37) + "..." : s;
}

struct Range {
    double lo, hi;
    bool loOpen = false, hiOpen = false;
    bool contains(double v) const {
        return std::isfinite(v) && (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
    }
    std::string text() const {
        return std::string(loOpen ? "(" : "[") + showNumber(lo) + ", " + showNumber(hi) + (hiOpen ? ")" : "]");
    }
};

// The first byte at which brackets outside strings nest deeper than 'limit', or npos.
size_t tooDeepAt(const char* text, size_t size, int limit) {
    int depth = 0;
    bool inString = false;
    for (size_t i = 0; i < size; ++i) {
        const char c = text[i];
        if (inString) {
            if (c == '\\') ++i;
            else if (c == '"') inString = false;
        } else if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            if (++depth > limit) return i;
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
    return std::string::npos;
}

class GltfChecker {
public:
    GltfChecker(const std::string& path, const Json& doc) : path_(path), doc_(doc) {}

    void run() {
        if (!doc_.is_object()) fail("", "expected a JSON object, got " + showJson(doc_));
        for (const char* name : {"scenes", "nodes", "meshes", "accessors", "bufferViews", "buffers", "cameras", "materials",
                                 "textures", "images", "samplers", "skins", "animations"}) {
            const Json& a = array(doc_, "", name);
            for (size_t i = 0; i < a.size(); ++i)
                if (!a[i].is_object()) fail(at("/" + std::string(name), i), "expected an object, got " + showJson(a[i]));
        }
        checkBuffers();
        checkImagesAndTextures();
        checkAccessors();
        checkMeshes();
        checkMaterials();
        checkCameras();
        checkLights();
        checkNodes();
        checkScenes();
        checkHierarchy();
    }

private:
    const std::string& path_;
    const Json& doc_;
    std::vector<int64_t> parent_;  // of each node (-1: none), after checkNodes

    [[noreturn]] void fail(const std::string& pointer, const std::string& reason) const {
        throw GltfValueError(path_, pointer.empty() ? "/" : pointer, reason);
    }
    static std::string key(const std::string& ptr, const std::string& k) { return ptr + "/" + pointerEscape(k); }
    static std::string at(const std::string& ptr, size_t i) { return ptr + "/" + std::to_string(i); }

    const Json& array(const Json& obj, const std::string& ptr, const char* name) const {
        static const Json empty = Json::array();
        auto it = obj.find(name);
        if (it == obj.end()) return empty;
        if (!it->is_array()) fail(key(ptr, name), "expected an array, got " + showJson(*it));
        return *it;
    }
    const Json* object(const Json& obj, const std::string& ptr, const char* name) const {
        auto it = obj.find(name);
        if (it == obj.end()) return nullptr;
        if (!it->is_object()) fail(key(ptr, name), "expected an object, got " + showJson(*it));
        return &*it;
    }
    size_t count(const char* name) const { return array(doc_, "", name).size(); }
    const Json& element(const char* name, size_t i) const { return doc_.at(name).at(i); }

    std::optional<double> number(const Json& obj, const std::string& ptr, const char* name, Range r, const std::string& meaning,
                                 bool required = false) const {
        auto it = obj.find(name);
        const std::string p = key(ptr, name);
        if (it == obj.end()) {
            if (required) fail(p, "missing: " + meaning + " in " + r.text() + " is required");
            return std::nullopt;
        }
        return numberValue(*it, p, r, meaning);
    }
    double numberValue(const Json& v, const std::string& p, Range r, const std::string& meaning) const {
        if (!v.is_number()) fail(p, "expected a number in " + r.text() + " (" + meaning + "), got " + showJson(v));
        const double x = v.get<double>();
        if (!r.contains(x)) fail(p, showNumber(x) + " is outside " + r.text() + " (" + meaning + ")");
        return x;
    }
    std::vector<double> numbers(const Json& obj, const std::string& ptr, const char* name, size_t n, Range r,
                                const std::string& meaning) const {
        auto it = obj.find(name);
        if (it == obj.end()) return {};
        const std::string p = key(ptr, name);
        if (!it->is_array() || it->size() != n)
            fail(p, "expected an array of " + std::to_string(n) + " numbers in " + r.text() + " (" + meaning + "), got " + showJson(*it));
        std::vector<double> out;
        for (size_t i = 0; i < n; ++i) out.push_back(numberValue((*it)[i], at(p, i), r, meaning));
        return out;
    }
    // A non-negative integer in [lo, hi]; the caller checks sums and products with overflow checks.
    std::optional<uint64_t> integer(const Json& obj, const std::string& ptr, const char* name, uint64_t lo, uint64_t hi,
                                    const std::string& meaning, bool required = false) const {
        auto it = obj.find(name);
        const std::string p = key(ptr, name);
        const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
        if (it == obj.end()) {
            if (required) fail(p, "missing: " + meaning + ", an integer in " + range + ", is required");
            return std::nullopt;
        }
        if (!it->is_number_integer()) fail(p, "expected an integer in " + range + " (" + meaning + "), got " + showJson(*it));
        if (!it->is_number_unsigned() && it->get<int64_t>() < 0)
            fail(p, std::to_string(it->get<int64_t>()) + " is outside " + range + " (" + meaning + ")");
        const uint64_t v = it->get<uint64_t>();
        if (v < lo || v > hi) fail(p, std::to_string(v) + " is outside " + range + " (" + meaning + ")");
        return v;
    }
    // An index into the top-level array 'of' (the value v at pointer p).
    size_t indexValue(const Json& v, const std::string& p, const char* of) const {
        const size_t n = count(of);
        const std::string range = n ? "[0, " + std::to_string(n - 1) + "]" : "none: the file has no " + std::string(of);
        if (!v.is_number_integer()) fail(p, "expected an index into " + std::string(of) + " (" + range + "), got " + showJson(v));
        const bool negative = !v.is_number_unsigned() && v.get<int64_t>() < 0;
        if (negative || v.get<uint64_t>() >= n)
            fail(p, (negative ? std::to_string(v.get<int64_t>()) : std::to_string(v.get<uint64_t>())) + " is not an index into " +
                        of + " (" + (n ? "valid: " + range + ", the file has " + std::to_string(n) : range) + ")");
        return size_t(v.get<uint64_t>());
    }
    std::optional<size_t> index(const Json& obj, const std::string& ptr, const char* name, const char* of, bool required = false) const {
        auto it = obj.find(name);
        if (it == obj.end()) {
            if (required) fail(key(ptr, name), std::string("missing: an index into ") + of + " is required");
            return std::nullopt;
        }
        return indexValue(*it, key(ptr, name), of);
    }
    std::string string(const Json& obj, const std::string& ptr, const char* name, std::initializer_list<const char*> allowed,
                       bool required) const {
        auto it = obj.find(name);
        std::string list;
        for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + "\"" + a + "\"";
        if (it == obj.end()) {
            if (required) fail(key(ptr, name), "missing: one of " + list + " is required");
            return "";
        }
        if (it->is_string())
            for (const char* a : allowed)
                if (it->get<std::string>() == a) return a;
        fail(key(ptr, name), showJson(*it) + " is not one of " + list);
    }

    void checkBuffers() {
        const Json& buffers = array(doc_, "", "buffers");
        for (size_t i = 0; i < buffers.size(); ++i)
            integer(buffers[i], at("/buffers", i), "byteLength", 1, kMaxByteSize, "the buffer's size in bytes", true);
        const Json& views = array(doc_, "", "bufferViews");
        for (size_t i = 0; i < views.size(); ++i) {
            const std::string p = at("/bufferViews", i);
            const size_t buffer = *index(views[i], p, "buffer", "buffers", true);
            const uint64_t offset = integer(views[i], p, "byteOffset", 0, kMaxByteSize, "a byte offset into the buffer").value_or(0);
            const uint64_t length = *integer(views[i], p, "byteLength", 1, kMaxByteSize, "the view's size in bytes", true);
            if (auto stride = integer(views[i], p, "byteStride", 4, 252, "the distance between elements in bytes"); stride && *stride % 4)
                fail(key(p, "byteStride"), std::to_string(*stride) + " is not a multiple of 4 in [4, 252]");
            const uint64_t bufferLength = element("buffers", buffer).at("byteLength").get<uint64_t>();
            if (offset + length > bufferLength)
                fail(key(p, "byteLength"), "byteOffset " + std::to_string(offset) + " + byteLength " + std::to_string(length) +
                                               " = " + std::to_string(offset + length) + " is beyond buffer " +
                                               std::to_string(buffer) + "'s byteLength " + std::to_string(bufferLength));
        }
    }

    void checkImagesAndTextures() {
        const Json& images = array(doc_, "", "images");
        for (size_t i = 0; i < images.size(); ++i) index(images[i], at("/images", i), "bufferView", "bufferViews");
        const Json& textures = array(doc_, "", "textures");
        for (size_t i = 0; i < textures.size(); ++i) {
            index(textures[i], at("/textures", i), "source", "images");
            index(textures[i], at("/textures", i), "sampler", "samplers");
        }
    }

    static int componentBytes(uint64_t type) {
        switch (type) {
        case 5120: case 5121: return 1;
        case 5122: case 5123: return 2;
        case 5125: case 5126: return 4;
        default: return 0;
        }
    }

    void checkAccessors() {
        const Json& accessors = array(doc_, "", "accessors");
        for (size_t i = 0; i < accessors.size(); ++i) {
            const Json& a = accessors[i];
            const std::string p = at("/accessors", i);
            const auto view = index(a, p, "bufferView", "bufferViews");
            const uint64_t offset = integer(a, p, "byteOffset", 0, kMaxByteSize, "a byte offset into the bufferView").value_or(0);
            const uint64_t componentType = *integer(a, p, "componentType", 0, kMaxByteSize, "the component type", true);
            const int size = componentBytes(componentType);
            if (!size)
                fail(key(p, "componentType"), std::to_string(componentType) +
                                                  " is not a glTF component type (5120, 5121, 5122, 5123, 5125 or 5126)");
            // No upper bound of its own: count is bounded by its bufferView below (overflow included).
            const uint64_t elements = *integer(a, p, "count", 1, UINT64_MAX, "the number of elements", true);
            const std::string type = string(a, p, "type", {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"}, true);
            const int components = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : type == "VEC4" ? 4
                                   : type == "MAT2" ? 4 : type == "MAT3" ? 9 : 16;
            if (!view) continue;  // all zeros (or sparse): nothing is read
            const Json& v = element("bufferViews", *view);
            const uint64_t viewLength = v.at("byteLength").get<uint64_t>(), elementBytes = uint64_t(size) * uint64_t(components);
            const uint64_t stride = v.contains("byteStride") ? v.at("byteStride").get<uint64_t>() : elementBytes;
            uint64_t span = 0, end = 0;
            const bool fits = !__builtin_mul_overflow(elements - 1, stride, &span) && !__builtin_add_overflow(span, elementBytes, &end) &&
                              !__builtin_add_overflow(end, offset, &end) && end <= viewLength;
            if (!fits)
                fail(p, "accessor exceeds its bufferView " + std::to_string(*view) + ": byteOffset " + std::to_string(offset) +
                            " + (count " + std::to_string(elements) + " - 1) x stride " + std::to_string(stride) + " + " +
                            std::to_string(elementBytes) + " bytes must be at most its byteLength " + std::to_string(viewLength));
        }
    }

    void checkMeshes() {
        const Json& meshes = array(doc_, "", "meshes");
        for (size_t i = 0; i < meshes.size(); ++i) {
            const std::string mp = key(at("/meshes", i), "primitives");
            const Json& prims = array(meshes[i], at("/meshes", i), "primitives");
            for (size_t k = 0; k < prims.size(); ++k) {
                const std::string p = at(mp, k);
                if (!prims[k].is_object()) fail(p, "expected an object, got " + showJson(prims[k]));
                if (const Json* attributes = object(prims[k], p, "attributes"))
                    for (auto it = attributes->begin(); it != attributes->end(); ++it)
                        indexValue(it.value(), key(key(p, "attributes"), it.key()), "accessors");
                index(prims[k], p, "indices", "accessors");
                index(prims[k], p, "material", "materials");
                integer(prims[k], p, "mode", 0, 6, "the topology: 0 points ... 4 triangles ... 6 triangle fan");
            }
        }
    }

    void textureInfo(const Json& obj, const std::string& ptr, const char* name) const {
        const Json* t = object(obj, ptr, name);
        if (!t) return;
        const std::string p = key(ptr, name);
        index(*t, p, "index", "textures", true);
        integer(*t, p, "texCoord", 0, 255, "the TEXCOORD_n set");
    }

    void checkMaterials() {
        const Json& materials = array(doc_, "", "materials");
        const Range unit{0, 1};
        for (size_t i = 0; i < materials.size(); ++i) {
            const Json& m = materials[i];
            const std::string p = at("/materials", i);
            if (const Json* pbr = object(m, p, "pbrMetallicRoughness")) {
                const std::string pp = key(p, "pbrMetallicRoughness");
                numbers(*pbr, pp, "baseColorFactor", 4, unit, "linear RGBA");
                number(*pbr, pp, "metallicFactor", unit, "metalness");
                number(*pbr, pp, "roughnessFactor", unit, "perceptual roughness");
                textureInfo(*pbr, pp, "baseColorTexture");
                textureInfo(*pbr, pp, "metallicRoughnessTexture");
            }
            textureInfo(m, p, "normalTexture");
            if (const Json* n = object(m, p, "normalTexture"))
                number(*n, key(p, "normalTexture"), "scale", Range{-1e3, 1e3}, "the normal map's strength");
            textureInfo(m, p, "occlusionTexture");
            if (const Json* o = object(m, p, "occlusionTexture")) number(*o, key(p, "occlusionTexture"), "strength", unit, "occlusion strength");
            textureInfo(m, p, "emissiveTexture");
            numbers(m, p, "emissiveFactor", 3, unit, "linear RGB");
            const Json* ext = object(m, p, "extensions");
            if (!ext) continue;
            const std::string ep = key(p, "extensions");
            if (const Json* e = object(*ext, ep, "KHR_materials_emissive_strength"))
                number(*e, key(ep, "KHR_materials_emissive_strength"), "emissiveStrength", Range{0, 1e9}, "a multiplier of emissiveFactor");
            if (const Json* e = object(*ext, ep, "KHR_materials_transmission")) {
                number(*e, key(ep, "KHR_materials_transmission"), "transmissionFactor", unit, "the transmitted fraction");
                textureInfo(*e, key(ep, "KHR_materials_transmission"), "transmissionTexture");
            }
            if (const Json* e = object(*ext, ep, "KHR_materials_ior"); e && e->contains("ior")) {
                // The extension allows ior >= 1, and 0 (no refraction); bsdf.dielectric takes at most 10.
                const std::string ip = key(key(ep, "KHR_materials_ior"), "ior");
                const Json& v = e->at("ior");
                if (!(v.is_number() && v.get<double>() == 0.0)) numberValue(v, ip, Range{1, kMaxIor}, "index of refraction: 0 or [1, 10]");
            }
        }
    }

    void checkCameras() {
        const Json& cameras = array(doc_, "", "cameras");
        for (size_t i = 0; i < cameras.size(); ++i) {
            const std::string p = at("/cameras", i);
            const std::string type = string(cameras[i], p, "type", {"perspective", "orthographic"}, true);
            const Json* c = object(cameras[i], p, type.c_str());
            if (!c) fail(key(p, type), "missing: the " + type + " camera's parameters are required");
            const std::string cp = key(p, type);
            if (type == "perspective") {
                number(*c, cp, "yfov", Range{0, kPi, true, true}, "the vertical field of view in radians", true);
                // The scene import renders 540 rows and round(540 x aspectRatio) columns, 16 to 8192 (gltf_scene.cpp).
                const double h = GltfSceneInfo::kImageHeight;
                number(*c, cp, "aspectRatio", Range{GltfSceneInfo::kMinImageWidth / h, GltfSceneInfo::kMaxImageWidth / h},
                       "width / height; the image is 540 pixels high and 16 to 8192 wide");
                const double znear = *number(*c, cp, "znear", Range{0, kMaxDistance, true}, "the near clipping distance", true);
                number(*c, cp, "zfar", Range{znear, kMaxDistance, true}, "the far clipping distance, beyond znear");
            } else {
                for (const char* mag : {"xmag", "ymag"})
                    if (*number(*c, cp, mag, Range{-kMaxDistance, kMaxDistance}, "the half size of the view", true) == 0.0)
                        fail(key(cp, mag), "0 is outside [-1e+12, 1e+12] without 0 (the half size of the view)");
                const double znear = *number(*c, cp, "znear", Range{0, kMaxDistance}, "the near clipping distance", true);
                number(*c, cp, "zfar", Range{znear, kMaxDistance, true}, "the far clipping distance, beyond znear", true);
            }
        }
    }

    size_t lightCount() const {
        const Json* ext = object(doc_, "", "extensions");
        const Json* lp = ext ? object(*ext, "/extensions", "KHR_lights_punctual") : nullptr;
        return lp ? array(*lp, "/extensions/KHR_lights_punctual", "lights").size() : 0;
    }

    void checkLights() {
        const Json* ext = object(doc_, "", "extensions");
        const Json* lp = ext ? object(*ext, "/extensions", "KHR_lights_punctual") : nullptr;
        if (!lp) return;
        const std::string base = "/extensions/KHR_lights_punctual/lights";
        const Json& lights = array(*lp, "/extensions/KHR_lights_punctual", "lights");
        for (size_t i = 0; i < lights.size(); ++i) {
            const Json& l = lights[i];
            const std::string p = at(base, i);
            if (!l.is_object()) fail(p, "expected an object, got " + showJson(l));
            const std::string type = string(l, p, "type", {"directional", "point", "spot"}, true);
            numbers(l, p, "color", 3, Range{0, 1}, "linear RGB");
            number(l, p, "intensity", Range{0, kMaxLightIntensity}, type == "directional" ? "illuminance in lux" : "luminous intensity in candela");
            number(l, p, "range", Range{0, kMaxDistance, true}, "the distance where the light ends");
            if (type != "spot") continue;
            const Json* s = object(l, p, "spot");
            if (!s) continue;  // the defaults: 0 and pi/4
            const std::string sp = key(p, "spot");
            const double inner = number(*s, sp, "innerConeAngle", Range{0, kPi / 2, false, true}, "radians from the axis").value_or(0.0);
            const double outer = number(*s, sp, "outerConeAngle", Range{0, kPi / 2, true}, "radians from the axis").value_or(kPi / 4);
            if (!(inner < outer))
                fail(key(sp, "innerConeAngle"), showNumber(inner) + " is not below outerConeAngle " + showNumber(outer) +
                                                    " (valid: [0, outerConeAngle))");
        }
    }

    void checkNodes() {
        const Json& nodes = array(doc_, "", "nodes");
        const size_t lights = lightCount();
        parent_.assign(nodes.size(), -1);
        for (size_t i = 0; i < nodes.size(); ++i) {
            const Json& n = nodes[i];
            const std::string p = at("/nodes", i);
            index(n, p, "mesh", "meshes");
            index(n, p, "camera", "cameras");
            index(n, p, "skin", "skins");
            const Json& children = array(n, p, "children");
            for (size_t k = 0; k < children.size(); ++k) {
                const std::string cp = at(key(p, "children"), k);
                const size_t c = indexValue(children[k], cp, "nodes");
                if (c == i) fail(cp, "node " + std::to_string(i) + " is its own child (glTF nodes form trees)");
                if (parent_[c] >= 0)
                    fail(cp, "node " + std::to_string(c) + " is already a child of node " + std::to_string(parent_[c]) +
                                 " (glTF nodes form disjoint trees: one parent at most)");
                parent_[c] = int64_t(i);
            }
            if (const Json* ext = object(n, p, "extensions"))
                if (const Json* l = object(*ext, key(p, "extensions"), "KHR_lights_punctual")) {
                    const std::string lp = key(key(p, "extensions"), "KHR_lights_punctual");
                    const size_t valid = lights;
                    auto it = l->find("light");
                    if (it == l->end()) fail(key(lp, "light"), "missing: an index into KHR_lights_punctual's lights is required");
                    const bool ok = it->is_number_integer() && (it->is_number_unsigned() || it->get<int64_t>() >= 0) &&
                                    it->get<uint64_t>() < valid;
                    if (!ok)
                        fail(key(lp, "light"), showJson(*it) + " is not an index into /extensions/KHR_lights_punctual/lights (" +
                                                   (valid ? "valid: [0, " + std::to_string(valid - 1) + "]" : "the file has none") + ")");
                }
            const Range scale{-kMaxNodeScale, kMaxNodeScale}, move{-kMaxNodeTranslation, kMaxNodeTranslation};
            if (n.contains("matrix")) {
                const std::vector<double> m = numbers(n, p, "matrix", 16, Range{-kMaxNodeTranslation, kMaxNodeTranslation},
                                                      "a column-major affine transform");
                for (int c = 0; c < 3; ++c)
                    for (int r = 0; r < 3; ++r)
                        if (!scale.contains(m[size_t(c * 4 + r)]))
                            fail(at(key(p, "matrix"), size_t(c * 4 + r)), showNumber(m[size_t(c * 4 + r)]) + " is outside " + scale.text() +
                                                                             " (the linear part of the transform)");
                for (int k : {3, 7, 11, 15})
                    if (std::abs(m[size_t(k)] - (k == 15 ? 1.0 : 0.0)) > 1e-6)
                        fail(at(key(p, "matrix"), size_t(k)), showNumber(m[size_t(k)]) + " must be " + (k == 15 ? "1" : "0") +
                                                                 " (the last row of an affine transform is 0, 0, 0, 1)");
            }
            numbers(n, p, "translation", 3, move, "a translation in metres");
            numbers(n, p, "scale", 3, scale, "a scale factor");
            const std::vector<double> q = numbers(n, p, "rotation", 4, Range{-1.01, 1.01}, "a unit quaternion x, y, z, w");
            if (!q.empty()) {
                const double length = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
                if (!(std::abs(length - 1.0) <= 0.01))
                    fail(key(p, "rotation"), "a quaternion of length " + showNumber(length) + " is not a rotation (valid: length 1 +- 0.01)");
            }
        }
    }

    void checkScenes() {
        index(doc_, "", "scene", "scenes");
        const Json& scenes = array(doc_, "", "scenes");
        for (size_t s = 0; s < scenes.size(); ++s) {
            const std::string p = key(at("/scenes", s), "nodes");
            const Json& roots = array(scenes[s], at("/scenes", s), "nodes");
            std::set<size_t> seen;
            for (size_t k = 0; k < roots.size(); ++k) {
                const size_t r = indexValue(roots[k], at(p, k), "nodes");
                if (parent_[r] >= 0)
                    fail(at(p, k), "node " + std::to_string(r) + " is a child of node " + std::to_string(parent_[r]) +
                                       " (a scene lists root nodes only)");
                if (!seen.insert(r).second) fail(at(p, k), "node " + std::to_string(r) + " is listed twice");
            }
        }
    }

    // With one parent at most per node, a node that no root reaches lies on (or below) a cycle.
    void checkHierarchy() const {
        const Json& nodes = array(doc_, "", "nodes");
        std::vector<size_t> depth(nodes.size(), 0), stack;
        std::vector<char> reached(nodes.size(), 0);
        for (size_t i = 0; i < nodes.size(); ++i)
            if (parent_[i] < 0) stack.push_back(i), reached[i] = 1, depth[i] = 1;
        while (!stack.empty()) {
            const size_t i = stack.back();
            stack.pop_back();
            if (depth[i] > kMaxNodeDepth)
                fail(at("/nodes", i), "node " + std::to_string(i) + " is " + std::to_string(depth[i]) +
                                          " levels deep; the node hierarchy may be at most " + std::to_string(kMaxNodeDepth) + " deep");
            for (const Json& c : array(nodes[i], at("/nodes", i), "children")) {
                const size_t k = c.get<size_t>();
                reached[k] = 1, depth[k] = depth[i] + 1;
                stack.push_back(k);
            }
        }
        for (size_t i = 0; i < nodes.size(); ++i)
            if (!reached[i])
                fail(at("/nodes", i), "node " + std::to_string(i) + " is in a cycle of children (glTF nodes form trees; " +
                                          "its parent is node " + std::to_string(parent_[i]) + ")");
    }
};

// a + b and a * b, or false on overflow (accessor bounds come from the file: 2^57 + 1 elements wrapped the product).
bool addSize(size_t a, size_t b, size_t& r) { return !__builtin_add_overflow(a, b, &r); }
bool mulSize(size_t a, size_t b, size_t& r) { return !__builtin_mul_overflow(a, b, &r); }

// A bounds-checked view of one accessor's elements.
struct AccessorView {
    const unsigned char* data = nullptr;
    size_t stride = 0, count = 0;
    int componentType = 0, components = 0;
    bool normalized = false;

    double component(size_t i, int c) const {
        const unsigned char* q = data + i * stride;
        switch (componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: { float f; std::memcpy(&f, q + 4 * c, 4); return f; }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: { double x = q[c]; return normalized ? x / 255.0 : x; }
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            double x = double(int8_t(q[c]));
            return normalized ? std::max(x / 127.0, -1.0) : x;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t s; std::memcpy(&s, q + 2 * c, 2);
            return normalized ? s / 65535.0 : double(s);
        }
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t s; std::memcpy(&s, q + 2 * c, 2);
            return normalized ? std::max(s / 32767.0, -1.0) : double(s);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t u; std::memcpy(&u, q + 4 * c, 4); return u; }
        default: return 0.0;
        }
    }
    uint32_t index(size_t i) const {
        const unsigned char* q = data + i * stride;
        switch (componentType) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return q[0];
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t s; std::memcpy(&s, q, 2); return s; }
        default: { uint32_t u; std::memcpy(&u, q, 4); return u; }
        }
    }
};

// The nodes the default scene instances (all scenes' without a default; without scenes every root node).
std::vector<int> rootNodes(const tinygltf::Model& m) {
    std::vector<int> roots;
    if (!m.scenes.empty()) {
        if (m.defaultScene >= 0 && size_t(m.defaultScene) < m.scenes.size()) return m.scenes[size_t(m.defaultScene)].nodes;
        std::set<int> seen;  // scenes may share root nodes: each is instanced once
        for (const auto& scene : m.scenes)
            for (int n : scene.nodes)
                if (seen.insert(n).second) roots.push_back(n);
        return roots;
    }
    std::vector<bool> isChild(m.nodes.size(), false);
    for (const auto& node : m.nodes)
        for (int c : node.children)
            if (c >= 0 && size_t(c) < isChild.size()) isChild[size_t(c)] = true;
    for (size_t i = 0; i < m.nodes.size(); ++i)
        if (!isChild[i]) roots.push_back(int(i));
    return roots;
}

glm::dmat4 localTransform(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
        glm::dmat4 M;
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) M[c][r] = node.matrix[size_t(c * 4 + r)];  // column-major
        return M;
    }
    glm::dmat4 T(1.0), R(1.0), S(1.0);
    if (node.translation.size() == 3)
        T[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
    if (node.rotation.size() == 4) {  // glTF stores (x, y, z, w)
        glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
        R = glm::mat4_cast(glm::normalize(q));
    }
    if (node.scale.size() == 3) {
        S[0][0] = node.scale[0];
        S[1][1] = node.scale[1];
        S[2][2] = node.scale[2];
    }
    return T * R * S;  // glTF: M = T * R * S
}


// The transform of a node composed with its ancestors' is bounded as a node's own is (GltfChecker): many levels of
// modest scales multiply past float's range, and the triangles would overflow or collapse.
void checkComposedTransform(const std::string& path, int index, const glm::dmat4& M) {
    const std::string pointer = "/nodes/" + std::to_string(index);
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
            if (!(std::abs(M[c][r]) <= kMaxNodeScale))
                throw GltfValueError(path, pointer, "the transform composed with its ancestors' scales by " + showNumber(M[c][r]) +
                                                        ", outside [-1e+06, 1e+06] (as a node's own scale)");
    for (int r = 0; r < 3; ++r)
        if (!(std::abs(M[3][r]) <= kMaxNodeTranslation))
            throw GltfValueError(path, pointer, "the transform composed with its ancestors' translates by " + showNumber(M[3][r]) +
                                                    ", outside [-1e+09, 1e+09] (as a node's own translation)");
}

// Calls visit(node index, world transform) for every node under the roots, parents before children, in document
// order. GltfChecker has made the hierarchy a forest at most kMaxNodeDepth deep, so each node is visited once; an
// explicit stack replaces recursion (a deep hierarchy overflowed the call stack, issue 35).
template <class Visit>
void walkNodes(const std::string& path, const tinygltf::Model& m, const std::vector<int>& roots, Visit&& visit) {
    std::vector<std::pair<int, glm::dmat4>> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, glm::dmat4(1.0));
    size_t visits = 0;
    while (!stack.empty()) {
        const auto [index, parent] = stack.back();
        stack.pop_back();
        if (index < 0 || size_t(index) >= m.nodes.size() || ++visits > m.nodes.size())
            throwMeshError(path, "the node hierarchy is not a set of trees");  // kept out by GltfChecker
        const tinygltf::Node& node = m.nodes[size_t(index)];
        const glm::dmat4 world = parent * localTransform(node);
        checkComposedTransform(path, index, world);
        visit(index, world);
        for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) stack.emplace_back(*c, world);
    }
}

class GltfImporter {
public:
    GltfImporter(const std::string& path, const tinygltf::Model& model, int materialFilter)
        : path_(path), m_(model), materialFilter_(materialFilter) {}

    TriangleMesh run() {
        const std::vector<int> roots = rootNodes(m_);
        if (m_.nodes.empty())  // bare meshes, no node tree at all: take them untransformed
            for (size_t i = 0; i < m_.meshes.size(); ++i) addMesh(int(i), glm::dmat4(1.0));
        walkNodes(path_, m_, roots, [&](int index, const glm::dmat4& world) {
            if (m_.nodes[size_t(index)].mesh >= 0) addMesh(m_.nodes[size_t(index)].mesh, world);
        });
        if (parts_.empty())
            throwMeshError(path_, materialFilter_ != kAllGltfMaterials
                                      ? "no triangles with material " + std::to_string(materialFilter_)
                                      : skippedPrimitives_ ? "no triangles (only non-triangle primitives)" : "no triangles");
        return mergeMeshParts(parts_);
    }

private:
    const std::string& path_;
    const tinygltf::Model& m_;
    int materialFilter_;
    std::vector<TriangleMesh> parts_;
    int skippedPrimitives_ = 0;
    size_t instancedVertices_ = 0, instancedIndices_ = 0;  // over all node instances, bounded by kMaxInstancedElements

private:

    AccessorView view(int accessorIndex, const char* what, std::initializer_list<int> types) const {
        if (accessorIndex < 0 || size_t(accessorIndex) >= m_.accessors.size())
            throwMeshError(path_, std::string(what) + ": accessor index out of range");
        const tinygltf::Accessor& acc = m_.accessors[size_t(accessorIndex)];
        if (acc.sparse.isSparse) throwMeshError(path_, std::string(what) + ": sparse accessors are not supported");
        if (std::find(types.begin(), types.end(), acc.type) == types.end())
            throwMeshError(path_, std::string(what) + ": unexpected accessor type");
        if (acc.bufferView < 0 || size_t(acc.bufferView) >= m_.bufferViews.size())
            throwMeshError(path_, std::string(what) + ": accessor has no valid bufferView");
        const tinygltf::BufferView& bv = m_.bufferViews[size_t(acc.bufferView)];
        if (bv.buffer < 0 || size_t(bv.buffer) >= m_.buffers.size())
            throwMeshError(path_, std::string(what) + ": bufferView has no valid buffer");
        const tinygltf::Buffer& buf = m_.buffers[size_t(bv.buffer)];
        int compSize = tinygltf::GetComponentSizeInBytes(uint32_t(acc.componentType));
        int nComp = tinygltf::GetNumComponentsInType(uint32_t(acc.type));
        int stride = acc.ByteStride(bv);
        if (compSize <= 0 || nComp <= 0 || stride <= 0)
            throwMeshError(path_, std::string(what) + ": invalid component type or byteStride");
        size_t begin = 0, viewEnd = 0, span = 0, last = 0;
        const size_t elemSize = size_t(compSize) * size_t(nComp);
        bool fits = addSize(bv.byteOffset, acc.byteOffset, begin) && addSize(bv.byteOffset, bv.byteLength, viewEnd);
        viewEnd = std::min(viewEnd, buf.data.size());
        if (acc.count > 0)
            fits = fits && begin <= viewEnd && mulSize(acc.count - 1, size_t(stride), span) &&
                   addSize(span, elemSize, last) && last <= viewEnd - begin;
        if (!fits) throwMeshError(path_, std::string(what) + ": accessor exceeds its buffer");
        AccessorView v;
        v.data = buf.data.data() + begin;
        v.stride = size_t(stride);
        v.count = acc.count;
        v.componentType = acc.componentType;
        v.components = nComp;
        v.normalized = acc.normalized;
        return v;
    }

    void addMesh(int meshIndex, const glm::dmat4& M) {
        if (meshIndex < 0 || size_t(meshIndex) >= m_.meshes.size())
            throwMeshError(path_, "mesh index " + std::to_string(meshIndex) + " out of range");
        glm::dmat3 M3(M);
        double det = glm::determinant(M3);
        glm::dmat3 normalMatrix = glm::transpose(glm::inverse(M3));  // normals transform by M^-T
        double handedness = det < 0 ? -1.0 : 1.0;
        for (const tinygltf::Primitive& prim : m_.meshes[size_t(meshIndex)].primitives) {
            if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES) {
                ++skippedPrimitives_;
                continue;
            }
            if (materialFilter_ != kAllGltfMaterials && prim.material != materialFilter_) continue;
            auto attr = [&](const char* name) {
                auto it = prim.attributes.find(name);
                return it == prim.attributes.end() ? -1 : it->second;
            };
            if (attr("POSITION") < 0) throwMeshError(path_, "mesh primitive without POSITION");
            TriangleMesh part;
            AccessorView pos = view(attr("POSITION"), "POSITION", {TINYGLTF_TYPE_VEC3});
            size_t n = pos.count;
            // Each node instance is a copy: a small file can instance a mesh many times over (nodes x primitives).
            instancedVertices_ += n;
            if (instancedVertices_ > kMaxInstancedElements)
                throwMeshError(path_, "the node tree instances more than " + std::to_string(kMaxInstancedElements) +
                                          " vertices (2^26, the bound of one glTF file)");
            part.positions.resize(n);
            for (size_t i = 0; i < n; ++i) {
                glm::dvec4 p = M * glm::dvec4(pos.component(i, 0), pos.component(i, 1), pos.component(i, 2), 1.0);
                part.positions[i] = Vec3(p);
                if (!isFinite(part.positions[i]))
                    throw GltfValueError(path_, "/accessors/" + std::to_string(attr("POSITION")),
                                         "vertex " + std::to_string(i) + " is not a finite float once placed by its node (valid: |x| < 3.4e+38)");
            }
            if (attr("NORMAL") >= 0) {
                AccessorView nv = view(attr("NORMAL"), "NORMAL", {TINYGLTF_TYPE_VEC3});
                if (nv.count != n) throwMeshError(path_, "NORMAL count differs from POSITION count");
                part.normals.resize(n);
                for (size_t i = 0; i < n; ++i) {
                    glm::dvec3 nn = normalMatrix * glm::dvec3(nv.component(i, 0), nv.component(i, 1), nv.component(i, 2));
                    double len = glm::length(nn);
                    part.normals[i] = len > 0 ? Vec3(nn / len) : Vec3(0, 0, 1);
                }
            }
            if (attr("TEXCOORD_0") >= 0) {
                AccessorView tv = view(attr("TEXCOORD_0"), "TEXCOORD_0", {TINYGLTF_TYPE_VEC2});
                if (tv.count != n) throwMeshError(path_, "TEXCOORD_0 count differs from POSITION count");
                part.uvs.resize(n);
                // glTF puts v = 0 at the top of the image; Specula (like OpenGL and OBJ) puts v = 0 at
                // the bottom, so v' = 1 - v. The image itself is not flipped.
                for (size_t i = 0; i < n; ++i)
                    part.uvs[i] = Vec2(float(tv.component(i, 0)), float(1.0 - tv.component(i, 1)));
            }
            if (attr("TANGENT") >= 0) {
                AccessorView tv = view(attr("TANGENT"), "TANGENT", {TINYGLTF_TYPE_VEC4});
                if (tv.count != n) throwMeshError(path_, "TANGENT count differs from POSITION count");
                part.tangents.resize(n);
                // glTF's bitangent cross(n, t) * w points "up" in the image (its normal maps are +Y up,
                // OpenGL style), i.e. towards decreasing glTF v = increasing Specula v. So glTF's w already
                // describes Specula's +v bitangent and the v' = 1 - v conversion must NOT negate it
                // (glTF-Sample-Models#174, KhronosGroup/glTF#2046: MikkTSpace reproduces glTF tangents only
                // when fed 1 - v). Only a mirroring node transform (det < 0) flips the handedness.
                for (size_t i = 0; i < n; ++i) {
                    glm::dvec3 t = M3 * glm::dvec3(tv.component(i, 0), tv.component(i, 1), tv.component(i, 2));
                    double len = glm::length(t);
                    double w = tv.component(i, 3) < 0 ? -1.0 : 1.0;
                    part.tangents[i] = Vec4(len > 0 ? Vec3(t / len) : Vec3(1, 0, 0), float(w * handedness));
                }
            }
            std::vector<uint32_t> idx;
            if (prim.indices >= 0) {
                AccessorView iv = view(prim.indices, "indices", {TINYGLTF_TYPE_SCALAR});
                instancedIndices_ += iv.count;
                if (instancedIndices_ > kMaxInstancedElements)
                    throwMeshError(path_, "the node tree instances more than " + std::to_string(kMaxInstancedElements) +
                                              " vertex indices (2^26, the bound of one glTF file)");
                if (iv.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                    iv.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                    iv.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
                    throwMeshError(path_, "indices must be unsigned byte, short or int");
                idx.resize(iv.count);
                for (size_t i = 0; i < iv.count; ++i) {
                    idx[i] = iv.index(i);
                    if (idx[i] >= n)
                        throwMeshError(path_, "vertex index " + std::to_string(idx[i]) + " out of range (" +
                                                  std::to_string(n) + " vertices)");
                }
            } else {
                idx.resize(n);
                for (size_t i = 0; i < n; ++i) idx[i] = uint32_t(i);
            }
            // glTF: a node transform with negative determinant turns the winding clockwise; restore
            // counter-clockwise so that the geometric and shading normals keep agreeing.
            for (size_t t = 0; t + 2 < idx.size(); t += 3) {
                if (det < 0)
                    part.indices.emplace_back(idx[t], idx[t + 2], idx[t + 1]);
                else
                    part.indices.emplace_back(idx[t], idx[t + 1], idx[t + 2]);
            }
            if (!part.indices.empty()) parts_.push_back(std::move(part));
        }
    }
};

}  // namespace

namespace {
BufferAccess accessFor(const std::string& path) {
    BufferAccess access;
    access.baseDir = tinygltf::GetBaseDir(path);
    std::error_code ec;
    access.roots.push_back(std::filesystem::weakly_canonical(std::filesystem::absolute(path).parent_path(), ec));
    if (const char* extra = std::getenv("SPECULA_RESOURCE_PATH")) {
        std::stringstream list(extra);
        for (std::string dir; std::getline(list, dir, ':');)
            if (!dir.empty()) access.roots.push_back(std::filesystem::weakly_canonical(dir, ec).lexically_normal());
    for (auto& root : access.roots)
        if (root.has_parent_path() && root.filename().empty()) root = root.parent_path();  // "dir/" -> "dir"
    }
    return access;
}

// Reads the file (bounded), checks its JSON (nesting depth, then GltfChecker) and only then hands it to tinygltf, which
// reads the buffers (through the confined file callbacks above) and the images.
void loadModel(const std::string& path, bool binary, bool keepImages, tinygltf::Model& model) {
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(path, ec), limit = binary ? kMaxGlbBytes : kMaxGltfJsonBytes;
    if (ec) throwMeshError(path, "cannot read the file: " + ec.message());
    if (size > limit)
        throwMeshError(path, std::to_string(size) + " bytes is larger than a " + (binary ? "GLB file may be (4 GiB)" : ".gltf (JSON text) may be (256 MiB)"));
    std::string bytes(size_t(size), '\0');
    std::ifstream in(path, std::ios::binary);
    if (!in || (size > 0 && !in.read(bytes.data(), std::streamsize(size)))) throwMeshError(path, "cannot read the file");
    // The JSON text: the whole .gltf, or a GLB's first chunk (12-byte header, then chunk length and type).
    size_t jsonBegin = 0, jsonSize = bytes.size();
    if (binary) {
        uint32_t chunk = 0;
        if (bytes.size() >= 20) std::memcpy(&chunk, bytes.data() + 12, 4);
        jsonBegin = std::min<size_t>(20, bytes.size());
        jsonSize = std::min<size_t>(chunk, bytes.size() - jsonBegin);
    }
    if (size_t deep = tooDeepAt(bytes.data() + jsonBegin, jsonSize, kMaxGltfJsonDepth); deep != std::string::npos)
        throwMeshError(path, "the JSON nests deeper than " + std::to_string(kMaxGltfJsonDepth) + " levels (at byte " +
                                 std::to_string(jsonBegin + deep) + ")");
    Json doc;
    try {
        doc = Json::parse(bytes.begin() + std::ptrdiff_t(jsonBegin), bytes.begin() + std::ptrdiff_t(jsonBegin + jsonSize), nullptr, false);
    } catch (const Json::exception&) {  // a number beyond double's range: tinygltf reports it below
        doc = Json(Json::value_t::discarded);
    }
    if (!doc.is_discarded()) GltfChecker(path, doc).run();

    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(keepImages ? &keepImageBytes : &ignoreImage, nullptr);
    BufferAccess access = accessFor(path);
    loader.SetFsCallbacks({&bufferExists, &expandNothing, &readBuffer, nullptr, &access});
    std::string err, warn;
    bool ok = false;
    try {
        if (bytes.empty())
            err = "empty file";
        else if (binary)
            ok = loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                             unsigned(bytes.size()), access.baseDir);
        else
            ok = loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), unsigned(bytes.size()), access.baseDir);
    } catch (const std::exception& e) {
        // tinygltf indexes some GLB headers with vector::at (found by fuzz_mesh): a parse error like any other.
        throwMeshError(path, std::string("glTF parse error: ") + e.what());
    }
    if (!ok && !access.refused.empty())
        throwMeshError(path, "a buffer URI leads outside the glTF file's folder; buffers are read only from that folder "
                             "and from the folders listed in SPECULA_RESOURCE_PATH (docs/scene-format.md)");
    if (!ok) throwMeshError(path, "glTF parse error: " + (err.empty() ? std::string("unknown error") : trimmed(err)));
    if (doc.is_discarded()) throwMeshError(path, "glTF parse error: not valid JSON");  // tinygltf should have said so
}
}  // namespace

TriangleMesh loadGltfMesh(const std::string& path, bool binary, int materialFilter) {
    tinygltf::Model model;
    loadModel(path, binary, false, model);
    return GltfImporter(path, model, materialFilter).run();
}

namespace {

Vec3 factor3(const std::vector<double>& v, Vec3 def) {
    return v.size() >= 3 ? Vec3(float(v[0]), float(v[1]), float(v[2])) : def;
}
}  // namespace

GltfSceneInfo describeGltfScene(const std::string& path, bool binary,
                                const std::function<std::string(const std::vector<unsigned char>&, const std::string&)>& saveImage) {
    tinygltf::Model m;
    loadModel(path, binary, true, m);
    GltfSceneInfo info;
    // Images as files the texture store can read: external ones where they are (inside the folders buffers may come
    // from, as for buffers), embedded ones written by the caller; one per glTF image that a material uses.
    const BufferAccess access = accessFor(path);
    std::vector<std::string> imageFiles(m.images.size());
    auto externalImage = [&](const std::string& uri) {
        std::string decoded;  // percent-decoding (RFC 3986), as tinygltf decodes buffer URIs
        for (size_t i = 0; i < uri.size(); ++i) {
            if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
                std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
                decoded += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
                i += 2;
            } else {
                decoded += uri[i];
            }
        }
        const std::string file = !decoded.empty() && decoded[0] == '/' ? decoded : tinygltf::JoinPath(access.baseDir, decoded);
        std::error_code ec;
        if (!access.inside(file) || !std::filesystem::is_regular_file(file, ec))
            throwMeshError(path, "image URI '" + uri + "' is not a file inside the glTF file's folder or SPECULA_RESOURCE_PATH");
        return std::filesystem::weakly_canonical(file, ec).string();
    };
    auto textureFile = [&](int textureIndex) -> std::string {
        if (textureIndex < 0 || size_t(textureIndex) >= m.textures.size()) return "";
        const int source = m.textures[size_t(textureIndex)].source;
        if (source < 0 || size_t(source) >= m.images.size()) return "";
        const tinygltf::Image& img = m.images[size_t(source)];
        if (imageFiles[size_t(source)].empty() && img.image.empty() && !img.uri.empty() && img.uri.rfind("data:", 0) != 0)
            imageFiles[size_t(source)] = externalImage(img.uri);
        if (imageFiles[size_t(source)].empty()) {
            if (img.image.empty()) return "";
            std::string ext = img.mimeType == "image/jpeg" ? ".jpg" : img.mimeType == "image/png" ? ".png" : "";
            if (ext.empty() && !img.uri.empty() && img.uri.rfind("data:", 0) != 0)
                ext = std::filesystem::path(img.uri).extension().string();
            imageFiles[size_t(source)] = saveImage(img.image, ext.empty() ? ".png" : ext);
        }
        return imageFiles[size_t(source)];
    };
    for (const tinygltf::Material& mat : m.materials) {
        GltfSceneInfo::Material out;
        out.name = mat.name;
        const auto& pbr = mat.pbrMetallicRoughness;
        if (pbr.baseColorFactor.size() == 4)
            out.baseColor = Vec4(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]), float(pbr.baseColorFactor[2]),
                                 float(pbr.baseColorFactor[3]));
        out.metallic = float(pbr.metallicFactor);
        out.roughness = float(pbr.roughnessFactor);
        out.baseColorTexture = textureFile(pbr.baseColorTexture.index);
        out.metallicRoughnessTexture = textureFile(pbr.metallicRoughnessTexture.index);
        out.normalTexture = textureFile(mat.normalTexture.index);
        out.normalScale = float(mat.normalTexture.scale);
        out.emissive = factor3(mat.emissiveFactor, Vec3(0.f));
        out.emissiveTexture = textureFile(mat.emissiveTexture.index);
        if (auto it = mat.extensions.find("KHR_materials_emissive_strength"); it != mat.extensions.end() &&
                                                                              it->second.Has("emissiveStrength"))
            out.emissive *= float(it->second.Get("emissiveStrength").GetNumberAsDouble());
        if (auto it = mat.extensions.find("KHR_materials_transmission"); it != mat.extensions.end() &&
                                                                         it->second.Has("transmissionFactor"))
            out.transmission = std::clamp(float(it->second.Get("transmissionFactor").GetNumberAsDouble()), 0.f, 1.f);
        // ior 0 is the extension's "no refraction"; bsdf.dielectric needs an index above 1.
        if (auto it = mat.extensions.find("KHR_materials_ior"); it != mat.extensions.end() && it->second.Has("ior"))
            out.ior = std::clamp(float(it->second.Get("ior").GetNumberAsDouble()), 1.0001f, 10.f);
        info.materials.push_back(std::move(out));
    }
    // Walk the instanced node tree: cameras, lights, and which materials triangles use, with world bounds.
    std::vector<char> used(m.materials.size() + 1, 0);  // [0] = no material
    bool any = false;
    std::vector<int> roots = rootNodes(m);
    // Bare meshes without any node are taken untransformed, as the mesh loader does: a node of each, for the walk.
    if (m.nodes.empty() && !m.meshes.empty()) {
        for (size_t i = 0; i < m.meshes.size(); ++i) {
            tinygltf::Node n;
            n.mesh = int(i);
            m.nodes.push_back(n);
            roots.push_back(int(i));
        }
    }
    walkNodes(path, m, roots, [&](int index, const glm::dmat4& M) {
        const tinygltf::Node& node = m.nodes[size_t(index)];
        // GltfChecker has checked every index and value read here.
        if (node.camera >= 0 && m.cameras[size_t(node.camera)].type == "perspective") {
            const auto& pc = m.cameras[size_t(node.camera)].perspective;
            info.cameras.push_back({M, pc.yfov, pc.aspectRatio, m.cameras[size_t(node.camera)].name});
        }
        if (auto it = node.extensions.find("KHR_lights_punctual"); it != node.extensions.end() && it->second.Has("light")) {
            const int li = it->second.Get("light").GetNumberAsInt();
            if (li >= 0 && size_t(li) < m.lights.size()) {
                const tinygltf::Light& l = m.lights[size_t(li)];
                info.lights.push_back({l.type, l.name, factor3(l.color, Vec3(1.f)), l.intensity, l.spot.innerConeAngle,
                                       l.spot.outerConeAngle, M});
            }
        }
        if (node.mesh < 0) return;
        for (const tinygltf::Primitive& prim : m.meshes[size_t(node.mesh)].primitives) {
            if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES) continue;
            const int mat = prim.material >= 0 && size_t(prim.material) < m.materials.size() ? prim.material : -1;
            used[size_t(mat + 1)] = 1;
            auto pos = prim.attributes.find("POSITION");
            if (pos == prim.attributes.end() || pos->second < 0 || size_t(pos->second) >= m.accessors.size()) continue;
            const tinygltf::Accessor& acc = m.accessors[size_t(pos->second)];
            if (acc.minValues.size() != 3 || acc.maxValues.size() != 3) continue;
            for (int c = 0; c < 8; ++c) {  // the accessor's box corners, transformed
                const glm::dvec4 p = M * glm::dvec4(c & 1 ? acc.maxValues[0] : acc.minValues[0],
                                                    c & 2 ? acc.maxValues[1] : acc.minValues[1],
                                                    c & 4 ? acc.maxValues[2] : acc.minValues[2], 1.0);
                if (!isFinite(Vec3(p)))
                    throw GltfValueError(path, "/accessors/" + std::to_string(pos->second) + "/max",
                                         "the POSITION bounds min/max placed by node " + std::to_string(index) +
                                             " are beyond float's range (valid: |x| < 3.4e+38)");
                info.boundsMin = any ? glm::min(info.boundsMin, Vec3(p)) : Vec3(p);
                info.boundsMax = any ? glm::max(info.boundsMax, Vec3(p)) : Vec3(p);
                any = true;
            }
        }
    });
    info.hasBounds = any;
    for (size_t k = 0; k < used.size(); ++k)
        if (used[k]) info.usedMaterials.push_back(int(k) - 1);
    return info;
}

}  // namespace specula::detail
