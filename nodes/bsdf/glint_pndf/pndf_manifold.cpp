// Position-normal manifold build: triangulation (spec §2.1), Jacobian clamping (§2.3), min-max levels (§3.1).
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"

#include <cmath>
#include <cstring>
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

PndfManifold::PndfManifold(const std::vector<Vec3>& normals, int width, int height, double jacobianClamp,
                           bool withClusters)
    : width_(width), height_(height), jacobianClamp_(jacobianClamp) {
    if (width <= 0 || height <= 0)
        throw std::invalid_argument("PndfManifold: empty normal map (" + std::to_string(width) + "x" +
                                    std::to_string(height) + ")");
    if (normals.size() != static_cast<size_t>(width) * height)
        throw std::invalid_argument("PndfManifold: " + std::to_string(normals.size()) + " normals for a " +
                                    std::to_string(width) + "x" + std::to_string(height) + " map");
    if (!(jacobianClamp > 0)) throw std::invalid_argument("PndfManifold: the Jacobian clamp must be > 0");
    equilateralRadius_ = Equilateral(jacobianClamp).R;
    projected_.resize(normals.size());
    for (size_t i = 0; i < normals.size(); ++i) {
        Vec3 n = normals[i];
        float len = glm::length(n);
        if (!(len > 0) || !std::isfinite(len))
            throw std::invalid_argument("PndfManifold: normal " + std::to_string(i) + " is zero or not finite");
        n /= len;
        projected_[i] = Vec2(n.x, n.y);
    }
    if (withClusters) buildClusters();  // before the bounds, which must also cover the cluster vertices (§2.4)
    buildBounds();
}

void PndfManifold::cellTriangles(int row, int col, ManifoldTriangle out[2]) const {
    // Corners of cell (r, c) (spec §2.1): a = s[r,c], b = s[r,c+1], d = s[r+1,c], e = s[r+1,c+1].
    makeTriangles(toD(vertex(row, col)), toD(vertex(row, col + 1)), toD(vertex(row + 1, col)),
                  toD(vertex(row + 1, col + 1)), col, row, 1.0, out);
}

void PndfManifold::clusterTriangles(int level, int row, int col, ManifoldTriangle out[2]) const {
    const ClusterNode& n = cluster(level, row, col);
    const double size = double(1 << level);
    makeTriangles(toD(n.a), toD(n.b), toD(n.d), toD(n.e), col * size, row * size, size, out);
}

