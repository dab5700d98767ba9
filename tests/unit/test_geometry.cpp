// Unit tests for core/geometry: built-in shape tessellations against their exact parameterisations,
// vertex normal / tangent generation, and the OBJ / PLY / glTF loaders checked against each other.
#include "core/geometry/mesh_io.h"
#include "core/geometry/shapes.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <typeinfo>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <iomanip>
#include <random>
#include <sstream>

using namespace specula;
using glm::dvec2;
using glm::dvec3;

namespace {

constexpr double kPiD = 3.14159265358979323846;

double meshArea(const TriangleMesh& m) {
    double a = 0;
    for (const auto& t : m.indices) {
        dvec3 p0(m.positions[t.x]), p1(m.positions[t.y]), p2(m.positions[t.z]);
        a += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    }
    return a;
}

// Distance between two u values on the periodic [0,1) circle.
double circularDist(double a, double b) {
    double d = std::fabs(a - b);
    d -= std::floor(d);
    return std::min(d, 1.0 - d);
}

// ---- Built-in shapes -----------------------------------------------------------------------------
// Each case restates the parameterisation of shapes.h independently (in double precision) so the
// implementation is checked against the documented formulas, not against itself.
struct ShapeCase {
    std::string name;
    BuiltinShape shape;
    std::function<dvec3(double, double)> p;  // exact surface point at (u, v)
    std::function<dvec3(double, double)> n;  // exact outward unit normal at (u, v)
    double area = 0;                         // exact area
    double scale = 1;                        // characteristic size for absolute tolerances
    bool uPeriodic = false;                  // u is an azimuth (seam at u = 0/1)
    bool vPeriodic = false;                  // v is an angle too (torus)
    std::function<bool(double)> degenerateV = [](double) { return false; };  // rows where u is undefined
};

ShapeCase makeCase(const std::string& name) {
    ShapeCase c;
    c.name = name;
    if (name == "sphere") {
        const double r = 1.5;
        c.shape = makeSphere(float(r), 128);
        c.p = [r](double u, double v) {
            double th = kPiD * v, ph = 2 * kPiD * u;
            return r * dvec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
        };
        c.n = [](double u, double v) {
            double th = kPiD * v, ph = 2 * kPiD * u;
            return dvec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
        };
        c.area = 4 * kPiD * r * r;
        c.scale = r;
        c.uPeriodic = true;
        c.degenerateV = [](double v) { return v < 1e-6 || v > 1 - 1e-6; };
    } else if (name == "quad") {
        const double sx = 2, sy = 3;
        c.shape = makeQuad(float(sx), float(sy));
        c.p = [=](double u, double v) { return dvec3(sx * (u - 0.5), sy * (v - 0.5), 0); };
        c.n = [](double, double) { return dvec3(0, 0, 1); };
        c.area = sx * sy;
        c.scale = 3;
    } else if (name == "disk") {
        const double r = 0.75;
        c.shape = makeDisk(float(r), 128);
        c.p = [r](double u, double v) {
            double rho = r * (1 - v), ph = 2 * kPiD * u;
            return dvec3(rho * std::cos(ph), rho * std::sin(ph), 0);
        };
        c.n = [](double, double) { return dvec3(0, 0, 1); };
        c.area = kPiD * r * r;
        c.scale = r;
        c.uPeriodic = true;
        c.degenerateV = [](double v) { return v > 1 - 1e-6; };
    } else if (name == "cylinder") {
        const double r = 0.5, h = 2;
        c.shape = makeCylinder(float(r), float(h), 128);
        c.p = [=](double u, double v) {
            double ph = 2 * kPiD * u;
            return dvec3(r * std::cos(ph), r * std::sin(ph), h * v);
        };
        c.n = [](double u, double) { return dvec3(std::cos(2 * kPiD * u), std::sin(2 * kPiD * u), 0); };
        c.area = 2 * kPiD * r * h;
        c.scale = h;
        c.uPeriodic = true;
    } else if (name == "torus") {
        const double R = 2, r = 0.5;
        c.shape = makeTorus(float(R), float(r), 128);
        c.p = [=](double u, double v) {
            double ph = 2 * kPiD * u, ps = 2 * kPiD * v, ring = R + r * std::cos(ps);
            return dvec3(ring * std::cos(ph), ring * std::sin(ph), r * std::sin(ps));
        };
        c.n = [](double u, double v) {
            double ph = 2 * kPiD * u, ps = 2 * kPiD * v;
            return dvec3(std::cos(ps) * std::cos(ph), std::cos(ps) * std::sin(ph), std::sin(ps));
        };
        c.area = 4 * kPiD * kPiD * R * r;
        c.scale = R + r;
        c.uPeriodic = true;
        c.vPeriodic = true;
    }
    return c;
}

// Central differences of a function of (u, v).
dvec3 dU(const std::function<dvec3(double, double)>& f, double u, double v, double h = 1e-6) {
    return (f(u + h, v) - f(u - h, v)) / (2 * h);
}
dvec3 dV(const std::function<dvec3(double, double)>& f, double u, double v, double h = 1e-6) {
    return (f(u, v + h) - f(u, v - h)) / (2 * h);
}

// |a - b| <= rel * |b| + abs.
::testing::AssertionResult vecNear(const dvec3& a, const dvec3& b, double rel, double abs, const char* what) {
    double err = glm::length(a - b), tol = rel * glm::length(b) + abs;
    if (err <= tol) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << what << ": got (" << a.x << ", " << a.y << ", " << a.z << ") expected ("
                                         << b.x << ", " << b.y << ", " << b.z << "), error " << err << " > " << tol;
}

class ShapeTest : public ::testing::TestWithParam<std::string> {
protected:
    void SetUp() override { c = makeCase(GetParam()); }
    ShapeCase c;
};

TEST_P(ShapeTest, AreaMatchesAnalytic) {
    double a = meshArea(c.shape.mesh);
    EXPECT_NEAR(a / c.area, 1.0, c.name == "quad" ? 1e-6 : 1e-3) << c.name << " area " << a << " vs " << c.area;
    EXPECT_LE(a, c.area * (1 + 1e-6)) << "an inscribed tessellation cannot exceed the exact area";
}

TEST_P(ShapeTest, AttributeArraysAreComplete) {
    const TriangleMesh& m = c.shape.mesh;
    ASSERT_GT(m.triangleCount(), 0u);
    EXPECT_EQ(m.normals.size(), m.positions.size());
    EXPECT_EQ(m.tangents.size(), m.positions.size());
    EXPECT_EQ(m.uvs.size(), m.positions.size());
    ASSERT_NE(c.shape.surface, nullptr);
    std::vector<int> used(m.positions.size(), 0);
    for (const auto& t : m.indices)
        for (int k = 0; k < 3; ++k) {
            ASSERT_LT(t[k], m.positions.size());
            used[t[k]] = 1;
        }
    for (size_t i = 0; i < used.size(); ++i) EXPECT_TRUE(used[i]) << "unused vertex " << i;
}

TEST_P(ShapeTest, VerticesMatchParameterisation) {
    const TriangleMesh& m = c.shape.mesh;
    const double L = c.scale;
    for (size_t i = 0; i < m.positions.size(); ++i) {
        SCOPED_TRACE(c.name + " vertex " + std::to_string(i));
        dvec2 uv(m.uvs[i]);
        ASSERT_TRUE(uv.x >= 0 && uv.x <= 1 && uv.y >= 0 && uv.y <= 1);
        EXPECT_TRUE(vecNear(dvec3(m.positions[i]), c.p(uv.x, uv.y), 0, 1e-6 * L, "position = p(uv)"));
        // Normal: unit and exact.
        dvec3 n(m.normals[i]);
        EXPECT_NEAR(glm::length(n), 1.0, 1e-6);
        EXPECT_TRUE(vecNear(n, c.n(uv.x, uv.y), 0, 1e-6, "normal"));
        // Tangent: unit, perpendicular to n, along dp/du (its limit on a degenerate row), handedness of dp/dv.
        dvec3 t(m.tangents[i]);
        double w = m.tangents[i].w;
        EXPECT_NEAR(glm::length(t), 1.0, 1e-6);
        EXPECT_NEAR(glm::dot(t, n), 0.0, 1e-6);
        double vSafe = std::min(1 - 1e-4, std::max(1e-4, uv.y));
        dvec3 dpdu = dU(c.p, uv.x, vSafe), dpdv = dV(c.p, uv.x, vSafe);
        EXPECT_TRUE(vecNear(t, glm::normalize(dpdu), 0, 1e-4, "tangent direction"));
        EXPECT_TRUE(w == 1.f || w == -1.f);
        EXPECT_EQ(w, glm::dot(glm::cross(n, t), dpdv) < 0 ? -1.f : 1.f);
        // The analytic surface maps the vertex back to its own uv (u modulo the seam; u is arbitrary at poles).
        SurfaceGeometry g = c.shape.surface->at(m.positions[i]);
        if (c.vPeriodic)
            EXPECT_LT(circularDist(g.uv.y, uv.y), 1e-5);
        else
            EXPECT_NEAR(g.uv.y, uv.y, 1e-5);
        if (!c.degenerateV(uv.y)) {
            if (c.uPeriodic)
                EXPECT_LT(circularDist(g.uv.x, uv.x), 1e-5);
            else
                EXPECT_NEAR(g.uv.x, uv.x, 1e-5);
        }
        EXPECT_TRUE(vecNear(dvec3(g.p), dvec3(m.positions[i]), 0, 1e-5 * L, "at(vertex).p"));
    }
}

TEST_P(ShapeTest, WindingIsCounterClockwiseFromOutside) {
    const TriangleMesh& m = c.shape.mesh;
    for (size_t k = 0; k < m.indices.size(); ++k) {
        const auto& t = m.indices[k];
        dvec3 p0(m.positions[t.x]), p1(m.positions[t.y]), p2(m.positions[t.z]);
        dvec3 gn = glm::cross(p1 - p0, p2 - p0);
        ASSERT_GT(glm::length(gn), 0.0) << "degenerate triangle " << k;
        dvec3 ns = dvec3(m.normals[t.x]) + dvec3(m.normals[t.y]) + dvec3(m.normals[t.z]);
        ASSERT_GT(glm::dot(glm::normalize(gn), glm::normalize(ns)), 0.99) << c.name << " triangle " << k;
        // UVs are continuous inside each triangle: no triangle spans a seam.
        for (int axis = 0; axis < 2; ++axis) {
            if (!(axis == 0 ? c.uPeriodic : c.vPeriodic)) continue;
            float lo = std::min({m.uvs[t.x][axis], m.uvs[t.y][axis], m.uvs[t.z][axis]});
            float hi = std::max({m.uvs[t.x][axis], m.uvs[t.y][axis], m.uvs[t.z][axis]});
            ASSERT_LT(hi - lo, 0.1f) << "triangle " << k << " crosses the seam of uv axis " << axis;
        }
    }
}

TEST_P(ShapeTest, AnalyticSurfaceAtRandomPointsIsExact) {
    const TriangleMesh& m = c.shape.mesh;
    const AnalyticSurface& s = *c.shape.surface;
    const double L = c.scale;
    std::mt19937 rng(1234);
    std::uniform_int_distribution<size_t> pickTri(0, m.indices.size() - 1);
    std::uniform_real_distribution<double> U(0, 1);
    for (int it = 0; it < 2000; ++it) {
        const auto& t = m.indices[pickTri(rng)];
        double b1 = U(rng), b2 = U(rng);
        if (b1 + b2 > 1) { b1 = 1 - b1; b2 = 1 - b2; }
        double b0 = 1 - b1 - b2;
        dvec3 q = b0 * dvec3(m.positions[t.x]) + b1 * dvec3(m.positions[t.y]) + b2 * dvec3(m.positions[t.z]);
        dvec3 nInterp = b0 * dvec3(m.normals[t.x]) + b1 * dvec3(m.normals[t.y]) + b2 * dvec3(m.normals[t.z]);
        dvec2 uvInterp = b0 * dvec2(m.uvs[t.x]) + b1 * dvec2(m.uvs[t.y]) + b2 * dvec2(m.uvs[t.z]);
        SurfaceGeometry g = s.at(Vec3(q));
        SCOPED_TRACE(c.name + " sample " + std::to_string(it));
        ASSERT_TRUE(isFinite(g.p) && isFinite(g.n) && isFinite(g.dpdu) && isFinite(g.dpdv) && isFinite(g.dndu) &&
                    isFinite(g.dndv));
        double u = g.uv.x, v = g.uv.y;
        // Projection lands on the exact surface, close to the tessellation point and its uv.
        EXPECT_TRUE(vecNear(dvec3(g.p), c.p(u, v), 0, 2e-6 * L, "p on exact surface"));
        EXPECT_LT(glm::length(dvec3(g.p) - q), 1e-3 * L);
        EXPECT_LT(c.vPeriodic ? circularDist(v, uvInterp.y) : std::fabs(v - uvInterp.y), 0.02);
        if (!c.degenerateV(v)) EXPECT_LT(c.uPeriodic ? circularDist(u, uvInterp.x) : std::fabs(u - uvInterp.x), 0.02);
        // Exact unit outward normal.
        EXPECT_NEAR(glm::length(dvec3(g.n)), 1.0, 1e-6);
        EXPECT_TRUE(vecNear(dvec3(g.n), c.n(u, v), 0, 2e-6, "n"));
        EXPECT_GT(glm::dot(dvec3(g.n), glm::normalize(nInterp)), 0.999);
        // Partials against finite differences of the documented parameterisation (relative error < 1e-3).
        EXPECT_TRUE(vecNear(dvec3(g.dpdu), dU(c.p, u, v), 1e-3, 1e-6 * L, "dpdu"));
        EXPECT_TRUE(vecNear(dvec3(g.dpdv), dV(c.p, u, v), 1e-3, 1e-6 * L, "dpdv"));
        EXPECT_TRUE(vecNear(dvec3(g.dndu), dU(c.n, u, v), 1e-3, 1e-6, "dndu"));
        EXPECT_TRUE(vecNear(dvec3(g.dndv), dV(c.n, u, v), 1e-3, 1e-6, "dndv"));
        EXPECT_NEAR(glm::dot(g.n, g.dpdu), 0.0, 1e-5 * glm::length(g.dpdu) + 1e-7);
        EXPECT_NEAR(glm::dot(g.n, g.dpdv), 0.0, 1e-5 * glm::length(g.dpdv) + 1e-7);
    }
}

TEST_P(ShapeTest, ComputedNormalsAndTangentsAgreeWithAnalytic) {
    TriangleMesh m = c.shape.mesh;
    const TriangleMesh& ref = c.shape.mesh;
    m.normals.clear();
    m.tangents.clear();
    computeTangents(m);  // computes area-weighted normals first
    ASSERT_EQ(m.normals.size(), ref.positions.size());
    ASSERT_EQ(m.tangents.size(), ref.positions.size());
    for (size_t i = 0; i < ref.positions.size(); ++i) {
        SCOPED_TRACE(c.name + " vertex " + std::to_string(i));
        // Seam and pole vertices are split, so each copy only sees the faces on its side of the seam.
        Vec2 uv = ref.uvs[i];
        bool seam = (c.uPeriodic && (uv.x == 0.f || uv.x == 1.f)) || (c.vPeriodic && (uv.y == 0.f || uv.y == 1.f)) ||
                    c.degenerateV(uv.y);
        EXPECT_GT(glm::dot(m.normals[i], ref.normals[i]), seam ? 0.998f : 0.9999f);
        // Near the poles / disk centre the per-face uv gradients vary wildly: compare away from them.
        if (c.name == "sphere" && std::sin(kPiD * ref.uvs[i].y) < 0.2) continue;
        if (c.name == "disk" && ref.uvs[i].y > 0.8f) continue;
        Vec3 t(m.tangents[i]);
        EXPECT_NEAR(glm::length(t), 1.f, 1e-5f);
        EXPECT_NEAR(glm::dot(t, m.normals[i]), 0.f, 1e-5f);
        EXPECT_GT(glm::dot(t, Vec3(ref.tangents[i])), 0.999f);
        EXPECT_EQ(m.tangents[i].w, ref.tangents[i].w);
    }
}

INSTANTIATE_TEST_SUITE_P(Builtins, ShapeTest, ::testing::Values("sphere", "quad", "disk", "cylinder", "torus"),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

TEST(Shapes, SpherePolesAreFiniteWithConsistentTangents) {
    BuiltinShape s = makeSphere(2.f, 32);
    for (float z : {2.f, -2.f, 2.001f}) {
        SurfaceGeometry g = s.surface->at(Vec3(0, 0, z));
        EXPECT_TRUE(isFinite(g.p) && isFinite(g.n) && isFinite(g.dpdu) && isFinite(g.dpdv) && isFinite(g.dndu) &&
                    isFinite(g.dndv));
        EXPECT_NEAR(g.p.z, z > 0 ? 2.f : -2.f, 1e-6f);
        EXPECT_NEAR(g.n.z, z > 0 ? 1.f : -1.f, 1e-6f);
        EXPECT_EQ(g.uv.y, z > 0 ? 0.f : 1.f);
        ASSERT_GT(glm::length(g.dpdu), 0.f) << "dpdu must stay usable as a tangent at the pole";
        Frame f = Frame::fromNormalTangent(g.n, g.dpdu);
        EXPECT_TRUE(isFinite(f.t) && isFinite(f.b));
        EXPECT_NEAR(glm::dot(glm::normalize(g.dpdu), g.n), 0.f, 1e-5f);
    }
    SurfaceGeometry g0 = s.surface->at(Vec3(0.f));  // the centre: no direction at all, must not be NaN
    EXPECT_TRUE(isFinite(g0.p) && isFinite(g0.n) && isFinite(g0.dpdu));
    // Pole vertices: one per cell, at mid-cell u, with the tangent of their meridian's limit.
    int poleVertices = 0;
    for (size_t i = 0; i < s.mesh.positions.size(); ++i)
        if (s.mesh.uvs[i].y == 0.f) {
            ++poleVertices;
            float phi = 2 * kPi * s.mesh.uvs[i].x;
            EXPECT_GT(glm::dot(Vec3(s.mesh.tangents[i]), Vec3(-std::sin(phi), std::cos(phi), 0)), 0.9999f);
        }
    EXPECT_EQ(poleVertices, 32);
}

TEST(Shapes, DiskCentreIsFinite) {
    BuiltinShape s = makeDisk(1.f, 16);
    SurfaceGeometry g = s.surface->at(Vec3(0.f));
    EXPECT_TRUE(isFinite(g.dpdu) && isFinite(g.dpdv));
    EXPECT_GT(glm::length(g.dpdu), 0.f);
    EXPECT_EQ(g.uv.y, 1.f);
    EXPECT_EQ(g.n, Vec3(0, 0, 1));
}

TEST(Shapes, SeamVerticesAreDuplicated) {
    for (const BuiltinShape& s : {makeSphere(1.f, 16), makeCylinder(1.f, 1.f, 16), makeTorus(2.f, 1.f, 16)}) {
        int atZero = 0, atOne = 0;
        for (size_t i = 0; i < s.mesh.positions.size(); ++i) {
            if (s.mesh.uvs[i].x == 0.f) ++atZero;
            if (s.mesh.uvs[i].x == 1.f) ++atOne;
        }
        EXPECT_GT(atZero, 0);
        EXPECT_EQ(atZero, atOne);
    }
}

TEST(Shapes, TessellationCountsFollowSegments) {
    // sphere: segments x segments/2 cells, the two pole rows emit one triangle per cell.
    EXPECT_EQ(makeSphere(1.f, 16).mesh.triangleCount(), size_t(16 * 8 * 2 - 2 * 16));
    EXPECT_EQ(makeQuad(1.f, 1.f).mesh.triangleCount(), 2u);
    EXPECT_EQ(makeTorus(2.f, 1.f, 16).mesh.triangleCount(), size_t(16 * 8 * 2));
    EXPECT_THROW(makeSphere(-1.f), std::invalid_argument);
    EXPECT_THROW(makeTorus(1.f, 2.f), std::invalid_argument);
}

// ---- computeVertexNormals / computeTangents ------------------------------------------------------

TEST(Tangents, DegenerateUvsFallBackToOrthogonalTangent) {
    TriangleMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.uvs = {{0.5f, 0.5f}, {0.5f, 0.5f}, {0.5f, 0.5f}};
    m.indices = {{0, 1, 2}};
    computeTangents(m);
    ASSERT_EQ(m.normals.size(), 3u);
    ASSERT_EQ(m.tangents.size(), 3u);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(glm::distance(m.normals[i], Vec3(0, 0, 1)), 0.f, 1e-6f);
        Vec3 t(m.tangents[i]);
        EXPECT_TRUE(isFinite(t));
        EXPECT_NEAR(glm::length(t), 1.f, 1e-6f);
        EXPECT_NEAR(glm::dot(t, m.normals[i]), 0.f, 1e-6f);
        EXPECT_NEAR(glm::distance(t, Frame::fromNormal(m.normals[i]).t), 0.f, 1e-6f);
        EXPECT_EQ(m.tangents[i].w, 1.f);
    }
}

TEST(Tangents, MirroredUvsGiveNegativeHandedness) {
    TriangleMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.uvs = {{1, 0}, {0, 0}, {1, 1}};  // u runs along -x, v along +y; cross(n, t) = -y
    m.indices = {{0, 1, 2}};
    computeTangents(m);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(glm::distance(Vec3(m.tangents[i]), Vec3(-1, 0, 0)), 0.f, 1e-6f);
        EXPECT_EQ(m.tangents[i].w, -1.f);
    }
}

