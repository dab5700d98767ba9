// Internal helpers shared by the mesh loaders (mesh_io.cpp, gltf_loader.cpp): error reporting,
// merging per-part meshes with differing attribute sets, and the glTF entry point.
#pragma once

#include "core/geometry/mesh_io.h"

#include <functional>
#include <string>
#include <vector>

namespace specula::detail {

// Throws MeshLoadError("cannot load mesh '<path>': <reason>").
[[noreturn]] void throwMeshError(const std::string& path, const std::string& reason);

// Concatenates parts (each with valid indices) into one mesh. An attribute present in some parts
// but not others is completed per part: normals area-weighted, uvs zero, tangents via computeTangents.
TriangleMesh mergeMeshParts(std::vector<TriangleMesh>& parts);

// glTF 2.0 (.gltf with embedded or external buffers, or .glb); throws MeshLoadError. materialFilter: only the
// primitives of that material index (-1: those without one), kAllGltfMaterials: every primitive.
TriangleMesh loadGltfMesh(const std::string& path, bool binary, int materialFilter = kAllGltfMaterials);

// What a glTF file holds besides geometry, in glTF's own (y-up) world space: the scene import's input
// (core/scene/gltf_scene.cpp). saveImage(encoded bytes, ".png"/".jpg") writes one image and returns its path.
GltfSceneInfo describeGltfScene(const std::string& path, bool binary,
                                const std::function<std::string(const std::vector<unsigned char>&, const std::string&)>& saveImage);

}  // namespace specula::detail
