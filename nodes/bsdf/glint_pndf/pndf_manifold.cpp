// Position-normal manifold build: triangulation (spec §2.1), Jacobian clamping (§2.3), min-max levels (§3.1).
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace specula::pndf {

namespace {

double cross(const Vec2d& p, const Vec2d& q) { return p.x * q.y - p.y * q.x; }
Vec2d sub(const Vec2d& p, const Vec2d& q) { return {p.x - q.x, p.y - q.y}; }
Vec2d toD(const Vec2& v) { return {double(v.x), double(v.y)}; }

// Equilateral replacement E of spec §2.3, centred on the anti-diagonal vertex b, with |J| exactly ε_J:
// circumradius R = sqrt(2 ε_J / (3√3)), p = R√3/2, q = 3R/2. Both half-cells use the top vertex b + (0, R) as
// origin; the upper map takes (ξ,η) = (1,0) to the right vertex and (0,1) to the left one, the lower map (in its
// α = 1-ξ, β = 1-η weights) takes α -> left and β -> right, exactly the spec's two affine maps rewritten.
struct Equilateral {
    double R, p, q;
    explicit Equilateral(double eps) {
        R = std::sqrt(2.0 * eps / (3.0 * std::sqrt(3.0)));
        p = R * std::sqrt(3.0) / 2.0;
        q = 1.5 * R;
    }
};

void growBounds(NormalBounds& b, double x, double y) {
    b.minX = std::min(b.minX, float(x));
    b.minY = std::min(b.minY, float(y));
    b.maxX = std::max(b.maxX, float(x));
    b.maxY = std::max(b.maxY, float(y));
}

}  // namespace

PndfManifold::PndfManifold(const std::vector<Vec3>& normals, int width, int height, double jacobianClamp)
    : width_(width), height_(height), jacobianClamp_(jacobianClamp) {
    if (width <= 0 || height <= 0)
        throw std::invalid_argument("PndfManifold: empty normal map (" + std::to_string(width) + "x" +
                                    std::to_string(height) + ")");
    if (normals.size() != static_cast<size_t>(width) * height)
        throw std::invalid_argument("PndfManifold: " + std::to_string(normals.size()) + " normals for a " +
                                    std::to_string(width) + "x" + std::to_string(height) + " map");
    if (!(jacobianClamp > 0)) throw std::invalid_argument("PndfManifold: the Jacobian clamp must be > 0");
    projected_.resize(normals.size());
    for (size_t i = 0; i < normals.size(); ++i) {
        Vec3 n = normals[i];
        float len = glm::length(n);
        if (!(len > 0) || !std::isfinite(len))
            throw std::invalid_argument("PndfManifold: normal " + std::to_string(i) + " is zero or not finite");
        n /= len;
        projected_[i] = Vec2(n.x, n.y);
    }
    buildBounds();
}

void PndfManifold::cellTriangles(int row, int col, ManifoldTriangle out[2]) const {
    // Corners of cell (r, c) (spec §2.1): a = s[r,c], b = s[r,c+1], d = s[r+1,c], e = s[r+1,c+1].
    const Vec2d a = toD(vertex(row, col)), b = toD(vertex(row, col + 1));
    const Vec2d d = toD(vertex(row + 1, col)), e = toD(vertex(row + 1, col + 1));
    const double c0 = col, r0 = row;

    ManifoldTriangle& up = out[0];
    up.sOrigin = a;
    up.sEdge1 = sub(b, a);
    up.sEdge2 = sub(d, a);
    up.xOrigin = {c0, r0};
    up.xStep1 = {1, 0};
    up.xStep2 = {0, 1};

    ManifoldTriangle& lo = out[1];
    lo.sOrigin = e;
    lo.sEdge1 = sub(d, e);  // weight α = 1-ξ of d
    lo.sEdge2 = sub(b, e);  // weight β = 1-η of b
    lo.xOrigin = {c0 + 1, r0 + 1};
    lo.xStep1 = {-1, 0};
    lo.xStep2 = {0, -1};

    const Equilateral eq(jacobianClamp_);
    for (int t = 0; t < 2; ++t) {
        ManifoldTriangle& tri = out[t];
        tri.jacobian = cross(tri.sEdge1, tri.sEdge2);
        tri.replaced = !(std::abs(tri.jacobian) >= jacobianClamp_);
        if (!tri.replaced) continue;
        // Spec §2.3: replace by E centred on b so that 1/|J| is clamped to 1/ε_J while the x parametrisation (and
        // so the kernel mass of the half-cell) is unchanged.
        tri.sOrigin = {b.x, b.y + eq.R};
        if (t == 0) {
            tri.sEdge1 = {eq.p, -eq.q};
            tri.sEdge2 = {-eq.p, -eq.q};
        } else {
            tri.sEdge1 = {-eq.p, -eq.q};
            tri.sEdge2 = {eq.p, -eq.q};
        }
        tri.jacobian = cross(tri.sEdge1, tri.sEdge2);
    }
}

void PndfManifold::buildBounds() {
    levels_.clear();
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<NormalBounds> level0(static_cast<size_t>(width_) * height_);
    for (int r = 0; r < height_; ++r) {
        for (int c = 0; c < width_; ++c) {
            ManifoldTriangle tris[2];
            cellTriangles(r, c, tris);
            NormalBounds nb{inf, inf, -inf, -inf};
            // The bounds cover exactly the vertices the hit test uses: the original corners of an unreplaced
            // triangle, the equilateral vertices of a replaced one (spec §3.1 "plus any equilateral replacement
            // vertices"); a replaced triangle's own corners are not needed since nothing can hit them there.
            for (const ManifoldTriangle& t : tris) {
                growBounds(nb, t.sOrigin.x, t.sOrigin.y);
                growBounds(nb, t.sOrigin.x + t.sEdge1.x, t.sOrigin.y + t.sEdge1.y);
                growBounds(nb, t.sOrigin.x + t.sEdge2.x, t.sOrigin.y + t.sEdge2.y);
            }
            // Round outward by one float ulp: the replacement vertices are computed in double and rounded, and a
            // query on a bound must never be culled when the double hit test would accept it.
            nb.minX = std::nextafter(nb.minX, -inf);
            nb.minY = std::nextafter(nb.minY, -inf);
            nb.maxX = std::nextafter(nb.maxX, inf);
            nb.maxY = std::nextafter(nb.maxY, inf);
            level0[static_cast<size_t>(r) * width_ + c] = nb;
        }
    }
    levels_.push_back(std::move(level0));
    for (int l = 1; l <= kMaxLevel; ++l) {
        if ((width_ % (1 << l)) != 0 || (height_ % (1 << l)) != 0) break;
        const int w = levelWidth(l), h = levelHeight(l), pw = levelWidth(l - 1);
        const std::vector<NormalBounds>& prev = levels_.back();
        std::vector<NormalBounds> cur(static_cast<size_t>(w) * h);
        for (int r = 0; r < h; ++r)
            for (int c = 0; c < w; ++c) {
                NormalBounds nb{inf, inf, -inf, -inf};
                for (int dr = 0; dr < 2; ++dr)
                    for (int dc = 0; dc < 2; ++dc) {
                        const NormalBounds& ch = prev[static_cast<size_t>(2 * r + dr) * pw + 2 * c + dc];
                        nb.minX = std::min(nb.minX, ch.minX);
                        nb.minY = std::min(nb.minY, ch.minY);
                        nb.maxX = std::max(nb.maxX, ch.maxX);
                        nb.maxY = std::max(nb.maxY, ch.maxY);
                    }
                cur[static_cast<size_t>(r) * w + c] = nb;
            }
        levels_.push_back(std::move(cur));
    }
}

size_t PndfManifold::memoryBytes() const {
    size_t bytes = projected_.size() * sizeof(Vec2);
    for (const auto& l : levels_) bytes += l.size() * sizeof(NormalBounds);
    return bytes;
}

}  // namespace specula::pndf