TEST(Normals, AreaWeighted) {
    // Two faces sharing vertex 0: a large one in z=0 (normal +z) and a small one in x=0 (normal +x).
    TriangleMesh m;
    m.positions = {{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {0, 0, -1}, {0, 1, 0}};
    m.indices = {{0, 1, 2}, {0, 3, 4}};
    computeVertexNormals(m);
    // Face areas 4.5 and 0.5: normal of vertex 0 = normalize(9 z + 1 x).
    Vec3 expect = glm::normalize(Vec3(1, 0, 9));
    EXPECT_NEAR(glm::distance(m.normals[0], expect), 0.f, 1e-6f);
    EXPECT_NEAR(glm::distance(m.normals[1], Vec3(0, 0, 1)), 0.f, 1e-6f);
    EXPECT_NEAR(glm::distance(m.normals[3], Vec3(1, 0, 0)), 0.f, 1e-6f);
}

// ---- Loaders -------------------------------------------------------------------------------------

// 2-triangle quad in z=0 with uvs and +z normals.
TriangleMesh quadFixture() {
    TriangleMesh m;
    m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    m.indices = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

// Unit cube, 24 vertices (4 per face, flat normals), uvs per face; the -z face has a mirrored u so its
// tangents have w = -1. Vertices are first used in index order, so OBJ welding keeps the order.
TriangleMesh cubeFixture() {
    TriangleMesh m;
    const Vec3 axes[6][3] = {  // normal, u axis, v axis with cross(u, v) = normal
        {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},  {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}}, {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},
        {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}}, {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {0, 1, 0}, {1, 0, 0}}};
    for (int f = 0; f < 6; ++f) {
        Vec3 n = axes[f][0], a = axes[f][1], b = axes[f][2];
        uint32_t base = uint32_t(m.positions.size());
        const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (const auto& c : corners) {
            m.positions.push_back(0.5f * (n + c[0] * a + c[1] * b));
            m.normals.push_back(n);
            Vec2 uv(0.5f * (c[0] + 1), 0.5f * (c[1] + 1));
            if (f == 5) uv.x = 1 - uv.x;  // mirrored island
            m.uvs.push_back(uv * 0.25f + Vec2(0.125f * f, 0.5f));
        }
        m.indices.push_back({base, base + 1, base + 2});
        m.indices.push_back({base, base + 2, base + 3});
    }
    return m;
}

