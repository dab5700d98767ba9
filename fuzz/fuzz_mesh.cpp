// libFuzzer target: mesh files through loadMesh. The first byte picks the format (OBJ, PLY, glTF, GLB), the rest is the
// file. Only MeshLoadError (a documented, clear error) may leave; anything else or a crash is a finding, and a loaded
// mesh must be consistent (indices in range, finite positions, one normal/uv/tangent per vertex or none).
#include "core/geometry/mesh_io.h"
#include "fuzz/fuzz_common.h"

#include <cmath>
#include <cstdlib>

using namespace specula;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    static const char* kExt[] = {"obj", "ply", "gltf", "glb"};
    const std::string path = fuzz::writeScratch(std::string("mesh.") + kExt[data[0] % 4], data + 1, size - 1);
    try {
        TriangleMesh m = loadMesh(path);
        const size_t nv = m.positions.size();
        for (const auto& t : m.indices)
            if (t.x >= nv || t.y >= nv || t.z >= nv) std::abort();
        for (const auto& p : m.positions)
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) std::abort();
        if ((!m.normals.empty() && m.normals.size() != nv) || (!m.uvs.empty() && m.uvs.size() != nv) ||
            (!m.tangents.empty() && m.tangents.size() != nv))
            std::abort();
    } catch (const MeshLoadError&) {
    }
    return 0;
}
