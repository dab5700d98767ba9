// Built-in shapes: each is an exact parametric surface (AnalyticSurface) plus a uv-grid tessellation
// of it whose vertices carry the exact position, normal, tangent and uv of the parameterisation.
#include "core/geometry/shapes.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace specula {

namespace {

constexpr double kPiD = 3.14159265358979323846;
constexpr double k2PiD = 2.0 * kPiD;

// Where a parameterisation degenerates (sphere poles, disk centre) dp/du vanishes. We evaluate the
// derivatives with sin(theta) (resp. rho) clamped to this fraction of the radius, so that dp/du keeps
// the direction of its limit along the meridian u (a consistent, NaN-free tangent) while the
// position, normal and uv stay exact (cf. pbrt-v3 §3.2.2, which nudges the hit point off the pole).
constexpr double kDegenerateEps = 1e-5;

double clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

// phi = atan2(y, x) mapped to u = phi / (2 pi) in [0, 1).
double azimuthU(double x, double y) {
    double phi = std::atan2(y, x);
    if (phi < 0) phi += k2PiD;
    double u = phi / k2PiD;
    return u >= 1.0 ? 0.0 : u;
}

Vec3 toVec3(double x, double y, double z) { return Vec3(float(x), float(y), float(z)); }

// A surface given by an exact parameterisation (u,v) -> SurfaceGeometry and an inverse mapping that
// projects an object-space point onto the surface's parameter domain. at() = eval(project(p)).
class ParametricSurface : public AnalyticSurface {
public:
    virtual SurfaceGeometry eval(double u, double v) const = 0;
    virtual Vec2 project(const Vec3& p) const = 0;
    SurfaceGeometry at(const Vec3& pObject) const override {
        Vec2 uv = project(pObject);
        return eval(uv.x, uv.y);
    }
};

// For all built-ins the coordinate lines are lines of curvature (F = f = 0), so the Weingarten
// equations (pbrt-v3 §3.2.3: dn/du = ((fF - eG) dp/du + (eF - fE) dp/dv) / (EG - F^2), likewise dn/dv)
// reduce to dn/du = -(e/E) dp/du and dn/dv = -(g/G) dp/dv, with principal curvatures -e/E, -g/G.
// Each shape below writes these closed forms directly.

// Sphere: p = r (sin(theta) cos(phi), sin(theta) sin(phi), cos(theta)), theta = pi v, phi = 2 pi u.
// Curvature 1/r in every direction: dn = dp / r.
class SphereSurface final : public ParametricSurface {
public:
    explicit SphereSurface(double r) : r_(r) {}
    SurfaceGeometry eval(double u, double v) const override {
        double phi = k2PiD * u, theta = kPiD * v;
        double sp = std::sin(phi), cp = std::cos(phi), st = std::sin(theta), ct = std::cos(theta);
        double stc = std::max(st, kDegenerateEps);
        SurfaceGeometry g;
        g.n = toVec3(st * cp, st * sp, ct);
        g.p = g.n * float(r_);
        g.uv = Vec2(float(u), float(v));
        g.dpdu = toVec3(-k2PiD * r_ * stc * sp, k2PiD * r_ * stc * cp, 0.0);
        g.dpdv = toVec3(kPiD * r_ * ct * cp, kPiD * r_ * ct * sp, -kPiD * r_ * st);
        g.dndu = g.dpdu / float(r_);
        g.dndv = g.dpdv / float(r_);
        return g;
    }
    void closest(const Vec3& pObject, Vec3& p, Vec3& n) const override {
        float len = glm::length(pObject);
        n = len > 0.f ? pObject / len : Vec3(0, 0, 1);
        p = n * float(r_);
    }
    // Direct evaluation without trigonometric round trips (the hot path of every sphere hit):
    // n = p/|p|, dp/du = 2π (-y, x, 0), dp/dv = π r (cosθ cosφ, cosθ sinφ, -sinθ).
    SurfaceGeometry at(const Vec3& pObject) const override {
        float len = glm::length(pObject);
        if (!(len > 0.f)) return eval(0.0, 0.0);
        const float r = float(r_);
        SurfaceGeometry g;
        g.n = pObject / len;
        g.p = g.n * r;
        float rho = std::sqrt(g.n.x * g.n.x + g.n.y * g.n.y);  // sinθ
        float rhoc = std::max(rho, float(kDegenerateEps));
        float cp = rho > 0.f ? g.n.x / rho : 1.f, sp = rho > 0.f ? g.n.y / rho : 0.f;
        float ct = g.n.z;
        const float k2Pi = float(k2PiD), kPi = float(kPiD);
        g.uv = Vec2(float(azimuthU(g.n.x, g.n.y)), std::clamp(std::atan2(rho, ct) / kPi, 0.f, 1.f));  // atan2: well conditioned at the poles
        g.dpdu = Vec3(-k2Pi * r * rhoc * sp, k2Pi * r * rhoc * cp, 0.f);
        g.dpdv = Vec3(kPi * r * ct * cp, kPi * r * ct * sp, -kPi * r * rho);
        g.dndu = g.dpdu / r;
        g.dndv = g.dpdv / r;
        return g;
    }
    Vec2 project(const Vec3& p) const override {
        double x = p.x, y = p.y, z = p.z;
        double len = std::sqrt(x * x + y * y + z * z);
        if (!(len > 0)) return Vec2(0.f, 0.f);
        double theta = std::acos(std::min(1.0, std::max(-1.0, z / len)));
        return Vec2(float(azimuthU(x, y)), float(clamp01(theta / kPiD)));
    }

private:
    double r_;
};

// Quad: p = (sx (u - 1/2), sy (v - 1/2), 0), flat (dn = 0).
class QuadSurface final : public ParametricSurface {
public:
    QuadSurface(double sx, double sy) : sx_(sx), sy_(sy) {}
    bool isPlanar() const override { return true; }
    SurfaceGeometry eval(double u, double v) const override {
        SurfaceGeometry g;
        g.p = toVec3(sx_ * (u - 0.5), sy_ * (v - 0.5), 0.0);
        g.n = Vec3(0, 0, 1);
        g.uv = Vec2(float(u), float(v));
        g.dpdu = toVec3(sx_, 0, 0);
        g.dpdv = toVec3(0, sy_, 0);
        g.dndu = g.dndv = Vec3(0.f);
        return g;
    }
    Vec2 project(const Vec3& p) const override {
        return Vec2(float(clamp01(p.x / sx_ + 0.5)), float(clamp01(p.y / sy_ + 0.5)));
    }

private:
    double sx_, sy_;
};

// Disk: p = rho (cos(phi), sin(phi), 0) with rho = r (1 - v), flat (dn = 0).
class DiskSurface final : public ParametricSurface {
public:
    explicit DiskSurface(double r) : r_(r) {}
    bool isPlanar() const override { return true; }
    SurfaceGeometry eval(double u, double v) const override {
        double phi = k2PiD * u, sp = std::sin(phi), cp = std::cos(phi);
        double rho = r_ * (1.0 - v), rhoc = std::max(rho, kDegenerateEps * r_);
        SurfaceGeometry g;
        g.p = toVec3(rho * cp, rho * sp, 0.0);
        g.n = Vec3(0, 0, 1);
        g.uv = Vec2(float(u), float(v));
        g.dpdu = toVec3(-k2PiD * rhoc * sp, k2PiD * rhoc * cp, 0.0);
        g.dpdv = toVec3(-r_ * cp, -r_ * sp, 0.0);
        g.dndu = g.dndv = Vec3(0.f);
        return g;
    }
    Vec2 project(const Vec3& p) const override {
        double rho = std::sqrt(double(p.x) * p.x + double(p.y) * p.y);
        return Vec2(float(azimuthU(p.x, p.y)), float(clamp01(1.0 - rho / r_)));
    }

private:
    double r_;
};

// Cylinder: p = (r cos(phi), r sin(phi), h v). Curvatures 1/r around, 0 along z:
// dn/du = dp/du / r, dn/dv = 0.
class CylinderSurface final : public ParametricSurface {
public:
    CylinderSurface(double r, double h) : r_(r), h_(h) {}
    SurfaceGeometry eval(double u, double v) const override {
        double phi = k2PiD * u, sp = std::sin(phi), cp = std::cos(phi);
        SurfaceGeometry g;
        g.n = toVec3(cp, sp, 0.0);
        g.p = toVec3(r_ * cp, r_ * sp, h_ * v);
        g.uv = Vec2(float(u), float(v));
        g.dpdu = toVec3(-k2PiD * r_ * sp, k2PiD * r_ * cp, 0.0);
        g.dpdv = toVec3(0, 0, h_);
        g.dndu = toVec3(-k2PiD * sp, k2PiD * cp, 0.0);
        g.dndv = Vec3(0.f);
        return g;
    }
    Vec2 project(const Vec3& p) const override {
        return Vec2(float(azimuthU(p.x, p.y)), float(clamp01(p.z / h_)));
    }

private:
    double r_, h_;
};

// Torus: n = cos(psi) rho_hat(phi) + sin(psi) z, p = R rho_hat(phi) + r n, phi = 2 pi u, psi = 2 pi v.
// Curvatures cos(psi) / (R + r cos(psi)) along u and 1/r along v:
// dn/du = 2 pi cos(psi) phi_hat, dn/dv = dp/dv / r. Expects R > r (a ring torus).
class TorusSurface final : public ParametricSurface {
public:
    TorusSurface(double R, double r) : R_(R), r_(r) {}
    SurfaceGeometry eval(double u, double v) const override {
        double phi = k2PiD * u, psi = k2PiD * v;
        double sp = std::sin(phi), cp = std::cos(phi), ss = std::sin(psi), cs = std::cos(psi);
        double ring = R_ + r_ * cs;
        SurfaceGeometry g;
        g.n = toVec3(cs * cp, cs * sp, ss);
        g.p = toVec3(ring * cp, ring * sp, r_ * ss);
        g.uv = Vec2(float(u), float(v));
        g.dpdu = toVec3(-k2PiD * ring * sp, k2PiD * ring * cp, 0.0);
        g.dpdv = toVec3(-k2PiD * r_ * ss * cp, -k2PiD * r_ * ss * sp, k2PiD * r_ * cs);
        g.dndu = toVec3(-k2PiD * cs * sp, k2PiD * cs * cp, 0.0);
        g.dndv = toVec3(-k2PiD * ss * cp, -k2PiD * ss * sp, k2PiD * cs);
        return g;
    }
    Vec2 project(const Vec3& p) const override {
        double x = p.x, y = p.y, z = p.z;
        double rho = std::sqrt(x * x + y * y);
        double cp = 1.0, sp = 0.0;
        if (rho > 0) { cp = x / rho; sp = y / rho; }
        double dRadial = x * cp + y * sp - R_;  // offset from the tube's centre circle, in its plane
        double psi = std::atan2(z, dRadial);
        if (psi < 0) psi += k2PiD;
        double v = psi / k2PiD;
        if (v >= 1.0) v = 0.0;
        return Vec2(float(azimuthU(x, y)), float(v));
    }

private:
    double R_, r_;
};

// Tessellates a parametric surface on an nu x nv grid of (u,v) = (i/nu, j/nv). Columns i = 0 and
// i = nu are distinct vertices (the u seam is duplicated) so UVs are continuous inside each triangle.
// A collapsed row (a pole: every vertex of the row maps to one point) gets one vertex per cell, at
// the cell's mid-u, and only the non-degenerate triangle of each of its cells is emitted.
// flipWinding: set when cross(dp/du, dp/dv) points against the outward normal, so that every
// triangle is counter-clockwise seen from outside (cross(p1-p0, p2-p0) along n).
TriangleMesh tessellate(const ParametricSurface& s, int nu, int nv, bool collapsedV0, bool collapsedV1,
                        bool flipWinding) {
    TriangleMesh mesh;
    auto addVertex = [&](double u, double v) {
        SurfaceGeometry g = s.eval(u, v);
        Vec3 t = glm::normalize(g.dpdu);
        // Handedness: +1 when cross(n, t) points along +v (dp/dv), see TriangleMesh::tangents.
        float w = glm::dot(glm::cross(g.n, t), g.dpdv) < 0.f ? -1.f : 1.f;
        mesh.positions.push_back(g.p);
        mesh.normals.push_back(g.n);
        mesh.tangents.push_back(Vec4(t, w));
        mesh.uvs.push_back(g.uv);
        return uint32_t(mesh.positions.size() - 1);
    };
    // rows[j][i]: vertex of grid node (i, j); a collapsed row holds nu vertices, one per cell.
    std::vector<std::vector<uint32_t>> rows(size_t(nv) + 1);
    for (int j = 0; j <= nv; ++j) {
        double v = double(j) / nv;
        bool collapsed = (j == 0 && collapsedV0) || (j == nv && collapsedV1);
        for (int i = 0; i < (collapsed ? nu : nu + 1); ++i)
            rows[j].push_back(addVertex(collapsed ? (i + 0.5) / nu : double(i) / nu, v));
    }
    auto addTriangle = [&](uint32_t a, uint32_t b, uint32_t c) {
        mesh.indices.push_back(flipWinding ? glm::uvec3(a, c, b) : glm::uvec3(a, b, c));
    };
    for (int j = 0; j < nv; ++j) {
        bool top = j == 0 && collapsedV0, bottom = j == nv - 1 && collapsedV1;
        for (int i = 0; i < nu; ++i) {
            // Cell corners a = (i,j), b = (i+1,j), c = (i+1,j+1), d = (i,j+1); triangles abc and acd.
            if (top) {
                addTriangle(rows[j][i], rows[j + 1][i + 1], rows[j + 1][i]);
            } else if (bottom) {
                addTriangle(rows[j][i], rows[j][i + 1], rows[j + 1][i]);
            } else {
                uint32_t a = rows[j][i], b = rows[j][i + 1], c = rows[j + 1][i + 1], d = rows[j + 1][i];
                addTriangle(a, b, c);
                addTriangle(a, c, d);
            }
        }
    }
    return mesh;
}

void requirePositive(float x, const char* what) {
    if (!(x > 0.f) || !std::isfinite(x))
        throw std::invalid_argument(std::string("built-in shape: ") + what + " must be positive and finite");
}

BuiltinShape build(std::shared_ptr<const ParametricSurface> s, int nu, int nv, bool c0, bool c1, bool flip) {
    BuiltinShape shape;
    shape.mesh = tessellate(*s, nu, nv, c0, c1, flip);
    shape.surface = std::move(s);
    return shape;
}

}  // namespace