TriangleMesh withTangents(TriangleMesh m) {
    m.tangents.clear();
    computeTangents(m);
    return m;
}

std::string num(float x) {
    std::ostringstream s;
    s << std::setprecision(9) << x;
    return s.str();
}

std::string objText(const TriangleMesh& m, bool normals, bool uvs) {
    std::ostringstream s;
    s << "# test mesh\no test\n";
    for (auto& p : m.positions) s << "v " << num(p.x) << ' ' << num(p.y) << ' ' << num(p.z) << '\n';
    if (uvs)
        for (auto& t : m.uvs) s << "vt " << num(t.x) << ' ' << num(t.y) << '\n';
    if (normals)
        for (auto& n : m.normals) s << "vn " << num(n.x) << ' ' << num(n.y) << ' ' << num(n.z) << '\n';
    for (auto& t : m.indices) {
        s << 'f';
        for (int k = 0; k < 3; ++k) {
            uint32_t i = t[k] + 1;
            s << ' ' << i;
            if (uvs || normals) s << '/' << (uvs ? std::to_string(i) : "") << (normals ? "/" + std::to_string(i) : "");
        }
        s << '\n';
    }
    return s.str();
}

// PLY writer with clutter the reader must skip: an element before the vertices, extra scalar and list
// properties, an int-typed face count, and an element after the faces.
template <typename T>
void putBinary(std::string& out, T value, bool bigEndian) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if (bigEndian) std::reverse(b, b + sizeof(T));
    out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

