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

const char* attributeSourceName(MeshAttributeSources::Source s);

// Loads every triangle of the file into one object-space mesh (glTF node transforms applied,
// polygons triangulated). Normals follow 'shading'; if the mesh has UVs but no tangents, tangents are computed with
// computeTangents(). Throws MeshLoadError with the path and reason on failure.
TriangleMesh loadMesh(const std::string& path, const MeshShading& shading = {},
                      MeshAttributeSources* sources = nullptr);

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
