// Position-normal manifold of a normal map (Wu et al. 2024, issue 12 slice 1): the texel grid triangulated into
// affine position->projected-normal triangles with Jacobian clamping, the min-max quadtree and the cluster hierarchy.
//
// Spec: shared/specs/pndf-manifold.md §1 (texture space, vertices at integer corners, periodic wrap), §2.1
// (anti-diagonal split), §2.2 (Jacobian), §2.3 (equilateral replacement, ε_J), §3.1 (min-max levels). Paper
// (shared/seeds/wu2024-position-normal-manifold-glints.txt) Sec. 4.1: mesh-based manifold, the Jacobian as twice the
// normal-triangle area, and the replacement of near-singular triangles; Fig. 5a: the min-max hierarchy.
// Cluster hierarchy (spec §3.2, paper Eq. 7): least-squares cluster corner normals per 2^ℓ block with weights
// 1/max(|J_T|, ε_J) and the true fit residual in float64 (the spec's recommended fix), levels 1..5.
// Memory (issue 12 item 2): level-0 bounds are recomputed, not stored; at 1024² the structures are 26.55 MB (normals
// 8.39, bounds levels 1..8 5.59, clusters levels 1..5 12.57) against the paper's 34 MB.
#pragma once

#include "core/math/math.h"

#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

namespace specula::pndf {

// Spec §2.3: the clamp on |J| (twice the normal-triangle area per unit texel parameter, in s-units²/texel²).
constexpr double kDefaultJacobianClamp = 1e-6;

// A 2D vector in double: the hit test and kernel weights are evaluated in double so that the hierarchy and the
// brute force scan (which share this code) agree to round-off, and float32 storage error stays the only error.
struct Vec2d {
    double x = 0, y = 0;
};

// One triangle of the manifold as the affine map of spec §2.1/§2.3, parametrised by (t1, t2) with t1, t2 >= 0,
// t1 + t2 <= 1:   s = sOrigin + t1·sEdge1 + t2·sEdge2   and   x = xOrigin + t1·xStep1 + t2·xStep2.
// For T⁺ (a, b, d): sOrigin = a, edges b-a and d-a, xOrigin = (c, r), steps (+1,0), (0,+1).
// For T⁻ (d, b, e): sOrigin = e, edges d-e and b-e (weights α = 1-ξ of d and β = 1-η of b), xOrigin = (c+1, r+1),
// steps (-1,0), (0,-1). A replaced (equilateral) triangle keeps the same x parametrisation, so it keeps the
// kernel mass of its texel half-cell (spec §2.3: normalisation is preserved).
struct ManifoldTriangle {
    Vec2d sOrigin, sEdge1, sEdge2;
    Vec2d xOrigin, xStep1, xStep2;
    double jacobian = 0;   // signed cross(sEdge1, sEdge2); |jacobian| >= ε_J after clamping
    double xArea = 1;      // |cross(xStep1, xStep2)|: 1 for a texel triangle, 4^ℓ for a level-ℓ cluster triangle
    bool replaced = false; // true when the original |J| < ε_J and the equilateral triangle E is used
};

// Axis-aligned bounds in projected-normal space, (min_x, min_y, max_x, max_y) as in spec §3.1.
struct NormalBounds {
    float minX, minY, maxX, maxY;
    bool contains(double sx, double sy) const { return sx >= minX && sx <= maxX && sy >= minY && sy <= maxY; }
};

// One node of the cluster hierarchy (spec §3.2): 9 floats, the residual and the four corner normals of the block,
// a = node-local (0,0), b = (1,0), d = (0,1), e = (1,1), triangulated along the anti-diagonal like a cell.
struct ClusterNode {
    float residual;
    Vec2 a, b, d, e;
};

class PndfManifold {
public:
    // Builds the manifold from width x height unit normals, row-major (row r = texture v = y, column c = u = x),
    // in the local shading frame. The projected normal is s = (n_x, n_y) of the normalised input (spec §1:
    // "channels R,G are used directly as s"; normalising first makes slightly non-unit decoded maps consistent
    // with m(s) = (s, sqrt(1-|s|²))). Throws std::invalid_argument for an empty map or a size mismatch.
    // buildClusters = false skips the cluster fit (spec §3.2), leaving only the min-max levels.
    PndfManifold(const std::vector<Vec3>& normals, int width, int height,
                 double jacobianClamp = kDefaultJacobianClamp, bool buildClusters = true);

    int width() const { return width_; }
    int height() const { return height_; }
    double jacobianClamp() const { return jacobianClamp_; }

    // Projected normal of vertex (row, col), wrapped periodically (spec §1: indexing wraps modulo N).
    Vec2 vertex(int row, int col) const {
        return projected_[static_cast<size_t>(wrap(row, height_)) * width_ + wrap(col, width_)];
    }

    // The two triangles of cell (row, col), with row/col *unwrapped* (any integer): positions x are reported in
    // unwrapped texel coordinates so that a footprint crossing the seam sees a continuous periodic tiling.
    // out[0] = T⁺ (upper, ξ+η < 1), out[1] = T⁻ (lower).
    void cellTriangles(int row, int col, ManifoldTriangle out[2]) const;