std::string plyText(const TriangleMesh& m, const std::string& format, const std::string& uvNames = "u v",
                    bool intCount = false) {
    std::istringstream un(uvNames);
    std::string uName, vName;
    un >> uName >> vName;
    std::ostringstream h;
    h << "ply\nformat " << format << " 1.0\ncomment written by test_geometry\n"
      << "element camera 1\nproperty float view_px\nproperty list uchar float junk\n"
      << "element vertex " << m.positions.size() << "\n"
      << "property float x\nproperty float y\nproperty double z\nproperty uchar red\n"
      << "property list uchar int vjunk\n"
      << "property float nx\nproperty float ny\nproperty float nz\n"
      << "property float " << uName << "\nproperty float " << vName << "\n"
      << "element face " << m.indices.size() << "\n"
      << (intCount ? "property list int uint vertex_index\n" : "property list uchar int vertex_indices\n")
      << "property short flags\n"
      << "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
    std::string out = h.str();
    if (format == "ascii") {
        std::ostringstream b;
        b << "1.5 2 7 8\n";
        for (size_t i = 0; i < m.positions.size(); ++i) {
            const Vec3 &p = m.positions[i], &n = m.normals[i];
            b << num(p.x) << ' ' << num(p.y) << ' ' << num(p.z) << " 255 3 1 2 3 " << num(n.x) << ' ' << num(n.y)
              << ' ' << num(n.z) << ' ' << num(m.uvs[i].x) << ' ' << num(m.uvs[i].y) << '\n';
        }
        for (auto& t : m.indices) b << "3 " << t.x << ' ' << t.y << ' ' << t.z << " -7\n";
        b << "0 1\n";
        return out + b.str();
    }
    bool be = format == "binary_big_endian";
    putBinary(out, 1.5f, be);
    putBinary(out, uint8_t(2), be);
    putBinary(out, 7.f, be);
    putBinary(out, 8.f, be);
    for (size_t i = 0; i < m.positions.size(); ++i) {
        putBinary(out, m.positions[i].x, be);
        putBinary(out, m.positions[i].y, be);
        putBinary(out, double(m.positions[i].z), be);
        putBinary(out, uint8_t(255), be);
        putBinary(out, uint8_t(2), be);
        putBinary(out, int32_t(-1), be);
        putBinary(out, int32_t(5), be);
        putBinary(out, m.normals[i].x, be);
        putBinary(out, m.normals[i].y, be);
        putBinary(out, m.normals[i].z, be);
        putBinary(out, m.uvs[i].x, be);
        putBinary(out, m.uvs[i].y, be);
    }
    for (auto& t : m.indices) {
        if (intCount)
            putBinary(out, int32_t(3), be);
        else
            putBinary(out, uint8_t(3), be);
        for (int k = 0; k < 3; ++k) {
            if (intCount)
                putBinary(out, uint32_t(t[k]), be);
            else
                putBinary(out, int32_t(t[k]), be);
        }
        putBinary(out, int16_t(-7), be);
    }
    putBinary(out, int32_t(0), be);
    putBinary(out, int32_t(1), be);
    return out;
}

std::string base64(const std::string& in) {
    static const char* tbl = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8 | uint8_t(in[i + 2]);
        for (int k = 3; k >= 0; --k) out += tbl[(v >> (6 * k)) & 63];
    }
    if (i + 1 == in.size()) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16;
        out += tbl[(v >> 18) & 63];
        out += tbl[(v >> 12) & 63];
        out += "==";
    } else if (i + 2 == in.size()) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8;
        out += tbl[(v >> 18) & 63];
        out += tbl[(v >> 12) & 63];
        out += tbl[(v >> 6) & 63];
        out += '=';
    }
    return out;
}

// Minimal glTF 2.0 writer: one binary buffer, bufferViews/accessors appended as JSON snippets.
struct GltfBuilder {
    std::string bin;
    std::vector<std::string> views, accessors;

