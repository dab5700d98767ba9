// Mesh loading (OBJ via tinyobjloader, PLY with our own reader, glTF in gltf_loader.cpp) into one
// object-space TriangleMesh, plus area-weighted vertex normals and Lengyel tangent generation.
#include "core/geometry/mesh_io.h"
#include "core/geometry/mesh_io_detail.h"

// Debian's tinyobjloader package ships the compiled library (linked through
// tinyobjloader::tinyobjloader), so TINYOBJLOADER_IMPLEMENTATION must not be defined here.
#include "core/util/input_files.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>

namespace specula {

namespace detail {

void throwMeshError(const std::string& path, const std::string& reason) {
    throw MeshLoadError("cannot load mesh '" + path + "': " + reason);
}

TriangleMesh mergeMeshParts(std::vector<TriangleMesh>& parts) {
    bool anyNormals = false, anyUvs = false, anyTangents = false;
    for (const auto& p : parts) {
        anyNormals |= !p.normals.empty();
        anyUvs |= !p.uvs.empty();
        anyTangents |= !p.tangents.empty();
    }
    TriangleMesh out;
    for (auto& p : parts) {
        if (anyNormals && p.normals.empty()) computeVertexNormals(p);
        if (anyUvs && p.uvs.empty()) p.uvs.assign(p.positions.size(), Vec2(0.f));
        if (anyTangents && p.tangents.empty()) computeTangents(p);
        uint32_t base = uint32_t(out.positions.size());
        out.positions.insert(out.positions.end(), p.positions.begin(), p.positions.end());
        out.normals.insert(out.normals.end(), p.normals.begin(), p.normals.end());
        out.uvs.insert(out.uvs.end(), p.uvs.begin(), p.uvs.end());
        out.tangents.insert(out.tangents.end(), p.tangents.begin(), p.tangents.end());
        for (const auto& t : p.indices) out.indices.push_back(t + glm::uvec3(base));
    }
    return out;
}

}  // namespace detail

namespace {

using detail::throwMeshError;

std::string lowerExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

std::string trimmed(std::string s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
    return s;
}

// ---- OBJ -----------------------------------------------------------------------------------------
// tinyobjloader triangulates polygons (fans) and keeps separate position/normal/uv indices; we weld
// each distinct (position, normal, uv) triple into one vertex, in order of first use. OBJ texture
// coordinates already use the v-up convention. A shape whose faces do not all carry normals (or uvs)
// drops that attribute; mergeMeshParts then completes it if other shapes have it.

struct TripleHash {
    size_t operator()(const std::array<int, 3>& k) const {
        size_t h = std::hash<int>()(k[0]);
        h = h * 1000003u ^ std::hash<int>()(k[1]);
        return h * 1000003u ^ std::hash<int>()(k[2]);
    }
};

// tinyobjloader reads a coordinate it cannot parse ("nan", "abc") as 0 and one that overflows as infinity: both would
// load as a silently wrong mesh (issue 16). The v/vn/vt lines are checked here first, with the line number.
void checkObjNumbers(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    for (size_t lineNo = 1; std::getline(in, line); ++lineNo) {
        size_t at = line.find_first_not_of(" \t");
        if (at == std::string::npos || line[at] != 'v') continue;
        std::istringstream words(line.substr(at));
        std::string tag, word;
        words >> tag;
        if (tag != "v" && tag != "vn" && tag != "vt") continue;
        while (words >> word) {
            if (word[0] == '#') break;
            char* end = nullptr;
            const float x = std::strtof(word.c_str(), &end);  // underflow to 0 or a denormal is fine
            if (end != word.c_str() + word.size() || !std::isfinite(x))
                throwMeshError(path, "line " + std::to_string(lineNo) + ": '" + word + "' in a '" + tag +
                                         "' line is not a finite number");
        }
    }
}

TriangleMesh loadObj(const std::string& path) {
    checkObjNumbers(path);
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    config.mtl_search_path = std::filesystem::path(path).parent_path().string();
    tinyobj::ObjReader reader;
    if (!reader.ParseFromFile(path, config))
        throwMeshError(path, "OBJ parse error: " + (reader.Error().empty() ? "unknown error" : trimmed(reader.Error())));
    const tinyobj::attrib_t& a = reader.GetAttrib();
    const int nPos = int(a.vertices.size() / 3), nNrm = int(a.normals.size() / 3), nTex = int(a.texcoords.size() / 2);

    std::vector<TriangleMesh> parts;
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        const auto& idx = shape.mesh.indices;
        if (idx.empty()) continue;
        bool hasN = nNrm > 0, hasT = nTex > 0;
        for (const auto& i : idx) {
            if (i.vertex_index < 0 || i.vertex_index >= nPos)
                throwMeshError(path, "vertex index " + std::to_string(i.vertex_index + 1) + " out of range (" +
                                         std::to_string(nPos) + " vertices)");
            if (i.normal_index >= nNrm) throwMeshError(path, "normal index out of range");
            if (i.texcoord_index >= nTex) throwMeshError(path, "texture coordinate index out of range");
            hasN &= i.normal_index >= 0;
            hasT &= i.texcoord_index >= 0;
        }
        TriangleMesh part;
        std::unordered_map<std::array<int, 3>, uint32_t, TripleHash> weld;
        std::vector<uint32_t> corner(idx.size());
        for (size_t k = 0; k < idx.size(); ++k) {
            std::array<int, 3> key{idx[k].vertex_index, hasN ? idx[k].normal_index : -1,
                                   hasT ? idx[k].texcoord_index : -1};
            auto [it, inserted] = weld.emplace(key, uint32_t(part.positions.size()));
            if (inserted) {
                size_t v = size_t(key[0]);
                part.positions.emplace_back(a.vertices[3 * v], a.vertices[3 * v + 1], a.vertices[3 * v + 2]);
                if (hasN) {
                    size_t n = size_t(key[1]);
                    Vec3 nn(a.normals[3 * n], a.normals[3 * n + 1], a.normals[3 * n + 2]);
                    float len = glm::length(nn);
                    part.normals.push_back(len > 0 ? nn / len : Vec3(0, 0, 1));
                }
                if (hasT) {
                    size_t t = size_t(key[2]);
                    part.uvs.emplace_back(a.texcoords[2 * t], a.texcoords[2 * t + 1]);
                }
            }
            corner[k] = it->second;
        }
        // Faces are triangles after triangulation; fan any that are not, to be safe.
        size_t offset = 0;
        for (unsigned char fv : shape.mesh.num_face_vertices) {
            for (unsigned k = 2; k < fv; ++k)
                part.indices.emplace_back(corner[offset], corner[offset + k - 1], corner[offset + k]);
            offset += fv;
        }
        if (!part.indices.empty()) parts.push_back(std::move(part));
    }
    if (parts.empty()) throwMeshError(path, "no triangles");
    return detail::mergeMeshParts(parts);
}

// ---- PLY -----------------------------------------------------------------------------------------
// Header grammar (Turk, "The PLY polygon file format"): "ply", "format <ascii|binary_little_endian|
// binary_big_endian> 1.0", then "element <name> <count>" each followed by its "property <type> <name>"
// or "property list <count type> <item type> <name>" lines, ending at "end_header". Elements are
// stored in header order. We read x/y/z, nx/ny/nz and u/v (or s/t, texture_u/texture_v,
// texture_s/texture_t) from "vertex" and the vertex_indices (or vertex_index) list from "face",
// fan-triangulating polygons; every other element and property is parsed and skipped. PLY texture
// coordinates are taken as v-up (what Blender, Meshlab and most exporters write).

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool parsePlyType(const std::string& s, PlyType& t) {
    static const std::pair<const char*, PlyType> names[] = {
        {"char", PlyType::Int8},     {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64}};
    for (const auto& [name, type] : names)
        if (s == name) { t = type; return true; }
    return false;
}

size_t plyTypeSize(PlyType t) {
    switch (t) {
    case PlyType::Int8: case PlyType::UInt8: return 1;
    case PlyType::Int16: case PlyType::UInt16: return 2;
    case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
    }
    return 0;
}

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;
    bool isList = false;
    PlyType countType = PlyType::UInt8;
};