    // Min-max quadtree (spec §3.1), level 0 = one AABB per cell over its 4 corners plus any replacement vertices;
    // level ℓ = 2x2 min/max pool of level ℓ-1. Levels exist while width and height are both divisible by 2^ℓ
    // (so every node maps to whole cells under periodic wrap), up to level kMaxLevel.
    static constexpr int kMaxLevel = 8;
    int levelCount() const { return static_cast<int>(levels_.size()); }
    int levelWidth(int level) const { return width_ >> level; }
    int levelHeight(int level) const { return height_ >> level; }
    // Bounds of node (row, col) of a level, row/col unwrapped. Level 0 is not stored (issue 12 item 2: it would be
    // 16 bytes per texel, half of the structures at 1024²); it is recomputed from the cell's corners exactly as the
    // build pooled it, so every level >= 1 is still the min/max pool of these values.
    NormalBounds bounds(int level, int row, int col) const {
        if (level == 0) return cellBounds(row, col);
        int w = levelWidth(level), h = levelHeight(level);
        return levels_[level][static_cast<size_t>(wrap(row, h)) * w + wrap(col, w)];
    }
    // Level-0 bounds of cell (row, col): its two triangles' vertices (the replacement vertices for a replaced one),
    // rounded outward by one float ulp.
    NormalBounds cellBounds(int row, int col) const;
    // Conservative level-0 cull for the traversal (cheaper than cellBounds: no triangle set-up): false only when
    // s lies outside the AABB of the 4 corners grown to cover the equilateral triangle around b (radius R, spec
    // §2.3) plus a 1e-6 margin, which contains cellBounds. So culling with it never drops a hit.
    bool cellMayContain(int row, int col, double sx, double sy) const {
        const int r0 = wrap(row, height_), r1 = r0 + 1 == height_ ? 0 : r0 + 1;
        const int c0 = wrap(col, width_), c1 = c0 + 1 == width_ ? 0 : c0 + 1;
        const Vec2* p0 = &projected_[static_cast<size_t>(r0) * width_];
        const Vec2* p1 = &projected_[static_cast<size_t>(r1) * width_];
        const Vec2 a = p0[c0], b = p0[c1], d = p1[c0], e = p1[c1];
        // b ± pad covers b itself, so b's own coordinates need not enter the corner min/max.
        const double pad = equilateralRadius_ + 1e-6;
        const double minX = std::min(std::min(a.x, d.x), e.x), maxX = std::max(std::max(a.x, d.x), e.x);
        const double minY = std::min(std::min(a.y, d.y), e.y), maxY = std::max(std::max(a.y, d.y), e.y);
        return sx >= std::min(minX - 1e-6, double(b.x) - pad) && sx <= std::max(maxX + 1e-6, double(b.x) + pad) &&
               sy >= std::min(minY - 1e-6, double(b.y) - pad) && sy <= std::max(maxY + 1e-6, double(b.y) + pad);
    }

    // Cluster levels 1..clusterLevelCount() (block size 2^ℓ texels); 0 when not built. Spec §3.2 builds B = 2..32
    // and uses B <= 16 at query time. Node (row, col) unwrapped.
    static constexpr int kMaxClusterLevel = 5;
    int clusterLevelCount() const { return static_cast<int>(clusters_.size()); }
    const ClusterNode& cluster(int level, int row, int col) const {
        int w = levelWidth(level), h = levelHeight(level);
        return clusters_[level - 1][static_cast<size_t>(wrap(row, h)) * w + wrap(col, w)];
    }
    // The two cluster triangles of node (row, col) at level ℓ >= 1, in the same parametrisation as cellTriangles
    // (x = 2^ℓ·(node + (ξ,η))) and with the equilateral replacement in node-local units (|Ĵ| < ε_J, so the effective
    // texel threshold is ε_J/4^ℓ, spec §2.3).
    void clusterTriangles(int level, int row, int col, ManifoldTriangle out[2]) const;

    // Bytes held by the projected normals, the stored bound levels (1..) and the cluster levels (issue 12 item 2).
    size_t memoryBytes() const;
    struct MemoryBreakdown {
        size_t normals = 0;
        size_t bounds[kMaxLevel + 1] = {};           // per level; level 0 is recomputed, so 0
        size_t clusters[kMaxClusterLevel + 1] = {};  // per level 1..5
    };
    MemoryBreakdown memoryBreakdown() const;

    // Serialisation (issue 12 item 2, the disk cache of pndf_cache.h): a little-endian byte image of everything the
    // queries read (dimensions, ε_J, normals, bound levels, cluster levels). deserialize checks every size against
    // the buffer before allocating and returns nullptr for a malformed buffer (never throws on bad data).
    std::vector<uint8_t> serialize() const;
    static std::shared_ptr<PndfManifold> deserialize(const uint8_t* data, size_t size);
    // Bit-identical comparison of two manifolds (every normal, bound and cluster float): the cache round-trip test.
    bool identicalTo(const PndfManifold& other) const;


    static int wrap(int i, int n) {
        if (static_cast<unsigned>(i) < static_cast<unsigned>(n)) return i;  // common case: no division
        int m = i % n;
        return m < 0 ? m + n : m;
    }

private:
    PndfManifold() = default;  // for deserialize
    void buildBounds();
    void buildClusters();
    void makeTriangles(const Vec2d& a, const Vec2d& b, const Vec2d& d, const Vec2d& e, double col0, double row0,
                       double size, ManifoldTriangle out[2]) const;

    int width_ = 0, height_ = 0;
    double jacobianClamp_ = kDefaultJacobianClamp;
    double equilateralRadius_ = 0;                // R of spec §2.3 for jacobianClamp_
    std::vector<Vec2> projected_;                 // s per vertex, float32 (8 bytes/texel as in spec §1)
    std::vector<std::vector<NormalBounds>> levels_;  // levels_[0] is empty (recomputed by cellBounds)
    std::vector<std::vector<ClusterNode>> clusters_;  // clusters_[ℓ-1] = level ℓ
};

}  // namespace specula::pndf
