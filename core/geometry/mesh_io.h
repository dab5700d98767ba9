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

// Loads every triangle of the file into one object-space mesh (glTF node transforms applied,
// polygons triangulated). If the file has UVs but no tangents, tangents are computed with
// computeTangents(). Throws MeshLoadError with the path and reason on failure.
TriangleMesh loadMesh(const std::string& path);

// Per-vertex tangents from UVs (Lengyel's method: accumulate per-triangle dp/du, Gram-Schmidt
// against the vertex normal, handedness in w). Requires uvs; computes area-weighted vertex
// normals first if normals are missing. Degenerate UVs fall back to an arbitrary orthogonal tangent.
void computeTangents(TriangleMesh& mesh);

// Area-weighted per-vertex normals.
void computeVertexNormals(TriangleMesh& mesh);

}  // namespace specula
