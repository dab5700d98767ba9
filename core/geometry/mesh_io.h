// Loading triangle meshes from OBJ (tinyobjloader), PLY (ASCII and binary) and glTF 2.0
// (tinygltf, .gltf/.glb), plus UV-based tangent generation applied identically to every format.
#pragma once

#include "core/geometry/mesh.h"

#include <stdexcept>
#include <string>

namespace specula {

struct MeshLoadError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// How shading normals are made for a loaded mesh (the scene's "shading" and "smooth_angle" keys, docs/scene-format.md).
struct MeshShading {
    enum Mode : uint8_t {
        Auto,    // the file's normals; where it has none, smooth by angle (Blender's auto smooth)
        Smooth,  // the file's normals; where it has none, area-weighted vertex normals across every edge
        Flat,    // one normal per triangle, the file's normals ignored (Blender's Shade Flat)
    };
    Mode mode = Auto;
    float smoothAngleDegrees = 30.f;  // Auto: faces meeting at a larger angle keep a crease
};

// A glTF value that the glTF 2.0 specification (or the schema of an extension Specula reads) does not allow, or that
// is beyond Specula's bounds (issue 35): what() is "cannot load mesh '<file>': <pointer>: <reason>", where pointer is
// a JSON pointer into the glTF's JSON ("/cameras/0/perspective/yfov") and reason names the value and its valid range.
// The glTF scene import turns it into an InputError (exit 1) at "<file>#<pointer>".
struct GltfValueError : MeshLoadError {
    GltfValueError(const std::string& file, const std::string& pointer, const std::string& reason);
    std::string file, pointer, reason;
};

const char* attributeSourceName(MeshAttributeSources::Source s);

constexpr int kAllGltfMaterials = -2;  // loadMesh's gltfMaterial: every primitive of a glTF file

// A glTF file's cameras, punctual lights and metallic-roughness materials (glTF's y-up world space), for the scene
// import (core/scene/gltf_scene.h). Textures are files written by the importer.
struct GltfSceneInfo {
    // The imported scene's image: kImageHeight rows and round(kImageHeight x aspectRatio) columns, the camera's
    // aspectRatio being checked to give kMinImageWidth to kMaxImageWidth (gltf_loader.cpp).
    static constexpr int kImageHeight = 540, kMinImageWidth = 16, kMaxImageWidth = 8192;
    struct Camera {
        glm::dmat4 world;
        double yfov = 0.7, aspect = 0.0;  // radians; 0: unspecified
        std::string name;
    };
    struct Light {
        std::string type, name;  // "point", "spot", "directional"
        Vec3 color{1.f};
        double intensity = 1.0;  // candela (point, spot) or lux (directional)
        double innerCone = 0.0, outerCone = 0.7853981633974483;
        glm::dmat4 world;
    };
    struct Material {
        std::string name;
        Vec4 baseColor{1.f};
        float metallic = 1.f, roughness = 1.f, normalScale = 1.f;
        Vec3 emissive{0.f};
        float transmission = 0.f, ior = 1.5f;  // KHR_materials_transmission (factor only), KHR_materials_ior
        std::string baseColorTexture, metallicRoughnessTexture, normalTexture, emissiveTexture;  // "" = none
    };
    std::vector<Material> materials;
    std::vector<int> usedMaterials;  // material indices that triangles use (-1: primitives without a material)
    std::vector<Camera> cameras;
    std::vector<Light> lights;
    bool hasBounds = false;
    Vec3 boundsMin{0.f}, boundsMax{0.f};
};

// Loads every triangle of the file into one object-space mesh (glTF node transforms applied,
// polygons triangulated). Normals follow 'shading'; if the mesh has UVs but no tangents, tangents are computed with
// computeTangents(). Throws MeshLoadError with the path and reason on failure.
TriangleMesh loadMesh(const std::string& path, const MeshShading& shading = {},
                      MeshAttributeSources* sources = nullptr, int gltfMaterial = kAllGltfMaterials);

// Normals by angle for a mesh without them (Blender's Smooth by Angle): edges whose two triangles meet at more than
// 'angleDegrees' are creases (0: flat, 180: smooth everywhere); corners around a position joined by smooth edges share
// the corner-angle-weighted mean normal. Vertices are split where corners disagree; uvs and tangents are carried along.
// Vertices at the same position count as one here, so uv seams do not crease the shading.
void computeAngleNormals(TriangleMesh& mesh, float angleDegrees);

// Per-vertex tangents from UVs (Lengyel's method: accumulate per-triangle dp/du, Gram-Schmidt
// against the vertex normal, handedness in w). Requires uvs; computes area-weighted vertex
// normals first if normals are missing. Degenerate UVs fall back to an arbitrary orthogonal tangent.
void computeTangents(TriangleMesh& mesh);

// Area-weighted per-vertex normals.
void computeVertexNormals(TriangleMesh& mesh);

}  // namespace specula
