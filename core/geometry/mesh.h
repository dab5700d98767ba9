// Triangle meshes as the renderer consumes them, and the analytic-surface hook that built-in
// shapes use to give exact UVs, normals and tangents at a hit on their tessellation.
#pragma once

#include "core/math/math.h"

#include <memory>
#include <string>
#include <vector>

namespace specula {

// Object-space triangle mesh. Optional attribute arrays are either empty or sized like positions.
struct TriangleMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;    // per-vertex shading normals (empty: flat shading)
    std::vector<Vec4> tangents;   // xyz = unit tangent along +u, w = handedness sign of the bitangent (+v)
    std::vector<Vec2> uvs;        // per-vertex texture coordinates
    std::vector<glm::uvec3> indices;

    size_t triangleCount() const { return indices.size(); }
};

// Where each vertex attribute of a loaded mesh came from (`specula info`, the loader's warnings).
struct MeshAttributeSources {
    enum Source : uint8_t { None, File, Computed };
    Source normals = None, uvs = None, tangents = None;
};

// Exact differential geometry of a parametric surface (object space).
struct SurfaceGeometry {
    Vec3 p;           // point on the exact surface
    Vec3 n;           // unit outward normal
    Vec2 uv;          // surface parameters in [0,1]^2
    Vec3 dpdu, dpdv;  // position partials
    Vec3 dndu, dndv;  // normal partials (Weingarten equations)
};

// A built-in shape knows its exact surface; hits on its tessellation are projected onto it so that
// UVs, tangents, normals and their derivatives are exact and continuous across triangle edges.
class AnalyticSurface {
public:
    virtual ~AnalyticSurface() = default;
    // pObject: a point on (or very near) the tessellation, in object space.
    virtual SurfaceGeometry at(const Vec3& pObject) const = 0;
    // Closest point and unit normal only (no parameters or derivatives): what hit refinement needs.
    virtual void closest(const Vec3& pObject, Vec3& p, Vec3& n) const {
        SurfaceGeometry g = at(pObject);
        p = g.p;
        n = g.n;
    }
    // Planar surfaces coincide with their tessellation, so hits need no refinement onto the surface.
    virtual bool isPlanar() const { return false; }
};

struct BuiltinShape {
    TriangleMesh mesh;
    std::shared_ptr<const AnalyticSurface> surface;  // null for meshes loaded from files
};

}  // namespace specula