// cross(dp/du, dp/dv) = cross(phi_hat, theta_hat) points inward, hence the flipped winding.
BuiltinShape makeSphere(float radius, int segments) {
    requirePositive(radius, "sphere radius");
    int nu = std::max(3, segments), nv = std::max(2, nu / 2);
    return build(std::make_shared<SphereSurface>(radius), nu, nv, true, true, true);
}

BuiltinShape makeQuad(float sizeX, float sizeY) {
    requirePositive(sizeX, "quad sizeX");
    requirePositive(sizeY, "quad sizeY");
    return build(std::make_shared<QuadSurface>(sizeX, sizeY), 1, 1, false, false, false);
}

// Rings: segments/4 (the disk is flat; rings only make the interpolated vertex uv follow v = 1 - rho/r).
BuiltinShape makeDisk(float radius, int segments) {
    requirePositive(radius, "disk radius");
    int nu = std::max(3, segments), nv = std::max(1, nu / 4);
    return build(std::make_shared<DiskSurface>(radius), nu, nv, false, true, false);
}

// Rings: segments/8 (the tube is straight along z, so rings only limit triangle aspect ratio).
BuiltinShape makeCylinder(float radius, float height, int segments) {
    requirePositive(radius, "cylinder radius");
    requirePositive(height, "cylinder height");
    int nu = std::max(3, segments), nv = std::max(1, nu / 8);
    return build(std::make_shared<CylinderSurface>(radius, height), nu, nv, false, false, false);
}

// Tube rings: segments/2.
BuiltinShape makeTorus(float majorRadius, float minorRadius, int segments) {
    requirePositive(majorRadius, "torus major radius");
    requirePositive(minorRadius, "torus minor radius");
    if (!(minorRadius < majorRadius))
        throw std::invalid_argument("built-in shape: torus minor radius must be smaller than the major radius");
    int nu = std::max(3, segments), nv = std::max(3, nu / 2);
    return build(std::make_shared<TorusSurface>(majorRadius, minorRadius), nu, nv, false, false, false);
}

}  // namespace specula
