// Internal helpers shared by the mesh loaders (mesh_io.cpp, gltf_loader.cpp): error reporting,
// merging per-part meshes with differing attribute sets, and the glTF entry point.
#pragma once

#include "core/geometry/mesh_io.h"

#include <string>
#include <vector>

namespace specula::detail {

// Throws MeshLoadError("cannot load mesh '<path>': <reason>").
[[noreturn]] void throwMeshError(const std::string& path, const std::string& reason);

// Concatenates parts (each with valid indices) into one mesh. An attribute present in some parts
// but not others is completed per part: normals area-weighted, uvs zero, tangents via computeTangents.
TriangleMesh mergeMeshParts(std::vector<TriangleMesh>& parts);

// glTF 2.0 (.gltf with embedded or external buffers, or .glb); throws MeshLoadError.
TriangleMesh loadGltfMesh(const std::string& path, bool binary);

}  // namespace specula::detail