void PndfManifold::makeTriangles(const Vec2d& a, const Vec2d& b, const Vec2d& d, const Vec2d& e, double col0,
                                 double row0, double size, ManifoldTriangle out[2]) const {
    ManifoldTriangle& up = out[0];
    up.sOrigin = a;
    up.sEdge1 = sub(b, a);
    up.sEdge2 = sub(d, a);
    up.xOrigin = {col0, row0};
    up.xStep1 = {size, 0};
    up.xStep2 = {0, size};

    ManifoldTriangle& lo = out[1];
    lo.sOrigin = e;
    lo.sEdge1 = sub(d, e);  // weight α = 1-ξ of d
    lo.sEdge2 = sub(b, e);  // weight β = 1-η of b
    lo.xOrigin = {col0 + size, row0 + size};
    lo.xStep1 = {-size, 0};
    lo.xStep2 = {0, -size};

    for (int t = 0; t < 2; ++t) {
        ManifoldTriangle& tri = out[t];
        tri.xArea = size * size;
        tri.jacobian = cross(tri.sEdge1, tri.sEdge2);
        // The clamp applies in the triangle's own parameter units: texels for cells, node-local for clusters.
        tri.replaced = !(std::abs(tri.jacobian) >= jacobianClamp_);
        if (!tri.replaced) continue;
        const Equilateral eq(jacobianClamp_);  // only here: its two square roots are per replaced triangle
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

void PndfManifold::buildClusters() {
    clusters_.clear();
    for (int l = 1; l <= kMaxClusterLevel; ++l) {
        if ((width_ % (1 << l)) != 0 || (height_ % (1 << l)) != 0) break;
        const int B = 1 << l, w = levelWidth(l), h = levelHeight(l);
        std::vector<ClusterNode> level(static_cast<size_t>(w) * h);
        for (int nr = 0; nr < h; ++nr)
            for (int nc = 0; nc < w; ++nc) {
                // Normal equations of paper Eq. 7 / spec §3.2, accumulated exactly per fine triangle: M (4x4, hats
                // a, b, d, e), β_d and γ_d per component d, all in float64.
                double M[4][4] = {}, beta[2][4] = {}, gamma[2] = {};
                for (int r = nr * B; r < (nr + 1) * B; ++r)
                    for (int c = nc * B; c < (nc + 1) * B; ++c) {
                        const Vec2d va = toD(vertex(r, c)), vb = toD(vertex(r, c + 1));
                        const Vec2d vd = toD(vertex(r + 1, c)), ve = toD(vertex(r + 1, c + 1));
                        // Fine T⁺ = (a, b, d) at (c,r), (c+1,r), (c,r+1); T⁻ = (e, d, b) at (c+1,r+1), (c,r+1), (c+1,r).
                        const Vec2d sv[2][3] = {{va, vb, vd}, {ve, vd, vb}};
                        const double xv[2][3][2] = {{{0, 0}, {1, 0}, {0, 1}}, {{1, 1}, {0, 1}, {1, 0}}};
                        for (int t = 0; t < 2; ++t) {
                            const double J = cross(sub(sv[t][1], sv[t][0]), sub(sv[t][2], sv[t][0]));
                            // Spec's recommended weight 1/max(|J|, ε_J): thin triangles give tall peaks in D_P.
                            const double wT = 1.0 / std::max(std::abs(J), jacobianClamp_);
                            // Node-local positions of the 3 vertices and the cluster triangle holding T (by its centroid:
                            // fine anti-diagonals tile the cluster anti-diagonal, so T lies in one of them).
                            double lx[3], ly[3];
                            for (int i = 0; i < 3; ++i) {
                                lx[i] = (c - nc * B + xv[t][i][0]) / B;
                                ly[i] = (r - nr * B + xv[t][i][1]) / B;
                            }
                            const bool upper = (lx[0] + lx[1] + lx[2] + ly[0] + ly[1] + ly[2]) / 3 < 1;
                            double phi[4][3];
                            for (int i = 0; i < 3; ++i) {
                                if (upper) {
                                    phi[0][i] = 1 - lx[i] - ly[i];
                                    phi[1][i] = lx[i];
                                    phi[2][i] = ly[i];
                                    phi[3][i] = 0;
                                } else {
                                    phi[0][i] = 0;
                                    phi[1][i] = 1 - ly[i];
                                    phi[2][i] = 1 - lx[i];
                                    phi[3][i] = lx[i] + ly[i] - 1;
                                }
                            }
                            // ∫_T f g = (|T|/12)(Σ f_i g_i + Σ f_i Σ g_i) for linear f, g; |T| = 1/2 texel².
                            const double k = wT * 0.5 / 12.0;
                            auto integ = [k](const double* f, const double* g) {
                                return k * (f[0] * g[0] + f[1] * g[1] + f[2] * g[2] +
                                            (f[0] + f[1] + f[2]) * (g[0] + g[1] + g[2]));
                            };
                            const double sx[3] = {sv[t][0].x, sv[t][1].x, sv[t][2].x};
                            const double sy[3] = {sv[t][0].y, sv[t][1].y, sv[t][2].y};
                            for (int p = 0; p < 4; ++p) {
                                for (int q = 0; q < 4; ++q) M[p][q] += integ(phi[p], phi[q]);
                                beta[0][p] -= integ(phi[p], sx);
                                beta[1][p] -= integ(phi[p], sy);
                            }
                            gamma[0] += integ(sx, sx);
                            gamma[1] += integ(sy, sy);
                        }
                    }
                // Solve M ĉ_d = -β_d (SPD 4x4) by Gaussian elimination with partial pivoting, both components at once.
                double A[4][6];
                for (int p = 0; p < 4; ++p) {
                    for (int q = 0; q < 4; ++q) A[p][q] = M[p][q];
                    A[p][4] = -beta[0][p];
                    A[p][5] = -beta[1][p];
                }
                for (int col = 0; col < 4; ++col) {
                    int piv = col;
                    for (int p = col + 1; p < 4; ++p)
                        if (std::abs(A[p][col]) > std::abs(A[piv][col])) piv = p;
                    for (int q = 0; q < 6; ++q) std::swap(A[col][q], A[piv][q]);
                    for (int p = col + 1; p < 4; ++p) {
                        const double f = A[p][col] / A[col][col];
                        for (int q = col; q < 6; ++q) A[p][q] -= f * A[col][q];
                    }
                }
                double ch[2][4];
                for (int d = 0; d < 2; ++d)
                    for (int p = 3; p >= 0; --p) {
                        double v = A[p][4 + d];
                        for (int q = p + 1; q < 4; ++q) v -= A[p][q] * ch[d][q];
                        ch[d][p] = v / A[p][p];
                    }
                // True fit error E(ĉ*) = Σ_d (γ_d - β_dᵀ M⁻¹ β_d) = Σ_d (γ_d + β_dᵀ ĉ*_d) >= 0 (spec §3.2 fix), in
                // texel-area units weighted by 1/|J|; clamped at 0 against round-off.
                double res = 0;
                for (int d = 0; d < 2; ++d) {
                    res += gamma[d];
                    for (int p = 0; p < 4; ++p) res += beta[d][p] * ch[d][p];
                }
                ClusterNode& node = level[static_cast<size_t>(nr) * w + nc];
                node.residual = float(std::max(0.0, res));
                node.a = Vec2(float(ch[0][0]), float(ch[1][0]));
                node.b = Vec2(float(ch[0][1]), float(ch[1][1]));
                node.d = Vec2(float(ch[0][2]), float(ch[1][2]));
                node.e = Vec2(float(ch[0][3]), float(ch[1][3]));
            }
        clusters_.push_back(std::move(level));
    }
}

NormalBounds PndfManifold::cellBounds(int r, int c) const {
    const float inf = std::numeric_limits<float>::infinity();
    ManifoldTriangle tris[2];
    cellTriangles(r, c, tris);
    NormalBounds nb{inf, inf, -inf, -inf};
    // The bounds cover exactly the vertices the hit test uses: the original corners of an unreplaced triangle, the
    // equilateral vertices of a replaced one (spec §3.1 "plus any equilateral replacement vertices"); a replaced
    // triangle's own corners are not needed since nothing can hit them there.
    for (const ManifoldTriangle& t : tris) {
        growBounds(nb, t.sOrigin.x, t.sOrigin.y);
        growBounds(nb, t.sOrigin.x + t.sEdge1.x, t.sOrigin.y + t.sEdge1.y);
        growBounds(nb, t.sOrigin.x + t.sEdge2.x, t.sOrigin.y + t.sEdge2.y);
    }
    // Round outward by one float ulp: the replacement vertices are computed in double and rounded, and a query on
    // a bound must never be culled when the double hit test would accept it.
    nb.minX = std::nextafter(nb.minX, -inf);
    nb.minY = std::nextafter(nb.minY, -inf);
    nb.maxX = std::nextafter(nb.maxX, inf);
    nb.maxY = std::nextafter(nb.maxY, inf);
    return nb;
}

void PndfManifold::buildBounds() {
    levels_.clear();
    const float inf = std::numeric_limits<float>::infinity();
    levels_.emplace_back();  // level 0: recomputed by cellBounds, pooled below into level 1
    for (int l = 1; l <= kMaxLevel; ++l) {
        if ((width_ % (1 << l)) != 0 || (height_ % (1 << l)) != 0) break;
        const int w = levelWidth(l), h = levelHeight(l);
        std::vector<NormalBounds> cur(static_cast<size_t>(w) * h);
        for (int r = 0; r < h; ++r)
            for (int c = 0; c < w; ++c) {
                NormalBounds nb{inf, inf, -inf, -inf};
                for (int dr = 0; dr < 2; ++dr)
                    for (int dc = 0; dc < 2; ++dc) {
                        const NormalBounds ch = bounds(l - 1, 2 * r + dr, 2 * c + dc);
                        nb.minX = std::min(nb.minX, ch.minX);
                        nb.minY = std::min(nb.minY, ch.minY);
                        nb.maxX = std::max(nb.maxX, ch.maxX);
                        nb.maxY = std::max(nb.maxY, ch.maxY);
                    }
                // Spec §2.4 fix: the bounds also cover this level's cluster triangles (a least-squares fit can
                // overshoot the original normals), so culling stays valid when eval uses the cluster.
                if (l <= clusterLevelCount()) {
                    ManifoldTriangle tris[2];
                    clusterTriangles(l, r, c, tris);
                    NormalBounds cb{inf, inf, -inf, -inf};
                    for (const ManifoldTriangle& t : tris) {
                        growBounds(cb, t.sOrigin.x, t.sOrigin.y);
                        growBounds(cb, t.sOrigin.x + t.sEdge1.x, t.sOrigin.y + t.sEdge1.y);
                        growBounds(cb, t.sOrigin.x + t.sEdge2.x, t.sOrigin.y + t.sEdge2.y);
                    }
                    nb.minX = std::min(nb.minX, std::nextafter(cb.minX, -inf));
                    nb.minY = std::min(nb.minY, std::nextafter(cb.minY, -inf));
                    nb.maxX = std::max(nb.maxX, std::nextafter(cb.maxX, inf));
                    nb.maxY = std::max(nb.maxY, std::nextafter(cb.maxY, inf));
                }
                cur[static_cast<size_t>(r) * w + c] = nb;
            }
        levels_.push_back(std::move(cur));
    }
}

PndfManifold::MemoryBreakdown PndfManifold::memoryBreakdown() const {
    MemoryBreakdown mb;
    mb.normals = projected_.size() * sizeof(Vec2);
    for (size_t l = 0; l < levels_.size(); ++l) mb.bounds[l] = levels_[l].size() * sizeof(NormalBounds);
    for (size_t l = 0; l < clusters_.size(); ++l) mb.clusters[l + 1] = clusters_[l].size() * sizeof(ClusterNode);
    return mb;
}

size_t PndfManifold::memoryBytes() const {
    const MemoryBreakdown mb = memoryBreakdown();
    size_t bytes = mb.normals;
    for (size_t b : mb.bounds) bytes += b;
    for (size_t b : mb.clusters) bytes += b;
    return bytes;
}

namespace {

// Byte image layout (native byte order; every supported target is little-endian): u32 width, u32 height, f64 ε_J,
// u32 bound level count L, u32 cluster level count K, then float32 arrays: normals (2 per vertex), bound levels
// 1..L-1 (4 per node), cluster levels 1..K (9 per node). L and K must be what the constructor derives from the
// dimensions, so a buffer can only describe a manifold the build could have made.
constexpr size_t kSerialHeader = 4 + 4 + 8 + 4 + 4;

int expectedLevels(int w, int h, int maxLevel, int first) {
    int n = first;
    for (int l = 1; l <= maxLevel; ++l) {
        if ((w % (1 << l)) != 0 || (h % (1 << l)) != 0) break;
        ++n;
    }
    return n;
}

template <class T>
void put(std::vector<uint8_t>& out, const T& v) {
    const uint8_t* p = reinterpret_cast<const uint8_t*>(&v);
    out.insert(out.end(), p, p + sizeof(T));
}

template <class T>
void putArray(std::vector<uint8_t>& out, const std::vector<T>& v) {
    const uint8_t* p = reinterpret_cast<const uint8_t*>(v.data());
    out.insert(out.end(), p, p + v.size() * sizeof(T));
}

}  // namespace

std::vector<uint8_t> PndfManifold::serialize() const {
    static_assert(sizeof(Vec2) == 8 && sizeof(NormalBounds) == 16 && sizeof(ClusterNode) == 36, "packed floats");
    std::vector<uint8_t> out;
    size_t total = kSerialHeader + projected_.size() * sizeof(Vec2);
    for (const auto& l : levels_) total += l.size() * sizeof(NormalBounds);
    for (const auto& l : clusters_) total += l.size() * sizeof(ClusterNode);
    out.reserve(total);
    put(out, uint32_t(width_));
    put(out, uint32_t(height_));
    put(out, jacobianClamp_);
    put(out, uint32_t(levels_.size()));
    put(out, uint32_t(clusters_.size()));
    putArray(out, projected_);
    for (size_t l = 1; l < levels_.size(); ++l) putArray(out, levels_[l]);
    for (const auto& l : clusters_) putArray(out, l);
    return out;
}

std::shared_ptr<PndfManifold> PndfManifold::deserialize(const uint8_t* data, size_t size) {
    if (data == nullptr || size < kSerialHeader) return nullptr;
    uint32_t w, h, nLevels, nClusters;
    double eps;
    std::memcpy(&w, data, 4);
    std::memcpy(&h, data + 4, 4);
    std::memcpy(&eps, data + 8, 8);
    std::memcpy(&nLevels, data + 16, 4);
    std::memcpy(&nClusters, data + 20, 4);
    // Every size is checked against the buffer before anything is allocated (no allocation sized by bad data).
    if (w == 0 || h == 0 || w > (1u << 16) || h > (1u << 16) || !(eps > 0) || !std::isfinite(eps)) return nullptr;
    const int iw = int(w), ih = int(h);
    if (int(nLevels) != expectedLevels(iw, ih, kMaxLevel, 1)) return nullptr;
    if (nClusters != 0 && int(nClusters) != expectedLevels(iw, ih, kMaxClusterLevel, 0)) return nullptr;
    uint64_t need = kSerialHeader + uint64_t(w) * h * sizeof(Vec2);
    for (uint32_t l = 1; l < nLevels; ++l) need += uint64_t(w >> l) * (h >> l) * sizeof(NormalBounds);
    for (uint32_t l = 1; l <= nClusters; ++l) need += uint64_t(w >> l) * (h >> l) * sizeof(ClusterNode);
    if (need != size) return nullptr;
    std::shared_ptr<PndfManifold> m(new PndfManifold());
    m->width_ = iw;
    m->height_ = ih;
    m->jacobianClamp_ = eps;
    m->equilateralRadius_ = Equilateral(eps).R;
    const uint8_t* p = data + kSerialHeader;
    auto take = [&p](auto& vec, size_t count) {
        vec.resize(count);
        std::memcpy(vec.data(), p, count * sizeof(vec[0]));
        p += count * sizeof(vec[0]);
    };
    take(m->projected_, size_t(w) * h);
    for (const Vec2& v : m->projected_)
        if (!std::isfinite(v.x) || !std::isfinite(v.y)) return nullptr;
    m->levels_.resize(nLevels);
    for (uint32_t l = 1; l < nLevels; ++l) take(m->levels_[l], size_t(w >> l) * (h >> l));
    m->clusters_.resize(nClusters);
    for (uint32_t l = 1; l <= nClusters; ++l) take(m->clusters_[l - 1], size_t(w >> l) * (h >> l));
    return m;
}

bool PndfManifold::identicalTo(const PndfManifold& o) const {
    auto same = [](const auto& x, const auto& y) {
        return x.size() == y.size() && (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0);
    };
    if (width_ != o.width_ || height_ != o.height_ || jacobianClamp_ != o.jacobianClamp_) return false;
    if (!same(projected_, o.projected_) || levels_.size() != o.levels_.size() || clusters_.size() != o.clusters_.size())
        return false;
    for (size_t l = 0; l < levels_.size(); ++l)
        if (!same(levels_[l], o.levels_[l])) return false;
    for (size_t l = 0; l < clusters_.size(); ++l)
        if (!same(clusters_[l], o.clusters_[l])) return false;
    return true;
}

}  // namespace specula::pndf