struct PlyElement {
    std::string name;
    size_t count = 0;
    std::vector<PlyProperty> properties;
};

enum class PlyFormat { Ascii, BinaryLittle, BinaryBig };

// Sequential reader of the body, in whichever encoding the header declared.
class PlyBody {
public:
    PlyBody(const std::string& path, const std::string& data, size_t pos, PlyFormat format)
        : path_(path), data_(data), pos_(pos), format_(format) {}

    double read(PlyType t) {
        if (format_ == PlyFormat::Ascii) return readAscii(t);
        size_t n = plyTypeSize(t);
        if (data_.size() - pos_ < n) throwMeshError(path_, "PLY body ends unexpectedly");
        unsigned char b[8];
        std::memcpy(b, data_.data() + pos_, n);
        pos_ += n;
        if (format_ == PlyFormat::BinaryBig ? isLittleEndianHost() : !isLittleEndianHost()) std::reverse(b, b + n);
        switch (t) {
        case PlyType::Int8: return double(int8_t(b[0]));
        case PlyType::UInt8: return double(b[0]);
        case PlyType::Int16: { int16_t v; std::memcpy(&v, b, 2); return v; }
        case PlyType::UInt16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
        case PlyType::Int32: { int32_t v; std::memcpy(&v, b, 4); return v; }
        case PlyType::UInt32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
        case PlyType::Float32: { float v; std::memcpy(&v, b, 4); return v; }
        case PlyType::Float64: { double v; std::memcpy(&v, b, 8); return v; }
        }
        return 0.0;
    }
    size_t remaining() const { return data_.size() - pos_; }

private:
    static bool isLittleEndianHost() {
        const uint16_t one = 1;
        unsigned char c;
        std::memcpy(&c, &one, 1);
        return c == 1;
    }
    double readAscii(PlyType t) {
        while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
        if (pos_ >= data_.size()) throwMeshError(path_, "PLY body ends unexpectedly");
        const char* begin = data_.c_str() + pos_;
        char* end = nullptr;
        errno = 0;
        double v = std::strtod(begin, &end);
        if (end == begin || (*end != '\0' && !std::isspace(static_cast<unsigned char>(*end))))
            throwMeshError(path_, "PLY: malformed number near byte " + std::to_string(pos_));
        pos_ += size_t(end - begin);
        (void)t;
        return v;
    }