    int addView(const std::string& bytes, int stride = 0) {
        while (bin.size() % 4) bin += '\0';
        std::ostringstream s;
        s << "{\"buffer\":0,\"byteOffset\":" << bin.size() << ",\"byteLength\":" << bytes.size();
        if (stride) s << ",\"byteStride\":" << stride;
        s << "}";
        bin += bytes;
        views.push_back(s.str());
        return int(views.size() - 1);
    }
    int addAccessor(int view, int componentType, size_t count, const std::string& type, size_t offset = 0,
                    const std::string& extra = "") {
        std::ostringstream s;
        s << "{\"bufferView\":" << view << ",\"byteOffset\":" << offset << ",\"componentType\":" << componentType
          << ",\"count\":" << count << ",\"type\":\"" << type << "\"" << extra << "}";
        accessors.push_back(s.str());
        return int(accessors.size() - 1);
    }
    template <typename T>
    static std::string bytesOf(const std::vector<T>& v) {
        return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    // Adds one primitive's accessors (tightly packed) and returns its JSON. uvs are flipped to glTF's
    // v-down convention; tangents are written as given (same handedness convention, see gltf_loader.cpp).
    std::string addPrimitive(const TriangleMesh& m, bool tangents, int indexType = 5125) {
        std::ostringstream a;
        Vec3 lo(1e30f), hi(-1e30f);
        for (auto& p : m.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
        std::string mm = ",\"min\":[" + num(lo.x) + "," + num(lo.y) + "," + num(lo.z) + "],\"max\":[" + num(hi.x) +
                         "," + num(hi.y) + "," + num(hi.z) + "]";
        int pos = addAccessor(addView(bytesOf(m.positions)), 5126, m.positions.size(), "VEC3", 0, mm);
        a << "{\"attributes\":{\"POSITION\":" << pos;
        if (!m.normals.empty())
            a << ",\"NORMAL\":" << addAccessor(addView(bytesOf(m.normals)), 5126, m.normals.size(), "VEC3");
        if (!m.uvs.empty()) {
            std::vector<Vec2> flipped;
            for (auto uv : m.uvs) flipped.emplace_back(uv.x, 1 - uv.y);
            a << ",\"TEXCOORD_0\":" << addAccessor(addView(bytesOf(flipped)), 5126, flipped.size(), "VEC2");
        }
        if (tangents)
            a << ",\"TANGENT\":" << addAccessor(addView(bytesOf(m.tangents)), 5126, m.tangents.size(), "VEC4");
        a << "}";
        if (indexType >= 0) {
            std::string idx;
            for (auto& t : m.indices)
                for (int k = 0; k < 3; ++k) {
                    if (indexType == 5121) idx += char(uint8_t(t[k]));
                    if (indexType == 5123) { uint16_t s = uint16_t(t[k]); idx.append(reinterpret_cast<char*>(&s), 2); }
                    if (indexType == 5125) { uint32_t s = t[k]; idx.append(reinterpret_cast<char*>(&s), 4); }
                }
            a << ",\"indices\":" << addAccessor(addView(idx), indexType, m.indices.size() * 3, "SCALAR");
        }
        a << ",\"mode\":4}";
        return a.str();
    }
    std::string json(const std::string& meshes, const std::string& nodes, const std::string& scenes,
                     const std::string& bufferUri) const {
        std::ostringstream s;
        s << "{\"asset\":{\"version\":\"2.0\",\"generator\":\"specula test\"}," << scenes << "\"nodes\":" << nodes
          << ",\"meshes\":" << meshes << ",\"buffers\":[{\"byteLength\":" << bin.size();
        if (!bufferUri.empty()) s << ",\"uri\":\"" << bufferUri << "\"";
        s << "}],\"bufferViews\":[";
        for (size_t i = 0; i < views.size(); ++i) s << (i ? "," : "") << views[i];
        s << "],\"accessors\":[";
        for (size_t i = 0; i < accessors.size(); ++i) s << (i ? "," : "") << accessors[i];
        s << "]}";
        return s.str();
    }
    std::string gltf(const std::string& meshes, const std::string& nodes, const std::string& scenes) const {
        return json(meshes, nodes, scenes, "data:application/octet-stream;base64," + base64(bin));
    }
    std::string glb(const std::string& meshes, const std::string& nodes, const std::string& scenes) const {
        std::string j = json(meshes, nodes, scenes, "");
        while (j.size() % 4) j += ' ';
        std::string b = bin;
        while (b.size() % 4) b += '\0';
        std::string out;
        auto u32 = [&out](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
        u32(0x46546C67u);  // "glTF"
        u32(2);
        u32(uint32_t(12 + 8 + j.size() + 8 + b.size()));
        u32(uint32_t(j.size()));
        u32(0x4E4F534Au);  // "JSON"
        out += j;
        u32(uint32_t(b.size()));
        u32(0x004E4942u);  // "BIN\0"
        out += b;
        return out;
    }
};

const std::string kOneNodeScene = "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],";

std::string gltfSingleMesh(const TriangleMesh& m, bool tangents, bool binary, int indexType = 5125) {
    GltfBuilder b;
    std::string prim = b.addPrimitive(m, tangents, indexType);
    std::string meshes = "[{\"primitives\":[" + prim + "]}]", nodes = "[{\"mesh\":0}]";
    return binary ? b.glb(meshes, nodes, kOneNodeScene) : b.gltf(meshes, nodes, kOneNodeScene);
}

void expectSameMesh(const TriangleMesh& got, const TriangleMesh& want, const std::string& what) {
    SCOPED_TRACE(what);
    ASSERT_EQ(got.positions.size(), want.positions.size());
    ASSERT_EQ(got.indices.size(), want.indices.size());
    ASSERT_EQ(got.normals.size(), want.normals.size());
    ASSERT_EQ(got.uvs.size(), want.uvs.size());
    ASSERT_EQ(got.tangents.size(), want.tangents.size());
    for (size_t i = 0; i < got.indices.size(); ++i) EXPECT_EQ(got.indices[i], want.indices[i]) << "triangle " << i;
    for (size_t i = 0; i < got.positions.size(); ++i) {
        EXPECT_LT(glm::distance(got.positions[i], want.positions[i]), 1e-6f) << "position " << i;
        if (!want.normals.empty()) EXPECT_LT(glm::distance(got.normals[i], want.normals[i]), 1e-6f) << "normal " << i;
        if (!want.uvs.empty()) EXPECT_LT(glm::distance(got.uvs[i], want.uvs[i]), 1e-6f) << "uv " << i;
        if (!want.tangents.empty()) {
            EXPECT_LT(glm::distance(Vec3(got.tangents[i]), Vec3(want.tangents[i])), 1e-5f) << "tangent " << i;
            EXPECT_EQ(got.tangents[i].w, want.tangents[i].w) << "handedness " << i;
        }
    }
}

// Every failure names the file and the reason.
void expectLoadError(const std::string& path, const std::string& reason) {
    try {
        loadMesh(path);
        ADD_FAILURE() << "no MeshLoadError for " << path;
    } catch (const MeshLoadError& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find(path), std::string::npos) << msg;
        EXPECT_NE(msg.find(reason), std::string::npos) << "expected '" << reason << "' in: " << msg;
    }
}

class LoaderTest : public ::testing::Test {
protected:
    std::string dir = test::tempDir("geometry");
    std::string write(const std::string& name, const std::string& content) {
        std::string path = dir + "/" + name;
        test::writeFile(path, content);
        return path;
    }
};

TEST_F(LoaderTest, FormatsAgreeOnQuadAndCube) {
    for (const auto& [name, fixture] : {std::make_pair(std::string("quad"), quadFixture()),
                                        std::make_pair(std::string("cube"), cubeFixture())}) {
        const TriangleMesh ref = withTangents(fixture);
        const std::vector<std::pair<std::string, std::string>> files = {
            {name + ".obj", objText(fixture, true, true)},
            {name + "_ascii.ply", plyText(fixture, "ascii")},
            {name + "_le.ply", plyText(fixture, "binary_little_endian", "s t")},
            {name + "_be.ply", plyText(fixture, "binary_big_endian", "texture_u texture_v", true)},
            {name + "_ascii_int.ply", plyText(fixture, "ascii", "texture_s texture_t", true)},
            {name + ".gltf", gltfSingleMesh(fixture, false, false)},
            {name + ".glb", gltfSingleMesh(fixture, false, true)},
            {name + "_tangents.gltf", gltfSingleMesh(ref, true, false)},
            {name + "_u16.glb", gltfSingleMesh(ref, true, true, 5123)},
            {name + "_u8.gltf", gltfSingleMesh(fixture, false, false, 5121)},
        };
        for (const auto& [file, text] : files) {
            TriangleMesh got;
            ASSERT_NO_THROW(got = loadMesh(write(file, text))) << file;
            expectSameMesh(got, ref, file);
        }
    }
    // The cube's mirrored face really is left-handed, in every format.
    const TriangleMesh ref = withTangents(cubeFixture());
    for (int i = 0; i < 24; ++i) EXPECT_EQ(ref.tangents[i].w, i >= 20 ? -1.f : 1.f) << i;
}

TEST_F(LoaderTest, UppercaseExtensionAndUnindexedGltf) {
    TriangleMesh q = quadFixture();
    expectSameMesh(loadMesh(write("QUAD.OBJ", objText(q, true, true))), withTangents(q), "OBJ upper case");
    // Non-indexed glTF primitive: every 3 vertices form a triangle.
    TriangleMesh flat;
    for (const auto& t : q.indices)
        for (int k = 0; k < 3; ++k) {
            flat.positions.push_back(q.positions[t[k]]);
            flat.normals.push_back(q.normals[t[k]]);
            flat.uvs.push_back(q.uvs[t[k]]);
        }
    flat.indices = {{0, 1, 2}, {3, 4, 5}};
    expectSameMesh(loadMesh(write("flat.GLTF", gltfSingleMesh(flat, false, false, -1))), withTangents(flat),
                   "glTF without indices");
}

TEST_F(LoaderTest, GltfExternalBufferResolvesNextToTheFile) {
    TriangleMesh q = quadFixture();
    GltfBuilder b;
    std::string prim = b.addPrimitive(q, false);
    write("sub/quad.bin", b.bin);
    std::string path = write("sub/external.gltf", b.json("[{\"primitives\":[" + prim + "]}]", "[{\"mesh\":0}]",
                                                         kOneNodeScene, "quad.bin"));
    expectSameMesh(loadMesh(path), withTangents(q), "external .bin");
    std::remove((dir + "/sub/quad.bin").c_str());
    expectLoadError(path, "glTF parse error");
}

// Issue 16: a buffer URI that leads out of the glTF's folder is not followed (and nothing about that file is told)
// unless SPECULA_RESOURCE_PATH lists its folder; an accessor count that overflows the bounds check is refused.
TEST_F(LoaderTest, GltfBuffersStayInsideAllowedFoldersAndAccessorsCannotOverflow) {
    TriangleMesh q = quadFixture();
    GltfBuilder b;
    std::string prim = b.addPrimitive(q, false);
    write("outside/quad.bin", b.bin);
    std::string path = write("inside/escape.gltf", b.json("[{\"primitives\":[" + prim + "]}]", "[{\"mesh\":0}]",
                                                          kOneNodeScene, "../outside/quad.bin"));
    ::unsetenv("SPECULA_RESOURCE_PATH");
    expectLoadError(path, "a buffer URI leads outside the glTF file's folder");
    std::string msg;
    try {
        loadMesh(path);
    } catch (const std::exception& e) {
        msg = e.what();
    }
    EXPECT_EQ(msg.find("outside/quad.bin"), std::string::npos) << msg;  // not even the resolved name
    std::string absolute = write("inside/absolute.gltf", b.json("[{\"primitives\":[" + prim + "]}]", "[{\"mesh\":0}]",
                                                               kOneNodeScene, dir + "/outside/quad.bin"));
    expectLoadError(absolute, "File not found");  // tinygltf joins it under the folder; its "./" retry is refused
    // A link inside the folder that points out of it is refused the same way.
    std::filesystem::create_symlink(dir + "/outside/quad.bin", dir + "/inside/link.bin");
    expectLoadError(write("inside/link.gltf", b.json("[{\"primitives\":[" + prim + "]}]", "[{\"mesh\":0}]",
                                                     kOneNodeScene, "link.bin")),
                    "leads outside");
    // The user opts in by listing the folder.
    ::setenv("SPECULA_RESOURCE_PATH", (dir + "/elsewhere:" + dir + "/outside/").c_str(), 1);
    expectSameMesh(loadMesh(path), withTangents(q), "allowed folder");
    ::unsetenv("SPECULA_RESOURCE_PATH");
    // 2^57 + 1 elements of 128-byte stride: (count - 1) * stride wraps to 0 in 64 bits.
    std::string huge = b.json("[{\"primitives\":[" + prim + "]}]", "[{\"mesh\":0}]", kOneNodeScene, "quad.bin");
    write("inside/quad.bin", b.bin);
    size_t at = huge.find("\"count\":");
    ASSERT_NE(at, std::string::npos);
    size_t end = huge.find_first_of(",}", at);
    huge.replace(at, end - at, "\"count\":144115188075855873");
    size_t view = huge.find("\"byteLength\"", huge.find("\"bufferViews\""));
    ASSERT_NE(view, std::string::npos);
    huge.insert(view, "\"byteStride\":128,");
    expectLoadError(write("inside/huge.gltf", huge), "accessor exceeds its buffer");
}

// fuzz_mesh found a GLB that made tinygltf throw std::out_of_range (vector::at on its header): every prefix of a valid
// GLB and of a valid glTF must load or fail with MeshLoadError, never another exception.
TEST_F(LoaderTest, TruncatedGltfFilesFailWithAMeshError) {
    for (bool binary : {true, false}) {
        const std::string full = gltfSingleMesh(quadFixture(), false, binary);
        int failures = 0;
        for (size_t n = 0; n < full.size(); n += (n < 64 ? 1 : 7)) {
            const std::string path = write(binary ? "cut.glb" : "cut.gltf", full.substr(0, n));
            try {
                loadMesh(path);
            } catch (const MeshLoadError&) {
                ++failures;
            } catch (const std::exception& e) {
                ADD_FAILURE() << (binary ? "GLB" : "glTF") << " cut at " << n << " bytes: " << typeid(e).name() << ": " << e.what();
            }
        }
        EXPECT_GT(failures, 10);
    }
}

TEST_F(LoaderTest, GltfUvAndTangentConvention) {
    // A quad mapped the usual way: u along +x and the image's top edge at y = +1. glTF's texcoords put
    // the image's top row at v = 0, so the file stores v_gltf = 0 there, and a conforming exporter
    // writes tangent (1,0,0) with w = +1 (glTF bitangent cross(n, t) = +y = image up, as its +Y-up
    // normal maps require). After loading, Specula's v runs along +y, and both the file's tangents and
    // computeTangents must say w = +1.
    GltfBuilder b;
    std::string prim;
    {
        TriangleMesh m = quadFixture();
        m.tangents.assign(4, Vec4(1, 0, 0, 1));
        prim = b.addPrimitive(m, true);
    }
    std::string path = write("convention.gltf", b.gltf("[{\"primitives\":[" + prim + "]}]", "[{\"mesh\":0}]", kOneNodeScene));
    TriangleMesh got = loadMesh(path);
    ASSERT_EQ(got.uvs.size(), 4u);
    EXPECT_EQ(got.uvs[2], Vec2(1, 1));  // vertex (1,1,0) is the image's top-right corner
    EXPECT_EQ(got.uvs[0], Vec2(0, 0));
    TriangleMesh recomputed = withTangents(got);
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(got.tangents[i], Vec4(1, 0, 0, 1));
        EXPECT_EQ(recomputed.tangents[i].w, got.tangents[i].w);
    }
}

TEST_F(LoaderTest, GltfNodeTransformsAccumulate) {
    // Node 0: T(10,0,0) * Rz(90 deg) * S(2), child node 1 with a matrix translating by (0,0,5) and the
    // quad; node 2 mirrors x (scale -1,1,1), also instancing the quad. Not referenced nodes are ignored.
    GltfBuilder b;
    TriangleMesh q = withTangents(quadFixture());
    std::string prim = b.addPrimitive(q, true);
    const double s = std::sqrt(0.5);
    std::ostringstream nodes;
    nodes << std::setprecision(17) << "[{\"translation\":[10,0,0],\"rotation\":[0,0," << s << "," << s
          << "],\"scale\":[2,2,2],\"children\":[1]},"
          << "{\"matrix\":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1],\"mesh\":0},"
          << "{\"scale\":[-1,1,1],\"mesh\":0},"
          << "{\"translation\":[100,100,100],\"mesh\":0}]";
    std::string scenes = "\"scene\":1,\"scenes\":[{\"nodes\":[3]},{\"nodes\":[0,2]}],";
    TriangleMesh got = loadMesh(write("nodes.gltf", b.gltf("[{\"primitives\":[" + prim + "]}]", nodes.str(), scenes)));
    ASSERT_EQ(got.positions.size(), 8u);
    ASSERT_EQ(got.triangleCount(), 4u);
    // First instance: p' = (10,0,0) + Rz90(2 * (p + (0,0,5)/2))... the child's matrix applies first:
    // world = T R S (M_child p) = (10,0,0) + Rz90(2 (p + (0,0,5))).
    for (int i = 0; i < 4; ++i) {
        Vec3 p = q.positions[i] + Vec3(0, 0, 5);
        Vec3 expect = Vec3(10, 0, 0) + 2.f * Vec3(-p.y, p.x, p.z);
        EXPECT_LT(glm::distance(got.positions[i], expect), 1e-5f) << i;
        EXPECT_LT(glm::distance(got.normals[i], Vec3(0, 0, 1)), 1e-6f);
        EXPECT_LT(glm::distance(Vec3(got.tangents[i]), Vec3(0, 1, 0)), 1e-6f);  // +x rotated to +y
        EXPECT_EQ(got.tangents[i].w, 1.f);
    }
    // Mirrored instance: x negated, winding restored to CCW around the normal, handedness flipped.
    for (int i = 4; i < 8; ++i) {
        Vec3 p = q.positions[i - 4];
        EXPECT_LT(glm::distance(got.positions[i], Vec3(-p.x, p.y, p.z)), 1e-6f) << i;
        EXPECT_LT(glm::distance(Vec3(got.tangents[i]), Vec3(-1, 0, 0)), 1e-6f);
        EXPECT_EQ(got.tangents[i].w, -1.f);
    }
    for (const auto& t : got.indices) {
        Vec3 gn = glm::cross(got.positions[t.y] - got.positions[t.x], got.positions[t.z] - got.positions[t.x]);
        EXPECT_GT(glm::dot(gn, got.normals[t.x]), 0.f);
    }
    // The file's tangents agree with what computeTangents derives from the transformed mesh.
    TriangleMesh recomputed = withTangents(got);
    for (size_t i = 0; i < got.positions.size(); ++i) {
        EXPECT_LT(glm::distance(Vec3(recomputed.tangents[i]), Vec3(got.tangents[i])), 1e-5f) << i;
        EXPECT_EQ(recomputed.tangents[i].w, got.tangents[i].w) << i;
    }
}

TEST_F(LoaderTest, GltfInterleavedBufferWithByteStride) {
    TriangleMesh q = quadFixture();
    GltfBuilder b;
    std::string inter;
    for (size_t i = 0; i < 4; ++i) {
        Vec2 uv(q.uvs[i].x, 1 - q.uvs[i].y);
        inter.append(reinterpret_cast<const char*>(&q.positions[i]), 12);
        inter.append(reinterpret_cast<const char*>(&q.normals[i]), 12);
        inter.append(reinterpret_cast<const char*>(&uv), 8);
        inter.append(4, '\0');  // padding: stride 36
    }
    int view = b.addView(inter, 36);
    int pos = b.addAccessor(view, 5126, 4, "VEC3", 0, ",\"min\":[-1,-1,0],\"max\":[1,1,0]");
    int nrm = b.addAccessor(view, 5126, 4, "VEC3", 12);
    int tex = b.addAccessor(view, 5126, 4, "VEC2", 24);
    std::string idx;
    for (auto& t : q.indices)
        for (int k = 0; k < 3; ++k) idx += char(t[k]);
    int ind = b.addAccessor(b.addView(idx), 5121, 6, "SCALAR");
    std::ostringstream prim;
    prim << "{\"attributes\":{\"POSITION\":" << pos << ",\"NORMAL\":" << nrm << ",\"TEXCOORD_0\":" << tex
         << "},\"indices\":" << ind << "}";  // mode omitted: defaults to TRIANGLES
    std::string meshes = "[{\"primitives\":[" + prim.str() + "]}]";
    expectSameMesh(loadMesh(write("interleaved.glb", b.glb(meshes, "[{\"mesh\":0}]", kOneNodeScene))),
                   withTangents(q), "interleaved glb");
}

TEST_F(LoaderTest, PolygonsAreFanTriangulated) {
    // A unit square as one quad and a regular pentagon: 2 + 3 triangles.
    std::ostringstream pent;
    for (int k = 0; k < 5; ++k)
        pent << "v " << num(std::cos(2 * kPi * k / 5) + 5) << ' ' << num(std::sin(2 * kPi * k / 5)) << " 0\n";
    std::string obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n" + pent.str() + "f 1 2 3 4\nf 5 6 7 8 9\n";
    double pentArea = 2.5 * std::sin(2 * kPiD / 5);
    TriangleMesh mo = loadMesh(write("poly.obj", obj));
    EXPECT_EQ(mo.triangleCount(), 5u);
    EXPECT_NEAR(meshArea(mo), 1 + pentArea, 1e-5);
    // No normals in the file: made by angle (both polygons lie in z = 0, so every normal is +z); no uvs, no tangents.
    ASSERT_EQ(mo.normals.size(), mo.positions.size());
    for (const Vec3& n : mo.normals) EXPECT_EQ(n, Vec3(0, 0, 1));
    EXPECT_TRUE(mo.tangents.empty());
    EXPECT_TRUE(mo.uvs.empty());

    std::ostringstream ply;
    ply << "ply\r\nformat ascii 1.0\r\nelement vertex 9\r\nproperty float x\r\nproperty float y\r\n"
           "property float z\r\nelement face 2\r\nproperty list uchar uint vertex_indices\r\nend_header\r\n"
           "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
    for (int k = 0; k < 5; ++k)
        ply << num(std::cos(2 * kPi * k / 5) + 5) << ' ' << num(std::sin(2 * kPi * k / 5)) << " 0\n";
    ply << "4 0 1 2 3\n5 4 5 6 7 8\n";
    TriangleMesh mp = loadMesh(write("poly.ply", ply.str()));
    EXPECT_EQ(mp.triangleCount(), 5u);
    EXPECT_NEAR(meshArea(mp), 1 + pentArea, 1e-5);
    ASSERT_EQ(mp.normals.size(), mp.positions.size());
    for (const Vec3& n : mp.normals) EXPECT_EQ(n, Vec3(0, 0, 1));
}

// A unit cube without normals (8 positions, quads): auto smooth at 30 degrees keeps its 90-degree edges (24 vertices,
// axis normals, as Blender's Smooth by Angle); "smooth" welds every corner (8 vertices, normals along the diagonals,
// the area-weighted mean of three equal faces); "flat" gives each triangle its own normal whatever the file says.
TEST_F(LoaderTest, MeshesWithoutNormalsAreSmoothedByAngle) {
    const std::string cube =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    const std::string path = write("cube.obj", cube);
    MeshAttributeSources src;
    TriangleMesh autoSmooth = loadMesh(path, MeshShading{}, &src);
    EXPECT_EQ(src.normals, MeshAttributeSources::Computed);
    EXPECT_EQ(src.uvs, MeshAttributeSources::None);
    EXPECT_EQ(autoSmooth.positions.size(), 24u);
    EXPECT_EQ(autoSmooth.triangleCount(), 12u);
    for (const auto& t : autoSmooth.indices) {
        // Every corner of a triangle carries the triangle's outward axis normal.
        const Vec3 c = (autoSmooth.positions[t.x] + autoSmooth.positions[t.y] + autoSmooth.positions[t.z]) / 3.f;
        const Vec3 fn = glm::normalize(glm::cross(autoSmooth.positions[t.y] - autoSmooth.positions[t.x],
                                                  autoSmooth.positions[t.z] - autoSmooth.positions[t.x]));
        EXPECT_GT(glm::dot(fn, c - Vec3(0.5f)), 0.f) << "outward winding";
        for (int k = 0; k < 3; ++k) EXPECT_LT(glm::distance(autoSmooth.normals[t[k]], fn), 1e-6f);
    }
    TriangleMesh smooth = loadMesh(path, MeshShading{MeshShading::Smooth, 30.f}, &src);
    EXPECT_EQ(smooth.positions.size(), 8u);
    for (size_t i = 0; i < smooth.positions.size(); ++i) {
        const Vec3 diag = glm::normalize(smooth.positions[i] - Vec3(0.5f));
        EXPECT_LT(glm::distance(smooth.normals[i], diag), 1e-6f) << i;
    }
    // 89 degrees still creases a cube, 91 degrees smooths it.
    EXPECT_EQ(loadMesh(path, MeshShading{MeshShading::Auto, 89.f}).positions.size(), 24u);
    EXPECT_EQ(loadMesh(path, MeshShading{MeshShading::Auto, 91.f}).positions.size(), 8u);

    // Flat overrides the file's normals (here deliberately wrong ones): each triangle's corners get its face normal.
    const std::string withNormals = write("cube_vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 1 0 0\n"
                                                          "f 1//1 2//1 3//1\nf 1//1 2//1 4//1\n");
    TriangleMesh flat = loadMesh(withNormals, MeshShading{MeshShading::Flat, 30.f}, &src);
    EXPECT_EQ(src.normals, MeshAttributeSources::Computed);
    ASSERT_EQ(flat.triangleCount(), 2u);
    EXPECT_EQ(flat.positions.size(), 6u);
    EXPECT_LT(glm::distance(flat.normals[flat.indices[0].x], Vec3(0, 0, 1)), 1e-6f);
    EXPECT_LT(glm::distance(flat.normals[flat.indices[1].x], Vec3(0, -1, 0)), 1e-6f);
    TriangleMesh kept = loadMesh(withNormals, MeshShading{}, &src);
    EXPECT_EQ(src.normals, MeshAttributeSources::File);
    EXPECT_EQ(kept.normals[0], Vec3(1, 0, 0));
}

// A UV sphere whose neighbouring faces meet at 22.5 degrees is smooth at the default angle: its computed normals are
// the sphere's own within the facet error, and a uv seam (the same position with u = 0 and u = 1) does not crease it.
TEST_F(LoaderTest, AutoSmoothKeepsCurvedSurfacesSmoothAcrossUvSeams) {
    const int nu = 16, nv = 8;
    std::ostringstream obj;
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i) {  // column nu repeats column 0's positions: the seam
            const double th = kPiD * j / nv, ph = 2 * kPiD * (i % nu) / nu;
            const double r = j == 0 || j == nv ? 0.0 : std::sin(th);  // the poles' copies at exactly one position
            obj << "v " << num(r * std::cos(ph)) << ' ' << num(r * std::sin(ph)) << ' ' << num(std::cos(th)) << "\nvt " << num(double(i) / nu) << ' ' << num(1.0 - double(j) / nv) << "\n";
        }
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const int a = j * (nu + 1) + i + 1, b = a + 1, c = a + nu + 2, d = a + nu + 1;
            if (j > 0) obj << "f " << a << '/' << a << ' ' << d << '/' << d << ' ' << b << '/' << b << "\n";
            if (j < nv - 1) obj << "f " << b << '/' << b << ' ' << d << '/' << d << ' ' << c << '/' << c << "\n";
        }
    MeshAttributeSources src;
    TriangleMesh m = loadMesh(write("sphere.obj", obj.str()), MeshShading{}, &src);
    EXPECT_EQ(src.normals, MeshAttributeSources::Computed);
    EXPECT_EQ(src.uvs, MeshAttributeSources::File);
    EXPECT_EQ(src.tangents, MeshAttributeSources::Computed);
    float worst = 0.f;
    size_t worstAt = 0;
    for (size_t i = 0; i < m.positions.size(); ++i) {
        const float e = glm::distance(m.normals[i], glm::normalize(m.positions[i]));
        if (e > worst) worst = e, worstAt = i;
    }
    EXPECT_LT(worst, 0.04f) << "computed normals against the sphere's, worst at " << m.positions[worstAt].x << ","
                            << m.positions[worstAt].y << "," << m.positions[worstAt].z << " normal " << m.normals[worstAt].x
                            << "," << m.normals[worstAt].y << "," << m.normals[worstAt].z;
    // Same position, different uv (the seam, and the poles' fans): one normal.
    for (size_t i = 0; i < m.positions.size(); ++i)
        for (size_t k = i + 1; k < m.positions.size(); ++k)
            if (m.positions[i] == m.positions[k]) EXPECT_EQ(m.normals[i], m.normals[k]) << i << " " << k;
    // Flat on the same file: no two triangles of different orientation share a vertex.
    TriangleMesh f = loadMesh(write("sphere2.obj", obj.str()), MeshShading{MeshShading::Flat, 30.f});
    EXPECT_GT(f.positions.size(), m.positions.size());
}

