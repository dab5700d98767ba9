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

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

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
    if (ec || size > kMaxBufferBytes) {
        if (err) *err = "larger than 4 GiB";
        return false;
    }
    std::ifstream in(file, std::ios::binary);
    out->resize(size_t(size));
    if (size > 0 && !in.read(reinterpret_cast<char*>(out->data()), std::streamsize(size))) {
        if (err) *err = "read failed";
        return false;
    }
    return true;
}

std::string expandNothing(const std::string& path, void*) { return path; }  // no ~ or $VAR expansion in URIs

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
        for (const auto& scene : m.scenes) roots.insert(roots.end(), scene.nodes.begin(), scene.nodes.end());
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

class GltfImporter {
public:
    GltfImporter(const std::string& path, const tinygltf::Model& model, int materialFilter)
        : path_(path), m_(model), materialFilter_(materialFilter) {}

    TriangleMesh run() {
        const std::vector<int> roots = rootNodes(m_);
        if (m_.nodes.empty())  // bare meshes, no node tree at all: take them untransformed
            for (size_t i = 0; i < m_.meshes.size(); ++i) addMesh(int(i), glm::dmat4(1.0));
        for (int r : roots) visit(r, glm::dmat4(1.0), 0);
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

public:
    static glm::dmat4 localTransform(const tinygltf::Node& node) {
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

private:

    void visit(int nodeIndex, const glm::dmat4& parent, size_t depth) {
        if (nodeIndex < 0 || size_t(nodeIndex) >= m_.nodes.size())
            throwMeshError(path_, "node index " + std::to_string(nodeIndex) + " out of range");
        if (depth > m_.nodes.size()) throwMeshError(path_, "node hierarchy contains a cycle");
        const tinygltf::Node& node = m_.nodes[size_t(nodeIndex)];
        glm::dmat4 M = parent * localTransform(node);
        if (node.mesh >= 0) addMesh(node.mesh, M);
        for (int c : node.children) visit(c, M, depth + 1);
    }

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
            part.positions.resize(n);
            for (size_t i = 0; i < n; ++i) {
                glm::dvec4 p = M * glm::dvec4(pos.component(i, 0), pos.component(i, 1), pos.component(i, 2), 1.0);
                part.positions[i] = Vec3(p);
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

void loadModel(const std::string& path, bool binary, bool keepImages, tinygltf::Model& model) {
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(keepImages ? &keepImageBytes : &ignoreImage, nullptr);
    BufferAccess access = accessFor(path);
    loader.SetFsCallbacks({&bufferExists, &expandNothing, &readBuffer, nullptr, &access});
    std::string err, warn;
    bool ok = false;
    try {
        ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                    : loader.LoadASCIIFromFile(&model, &err, &warn, path);
    } catch (const std::exception& e) {
        // tinygltf indexes some GLB headers with vector::at (found by fuzz_mesh): a parse error like any other.
        throwMeshError(path, std::string("glTF parse error: ") + e.what());
    }
    if (!ok && !access.refused.empty())
        throwMeshError(path, "a buffer URI leads outside the glTF file's folder; buffers are read only from that folder "
                             "and from the folders listed in SPECULA_RESOURCE_PATH (docs/scene-format.md)");
    if (!ok) throwMeshError(path, "glTF parse error: " + (err.empty() ? std::string("unknown error") : trimmed(err)));
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
    std::vector<std::pair<int, glm::dmat4>> stack;
    for (int r : rootNodes(m)) stack.emplace_back(r, glm::dmat4(1.0));
    // Bare meshes without any node are taken untransformed, as the mesh loader does: a node of each, for the walk.
    if (m.nodes.empty() && !m.meshes.empty()) {
        for (size_t i = 0; i < m.meshes.size(); ++i) {
            tinygltf::Node n;
            n.mesh = int(i);
            m.nodes.push_back(n);
            stack.emplace_back(int(i), glm::dmat4(1.0));
        }
    }
    size_t visits = 0;
    while (!stack.empty()) {
        auto [index, parent] = stack.back();
        stack.pop_back();
        if (index < 0 || size_t(index) >= m.nodes.size()) throwMeshError(path, "node index " + std::to_string(index) + " out of range");
        if (++visits > 4 * m.nodes.size() + 16) throwMeshError(path, "node hierarchy contains a cycle");
        const tinygltf::Node& node = m.nodes[size_t(index)];
        const glm::dmat4 M = parent * GltfImporter::localTransform(node);
        if (node.camera >= 0 && size_t(node.camera) < m.cameras.size() && m.cameras[size_t(node.camera)].type == "perspective") {
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
        if (node.mesh >= 0 && size_t(node.mesh) < m.meshes.size())
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
                    info.boundsMin = any ? glm::min(info.boundsMin, Vec3(p)) : Vec3(p);
                    info.boundsMax = any ? glm::max(info.boundsMax, Vec3(p)) : Vec3(p);
                    any = true;
                }
            }
        for (int c : node.children) stack.emplace_back(c, M);
    }
    info.hasBounds = any;
    for (size_t k = 0; k < used.size(); ++k)
        if (used[k]) info.usedMaterials.push_back(int(k) - 1);
    return info;
}

}  // namespace specula::detail