    const std::string& path_;
    const std::string& data_;
    size_t pos_;
    PlyFormat format_;
};

std::string readWholeFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throwMeshError(path, "cannot open file");
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

TriangleMesh loadPly(const std::string& path) {
    const std::string data = readWholeFile(path);
    // Header: lines up to and including "end_header".
    size_t pos = 0;
    auto nextLine = [&](std::string& line) {
        if (pos >= data.size()) return false;
        size_t eol = data.find('\n', pos);
        if (eol == std::string::npos) eol = data.size();
        line = data.substr(pos, eol - pos);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        pos = std::min(data.size(), eol + 1);
        return true;
    };
    std::string line;
    if (!nextLine(line) || trimmed(line) != "ply") throwMeshError(path, "not a PLY file (missing 'ply' magic)");
    PlyFormat format = PlyFormat::Ascii;
    bool haveFormat = false, haveEnd = false;
    std::vector<PlyElement> elements;
    while (nextLine(line)) {
        std::istringstream ls(line);
        std::string kw;
        ls >> kw;
        if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
        if (kw == "end_header") { haveEnd = true; break; }
        if (kw == "format") {
            std::string f;
            ls >> f;
            if (f == "ascii") format = PlyFormat::Ascii;
            else if (f == "binary_little_endian") format = PlyFormat::BinaryLittle;
            else if (f == "binary_big_endian") format = PlyFormat::BinaryBig;
            else throwMeshError(path, "PLY: unknown format '" + f + "'");
            haveFormat = true;
        } else if (kw == "element") {
            PlyElement e;
            long long count = -1;
            ls >> e.name >> count;
            if (!ls || count < 0) throwMeshError(path, "PLY: malformed element line '" + line + "'");
            e.count = size_t(count);
            elements.push_back(e);
        } else if (kw == "property") {
            if (elements.empty()) throwMeshError(path, "PLY: property before any element");
            PlyProperty p;
            std::string t1;
            ls >> t1;
            if (t1 == "list") {
                std::string tc, ti;
                ls >> tc >> ti >> p.name;
                p.isList = true;
                if (!parsePlyType(tc, p.countType) || !parsePlyType(ti, p.type))
                    throwMeshError(path, "PLY: unknown list type in '" + line + "'");
            } else {
                ls >> p.name;
                if (!parsePlyType(t1, p.type)) throwMeshError(path, "PLY: unknown property type '" + t1 + "'");
            }
            if (p.name.empty()) throwMeshError(path, "PLY: malformed property line '" + line + "'");
            elements.back().properties.push_back(p);
        } else {
            throwMeshError(path, "PLY: unexpected header line '" + line + "'");
        }
    }
    if (!haveFormat || !haveEnd) throwMeshError(path, "PLY: incomplete header");

    PlyBody body(path, data, pos, format);
    TriangleMesh mesh;  // faces are fanned straight into mesh.indices; finalizeMesh checks index range
    bool haveVertices = false;
    for (const PlyElement& e : elements) {
        const size_t np = e.properties.size();
        auto find = [&](std::initializer_list<const char*> names) {
            for (const char* n : names)
                for (size_t i = 0; i < np; ++i)
                    if (!e.properties[i].isList && e.properties[i].name == n) return int(i);
            return -1;
        };
        int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1, iu = -1, iv = -1, iface = -1;
        bool isVertex = e.name == "vertex" && !haveVertices, isFace = e.name == "face";
        if (isVertex) {
            haveVertices = true;
            ix = find({"x"}), iy = find({"y"}), iz = find({"z"});
            if (ix < 0 || iy < 0 || iz < 0) throwMeshError(path, "PLY: vertex element lacks x, y or z");
            inx = find({"nx"}), iny = find({"ny"}), inz = find({"nz"});
            if (inx < 0 || iny < 0 || inz < 0) inx = -1;
            const std::pair<const char*, const char*> uvNames[] = {
                {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
            for (const auto& [un, vn] : uvNames) {
                iu = find({un}), iv = find({vn});
                if (iu >= 0 && iv >= 0) break;
            }
            if (iu < 0 || iv < 0) iu = -1;
            // Do not trust the header's count for the allocation: a vertex needs at least 1 byte/token.
            size_t n = std::min(e.count, body.remaining());
            mesh.positions.reserve(n);
        }
        if (isFace) {
            for (size_t i = 0; i < np; ++i)
                if (e.properties[i].isList &&
                    (e.properties[i].name == "vertex_indices" || e.properties[i].name == "vertex_index")) {
                    iface = int(i);
                    break;
                }
            if (iface < 0) throwMeshError(path, "PLY: face element lacks a vertex_indices list");
        }
        std::vector<double> values(np, 0.0);
        std::vector<uint32_t> poly;
        for (size_t k = 0; k < e.count; ++k) {
            for (size_t i = 0; i < np; ++i) {
                const PlyProperty& p = e.properties[i];
                if (!p.isList) {
                    values[i] = body.read(p.type);
                    continue;
                }
                double c = body.read(p.countType);
                if (!(c >= 0) || c != std::floor(c))
                    throwMeshError(path, "PLY: invalid list length " + std::to_string(c));
                if (c > double(body.remaining())) {  // every item takes at least one byte (or character)
                    // Printed from the double: a count beyond size_t (an ASCII 1e54) must not be cast to it.
                    char items[64];
                    std::snprintf(items, sizeof items, "%.0f", c);
                    throwMeshError(path, std::string("PLY body ends unexpectedly (list of ") + items + " items)");
                }
                size_t count = size_t(c);
                if (int(i) == iface) poly.clear();
                for (size_t j = 0; j < count; ++j) {
                    double x = body.read(p.type);
                    if (int(i) == iface) {
                        if (!(x >= 0) || x > 4294967295.0)
                            throwMeshError(path, "vertex index " +
                                                     (std::isfinite(x) ? std::to_string((long long)x) : "nan") +
                                                     " out of range");
                        poly.push_back(uint32_t(x));
                    }
                }
            }
            if (isVertex) {
                mesh.positions.emplace_back(values[size_t(ix)], values[size_t(iy)], values[size_t(iz)]);
                if (inx >= 0) {
                    Vec3 n(values[size_t(inx)], values[size_t(iny)], values[size_t(inz)]);
                    float len = glm::length(n);
                    mesh.normals.push_back(len > 0 ? n / len : Vec3(0, 0, 1));
                }
                if (iu >= 0) mesh.uvs.emplace_back(values[size_t(iu)], values[size_t(iv)]);
            } else if (isFace) {
                for (size_t j = 2; j < poly.size(); ++j) mesh.indices.emplace_back(poly[0], poly[j - 1], poly[j]);
            }
        }
    }
    if (!haveVertices) throwMeshError(path, "PLY: no vertex element");
    return mesh;
}

// Final checks and attribute completion shared by all formats.
void finalizeMesh(TriangleMesh& mesh, const std::string& path) {
    if (mesh.indices.empty()) throwMeshError(path, "no triangles");
    const size_t n = mesh.positions.size();
    for (const auto& t : mesh.indices)
        for (int k = 0; k < 3; ++k)
            if (t[k] >= n)
                throwMeshError(path, "vertex index " + std::to_string(t[k]) + " out of range (" + std::to_string(n) +
                                         " vertices)");
    for (const auto& p : mesh.positions)
        if (!isFinite(p)) throwMeshError(path, "non-finite vertex position");
}

// Normals by the scene's shading mode (MeshShading), then tangents from uvs where the file has none: tangents are
// relative to the shading normal, so they are made after it.
void completeAttributes(TriangleMesh& mesh, const MeshShading& shading, MeshAttributeSources& src) {
    src.normals = mesh.normals.empty() ? MeshAttributeSources::None : MeshAttributeSources::File;
    src.uvs = mesh.uvs.empty() ? MeshAttributeSources::None : MeshAttributeSources::File;
    src.tangents = mesh.tangents.empty() ? MeshAttributeSources::None : MeshAttributeSources::File;
    if (shading.mode == MeshShading::Flat) {
        // The file's tangents belong to its (smooth) normals: remade below from the uvs.
        mesh.normals.clear();
        mesh.tangents.clear();
        src.tangents = MeshAttributeSources::None;
        computeAngleNormals(mesh, 0.f);
        src.normals = MeshAttributeSources::Computed;
    } else if (mesh.normals.empty()) {
        computeAngleNormals(mesh, shading.mode == MeshShading::Smooth ? 180.f : shading.smoothAngleDegrees);
        src.normals = MeshAttributeSources::Computed;
    }
    if (!mesh.uvs.empty() && mesh.tangents.empty()) {
        computeTangents(mesh);
        src.tangents = MeshAttributeSources::Computed;
    }
}

// Hash of a position's exact bits: vertices at one position share their normal whatever their uvs.
struct PositionKey {
    uint32_t x, y, z;
    bool operator==(const PositionKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct PositionKeyHash {
    size_t operator()(const PositionKey& k) const {
        uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
        h ^= (h >> 29) + k.y * 0xBF58476D1CE4E5B9ull;
        h ^= (h >> 31) + k.z * 0x94D049BB133111EBull;
        return size_t(h ^ (h >> 32));
    }
};
PositionKey positionKey(const Vec3& p) {
    PositionKey k;
    const Vec3 q = p + Vec3(0.f);  // -0 and +0 are one position
    std::memcpy(&k.x, &q.x, 4);
    std::memcpy(&k.y, &q.y, 4);
    std::memcpy(&k.z, &q.z, 4);
    return k;
}

}  // namespace

const char* attributeSourceName(MeshAttributeSources::Source s) {
    switch (s) {
        case MeshAttributeSources::File: return "from the file";
        case MeshAttributeSources::Computed: return "computed";
        default: return "none";
    }
}

TriangleMesh loadMesh(const std::string& path, const MeshShading& shading, MeshAttributeSources* sources, int gltfMaterial) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throwMeshError(path, "file not found");
    if (!std::filesystem::is_regular_file(path, ec)) throwMeshError(path, "not a regular file");
    noteInputFile(path);  // no output of this command may replace it (core/util/input_files.h)
    const std::string ext = lowerExtension(path);
    TriangleMesh mesh;
    if (ext == ".obj")
        mesh = loadObj(path);
    else if (ext == ".ply")
        mesh = loadPly(path);
    else if (ext == ".gltf")
        mesh = detail::loadGltfMesh(path, false, gltfMaterial);
    else if (ext == ".glb")
        mesh = detail::loadGltfMesh(path, true, gltfMaterial);
    else
        throwMeshError(path, "unknown mesh extension '" + ext + "' (expected .obj, .ply, .gltf or .glb)");
    if (gltfMaterial != kAllGltfMaterials && ext != ".gltf" && ext != ".glb")
        throwMeshError(path, "a glTF material selection needs a .gltf or .glb file");
    finalizeMesh(mesh, path);
    MeshAttributeSources src;
    completeAttributes(mesh, shading, src);
    if (sources) *sources = src;
    return mesh;
}

// Auto smooth (Blender's "Smooth by Angle"): an edge between two triangles whose normals differ by more than the
// angle is sharp, as is an edge of one or of three and more triangles. Around each vertex position the corners that
// are connected across smooth edges form one fan and share one normal: the mean of the fan's face normals weighted
// by the corner angles (Thürmer & Wüthrich 1998, so a cube corner's normal is its diagonal however its faces are
// triangulated). 180 degrees (Smooth) takes every triangle around the position. Union-find over corners: linear time.
void computeAngleNormals(TriangleMesh& mesh, float angleDegrees) {
    const size_t nv = mesh.positions.size(), nt = mesh.indices.size();
    for (const auto& t : mesh.indices)
        if (t.x >= nv || t.y >= nv || t.z >= nv) throw std::out_of_range("computeAngleNormals: index out of range");
    std::unordered_map<PositionKey, uint32_t, PositionKeyHash> ids;
    ids.reserve(nv);
    std::vector<uint32_t> posId(nv);
    for (size_t i = 0; i < nv; ++i) posId[i] = ids.emplace(positionKey(mesh.positions[i]), uint32_t(ids.size())).first->second;
    auto pid = [&](size_t f, int k) { return posId[mesh.indices[f][k]]; };
    // Unit face normals and the angle-weighted normal of each corner (corner c = 3 f + k).
    std::vector<DVec3> faceU(nt), cornerW(3 * nt);
    for (size_t f = 0; f < nt; ++f) {
        const auto& t = mesh.indices[f];
        const DVec3 p[3] = {DVec3(mesh.positions[t.x]), DVec3(mesh.positions[t.y]), DVec3(mesh.positions[t.z])};
        const DVec3 fn = glm::cross(p[1] - p[0], p[2] - p[0]);
        const double len = glm::length(fn);
        faceU[f] = len > 0 && std::isfinite(len) ? fn / len : DVec3(0.0);
        for (int k = 0; k < 3; ++k) {
            const DVec3 a = p[(k + 1) % 3] - p[k], b = p[(k + 2) % 3] - p[k];
            const double la = glm::length(a), lb = glm::length(b);
            const double angle = la > 0 && lb > 0 ? std::acos(std::clamp(glm::dot(a, b) / (la * lb), -1.0, 1.0)) : 0.0;
            cornerW[3 * f + k] = faceU[f] * angle;
        }
    }
    std::vector<uint32_t> parent(3 * nt);
    for (size_t c = 0; c < parent.size(); ++c) parent[c] = uint32_t(c);
    auto find = [&](uint32_t c) {
        while (parent[c] != c) c = parent[c] = parent[parent[c]];
        return c;
    };
    auto unite = [&](uint32_t a, uint32_t b) {
        a = find(a), b = find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the smaller root: independent of visiting order
    };
    if (angleDegrees >= 180.f) {
        // Smooth: every corner at a position joins the first corner seen there.
        std::vector<uint32_t> firstCorner(ids.size(), UINT32_MAX);
        for (size_t c = 0; c < 3 * nt; ++c) {
            uint32_t& fc = firstCorner[pid(c / 3, int(c % 3))];
            if (fc == UINT32_MAX) fc = uint32_t(c);
            else unite(fc, uint32_t(c));
        }
    } else {
        // Edges by their two position ids; the triangles on each (up to two kept, a third marks it non-manifold).
        struct EdgeFaces {
            uint32_t face[2];
            uint8_t count = 0;
        };
        struct EdgeHash {
            size_t operator()(uint64_t k) const { return size_t(k * 0x9E3779B97F4A7C15ull >> 17); }
        };
        std::unordered_map<uint64_t, EdgeFaces, EdgeHash> edges;
        edges.reserve(3 * nt / 2 + 1);
        auto edgeKey = [](uint32_t a, uint32_t b) { return (uint64_t(std::min(a, b)) << 32) | std::max(a, b); };
        for (size_t f = 0; f < nt; ++f)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = pid(f, k), b = pid(f, (k + 1) % 3);
                if (a == b) continue;  // a collapsed edge joins nothing
                EdgeFaces& e = edges[edgeKey(a, b)];
                if (e.count < 2) e.face[e.count] = uint32_t(f);
                e.count = uint8_t(std::min(3, e.count + 1));
            }
        const double cosLimit = std::cos(double(angleDegrees) * 3.14159265358979323846 / 180.0) - 1e-9;
        auto cornerAt = [&](uint32_t f, uint32_t position) {
            for (int k = 0; k < 3; ++k)
                if (pid(f, k) == position) return 3 * f + uint32_t(k);
            return UINT32_MAX;
        };
        for (const auto& [key, e] : edges) {
            if (e.count != 2) continue;
            const uint32_t f = e.face[0], g = e.face[1];
            if (faceU[f] == DVec3(0.0) || faceU[g] == DVec3(0.0) || glm::dot(faceU[f], faceU[g]) < cosLimit) continue;
            for (uint32_t position : {uint32_t(key >> 32), uint32_t(key & 0xFFFFFFFFu)}) unite(cornerAt(f, position), cornerAt(g, position));
        }
    }
    // Each fan's normal; a fan of degenerate triangles takes the position's smooth normal, then +z.
    std::vector<DVec3> fanSum(3 * nt, DVec3(0.0)), positionSum(ids.size(), DVec3(0.0));
    for (size_t c = 0; c < 3 * nt; ++c) {
        fanSum[find(uint32_t(c))] += cornerW[c];
        positionSum[pid(c / 3, int(c % 3))] += cornerW[c];
    }
    auto unit = [](const DVec3& v, Vec3& out) {
        const double len = glm::length(v);
        if (!(len > 1e-300) || !std::isfinite(len)) return false;
        out = Vec3(v / len);
        return true;
    };
    // New vertices: one per (old vertex, fan normal).
    struct CornerKey {
        uint32_t vertex;
        PositionKey normal;
        bool operator==(const CornerKey& o) const { return vertex == o.vertex && normal == o.normal; }
    };
    struct CornerKeyHash {
        size_t operator()(const CornerKey& k) const { return PositionKeyHash()(k.normal) ^ (size_t(k.vertex) * 0x9E3779B1u); }
    };
    std::unordered_map<CornerKey, uint32_t, CornerKeyHash> corners;
    corners.reserve(nv);
    TriangleMesh out;
    out.indices.resize(nt);
    const bool hasUv = mesh.uvs.size() == nv, hasTangent = mesh.tangents.size() == nv;
    for (size_t f = 0; f < nt; ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = mesh.indices[f][k];
            Vec3 n(0, 0, 1);
            if (!unit(fanSum[find(uint32_t(3 * f + k))], n)) unit(positionSum[posId[v]], n);
            auto [it, added] = corners.emplace(CornerKey{v, positionKey(n)}, uint32_t(out.positions.size()));
            if (added) {
                out.positions.push_back(mesh.positions[v]);
                out.normals.push_back(n);
                if (hasUv) out.uvs.push_back(mesh.uvs[v]);
                if (hasTangent) out.tangents.push_back(mesh.tangents[v]);
            }
            out.indices[f][k] = it->second;
        }
    mesh = std::move(out);
}

// Area-weighted vertex normals: the unnormalised face normal cross(p1-p0, p2-p0) has length twice the
// triangle area, so summing it weights each face by area. Vertices touching only degenerate
// triangles (or none) get +z.
void computeVertexNormals(TriangleMesh& mesh) {
    const size_t n = mesh.positions.size();
    std::vector<DVec3> acc(n, DVec3(0.0));
    for (const auto& t : mesh.indices) {
        if (t.x >= n || t.y >= n || t.z >= n) throw std::out_of_range("computeVertexNormals: index out of range");
        DVec3 p0(mesh.positions[t.x]), p1(mesh.positions[t.y]), p2(mesh.positions[t.z]);
        DVec3 fn = glm::cross(p1 - p0, p2 - p0);
        acc[t.x] += fn;
        acc[t.y] += fn;
        acc[t.z] += fn;
    }
    mesh.normals.resize(n);
    for (size_t i = 0; i < n; ++i) {
        double len = glm::length(acc[i]);
        mesh.normals[i] = len > 0 ? Vec3(acc[i] / len) : Vec3(0, 0, 1);
    }
}

// Lengyel, "Computing Tangent Space Basis Vectors for an Arbitrary Mesh" (2001): per triangle with
// edges e1 = p1-p0, e2 = p2-p0 and uv deltas (du1,dv1), (du2,dv2), r = du1 dv2 - du2 dv1,
//   dp/du = (dv2 e1 - dv1 e2) / r,   dp/dv = (du1 e2 - du2 e1) / r.
// We accumulate their directions weighted by triangle area (so slivers with near-singular uv
// mappings cannot dominate), Gram-Schmidt the dp/du sum against the vertex normal and set
// w = sign(dot(cross(n, t), sum dp/dv)). Vertices with no usable uv gradient (or a mesh without
// uvs) get Frame::fromNormal(n).t and w = +1.
void computeTangents(TriangleMesh& mesh) {
    const size_t n = mesh.positions.size();
    if (mesh.normals.size() != n) computeVertexNormals(mesh);
    const bool hasUv = mesh.uvs.size() == n;
    std::vector<DVec3> sumU(n, DVec3(0.0)), sumV(n, DVec3(0.0));
    std::vector<double> weight(n, 0.0);
    if (hasUv) {
        for (const auto& t : mesh.indices) {
            if (t.x >= n || t.y >= n || t.z >= n) throw std::out_of_range("computeTangents: index out of range");
            DVec3 p0(mesh.positions[t.x]), p1(mesh.positions[t.y]), p2(mesh.positions[t.z]);
            glm::dvec2 w0(mesh.uvs[t.x]), w1(mesh.uvs[t.y]), w2(mesh.uvs[t.z]);
            DVec3 e1 = p1 - p0, e2 = p2 - p0;
            glm::dvec2 d1 = w1 - w0, d2 = w2 - w0;
            double r = d1.x * d2.y - d2.x * d1.y;
            double area = 0.5 * glm::length(glm::cross(e1, e2));
            if (!(std::abs(r) > 1e-20) || !(area > 0)) continue;
            DVec3 dpdu = (e1 * d2.y - e2 * d1.y) / r;
            DVec3 dpdv = (e2 * d1.x - e1 * d2.x) / r;
            double lu = glm::length(dpdu), lv = glm::length(dpdv);
            if (!(lu > 0) || !(lv > 0) || !std::isfinite(lu) || !std::isfinite(lv)) continue;
            for (uint32_t v : {t.x, t.y, t.z}) {
                sumU[v] += dpdu * (area / lu);
                sumV[v] += dpdv * (area / lv);
                weight[v] += area;
            }
        }
    }
    mesh.tangents.resize(n);
    for (size_t i = 0; i < n; ++i) {
        DVec3 nn(mesh.normals[i]);
        double nl = glm::length(nn);
        nn = nl > 0 ? nn / nl : DVec3(0, 0, 1);
        DVec3 t = sumU[i] - nn * glm::dot(nn, sumU[i]);
        double tl = glm::length(t);
        if (weight[i] > 0 && tl > 1e-6 * weight[i]) {
            t /= tl;
            double w = glm::dot(glm::cross(nn, t), sumV[i]) < 0 ? -1.0 : 1.0;
            mesh.tangents[i] = Vec4(Vec3(t), float(w));
        } else {
            mesh.tangents[i] = Vec4(Frame::fromNormal(Vec3(nn)).t, 1.f);
        }
    }
}

}  // namespace specula