TEST_F(LoaderTest, UvsWithoutNormalsGetComputedNormalsAndTangents) {
    TriangleMesh q = quadFixture();
    TriangleMesh got = loadMesh(write("nonormals.obj", objText(q, false, true)));
    ASSERT_EQ(got.normals.size(), 4u);
    ASSERT_EQ(got.tangents.size(), 4u);
    for (int i = 0; i < 4; ++i) {
        EXPECT_LT(glm::distance(got.normals[i], Vec3(0, 0, 1)), 1e-6f);
        EXPECT_EQ(got.tangents[i], Vec4(1, 0, 0, 1));
    }
}

TEST_F(LoaderTest, ObjShapesWithMixedAttributesAreCompleted) {
    // Shape a has normals and uvs, shape b neither: b gets area-weighted normals, zero uvs and
    // fallback tangents; the merged mesh has every attribute for every vertex.
    std::string obj =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
        "o a\nf 1/1/1 2/2/1 3/3/1\no b\nf 4 5 6\n";
    TriangleMesh m = loadMesh(write("mixed.obj", obj));
    ASSERT_EQ(m.positions.size(), 6u);
    ASSERT_EQ(m.normals.size(), 6u);
    ASSERT_EQ(m.uvs.size(), 6u);
    ASSERT_EQ(m.tangents.size(), 6u);
    for (int i = 0; i < 6; ++i) {
        EXPECT_LT(glm::distance(m.normals[i], Vec3(0, 0, 1)), 1e-6f);
        EXPECT_NEAR(glm::dot(Vec3(m.tangents[i]), m.normals[i]), 0.f, 1e-6f);
        EXPECT_NEAR(glm::length(Vec3(m.tangents[i])), 1.f, 1e-6f);
    }
}

TEST_F(LoaderTest, ErrorsNameThePathAndReason) {
    expectLoadError(dir + "/missing.obj", "not found");
    expectLoadError(write("mesh.stl", "solid x\n"), "unknown mesh extension");
    expectLoadError(write("noext", "v 0 0 0\n"), "unknown mesh extension");
    expectLoadError(write("empty.obj", "v 0 0 0\nv 1 0 0\n"), "no triangles");
    expectLoadError(write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), "out of range");
    // tinyobjloader reads these as 0 or infinity: refused with the line (issue 16).
    expectLoadError(write("nan.obj", "v 0 0 0\nv nan nan nan\nv 0 1 0\nf 1 2 3\n"),
                    "line 2: 'nan' in a 'v' line is not a finite number");
    expectLoadError(write("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n"), "line 3: '1e39'");
    expectLoadError(write("junk.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1x\nf 1//1 2//1 3//1\n"), "line 4: '1x'");
    expectLoadError(write("bad.ply", "plx\nformat ascii 1.0\nend_header\n"), "not a PLY file");
    expectLoadError(write("badfmt.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n"), "unknown format");
    expectLoadError(write("noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"),
                    "incomplete header");
    const std::string plyHead =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    expectLoadError(write("range.ply", plyHead + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), "out of range");
    expectLoadError(write("short.ply", plyHead + "0 0 0\n1 0 0\n"), "ends unexpectedly");
    // A list length beyond size_t (found by fuzz_mesh: the message cast it, a float-cast overflow under UBSan).
    expectLoadError(write("hugelist.ply", plyHead + "0 0 0\n1 0 0\n0 1 0\n1e54 0 1 2\n"),
                    "ends unexpectedly (list of 1000000000000000");
    expectLoadError(write("nan.ply", plyHead + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"), "malformed number");
    expectLoadError(write("noface.ply", plyHead.substr(0, plyHead.find("element face")) +
                                            "end_header\n0 0 0\n1 0 0\n0 1 0\n"),
                    "no triangles");
    std::string bin = plyText(quadFixture(), "binary_little_endian");
    expectLoadError(write("truncated.ply", bin.substr(0, bin.size() - 20)), "ends unexpectedly");
    expectLoadError(write("bad.gltf", "{ this is not json"), "glTF parse error");
    expectLoadError(write("bad.glb", "glTF garbage"), "glTF parse error");
    // glTF index out of range: indices accessor referring past the 4 vertices.
    {
        TriangleMesh q = quadFixture();
        q.indices[1] = {0, 2, 7};
        expectLoadError(write("range.gltf", gltfSingleMesh(q, false, false)), "out of range");
    }
    // glTF whose only primitive is a line strip.
    {
        GltfBuilder b;
        std::string prim = b.addPrimitive(quadFixture(), false, -1);
        prim.replace(prim.find("\"mode\":4"), 8, "\"mode\":3");
        expectLoadError(write("lines.gltf", b.gltf("[{\"primitives\":[" + prim + "]}]", "[{\"mesh\":0}]",
                                                   kOneNodeScene)),
                        "no triangles");
    }
}

}  // namespace
