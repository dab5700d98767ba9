// Test maps and helpers shared by the P-NDF tests (test_pndf*.cpp): periodic sinusoid height fields with folds and
// plateaus, the clamped manifold's s at a texel position, and a midpoint rule of D_P over an s-rectangle.
#pragma once

#include "nodes/bsdf/glint_pndf/pndf_eval.h"
#include "nodes/bsdf/glint_pndf/pndf_manifold.h"

#include <cmath>
#include <random>
#include <vector>

namespace specula::pndf::testing {

constexpr double kPiD = 3.14159265358979323846;

inline Vec3 normalFromSlope(double sx, double sy) {
    // Height-field normal: n ∝ (-∂h/∂x, -∂h/∂y, 1).
    return glm::normalize(Vec3(float(-sx), float(-sy), 1.f));
}

// A periodic smooth height field: a few sinusoids with integer frequencies (periodic on the N-grid), peak slopes
// around `slope`. With larger frequencies it has folds (negative Jacobians) and saddles.
inline std::vector<Vec3> sinusoidMap(int n, unsigned seed, int maxFreq, double slope, bool plateaus = false) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> freq(-maxFreq, maxFreq);
    std::uniform_real_distribution<double> phase(0, 2 * kPiD);
    struct Wave {
        double fx, fy, ph, amp;
    };
    std::vector<Wave> waves;
    while (waves.size() < 5) {
        int fx = freq(rng), fy = freq(rng);
        if (fx == 0 && fy == 0) continue;
        double w = 2 * kPiD * std::sqrt(double(fx * fx + fy * fy)) / n;
        waves.push_back({double(fx), double(fy), phase(rng), slope / (w * 5)});
    }
    std::vector<Vec3> normals(size_t(n) * n);
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) {
            double h = 0, hx = 0, hy = 0;
            for (const Wave& wv : waves) {
                double arg = 2 * kPiD * (wv.fx * c + wv.fy * r) / n + wv.ph;
                h += wv.amp * std::sin(arg);
                hx += wv.amp * std::cos(arg) * 2 * kPiD * wv.fx / n;
                hy += wv.amp * std::cos(arg) * 2 * kPiD * wv.fy / n;
            }
            // Plateaus: where h < 0 the surface is flat, so whole regions of triangles are replaced (§2.3).
            if (plateaus && h < 0) hx = hy = 0;
            normals[size_t(r) * n + c] = normalFromSlope(hx, hy);
        }
    return normals;
}

// The clamped manifold's s at texel position (x, y): the affine map of the triangle holding it (spec §2.1, §2.3).
inline Vec2d manifoldNormalAt(const PndfManifold& m, double x, double y) {
    int c = int(std::floor(x)), r = int(std::floor(y));
    double xi = x - c, eta = y - r;
    ManifoldTriangle tris[2];
    m.cellTriangles(r, c, tris);
    const bool upper = xi + eta < 1;
    const ManifoldTriangle& t = tris[upper ? 0 : 1];
    double t1 = upper ? xi : 1 - xi, t2 = upper ? eta : 1 - eta;
    return {t.sOrigin.x + t1 * t.sEdge1.x + t2 * t.sEdge2.x, t.sOrigin.y + t1 * t.sEdge1.y + t2 * t.sEdge2.y};
}

// Midpoint rule of D_P over an s-rectangle on a g x g grid, optionally weighted by f(s).
template <class F>
double integrateOverRect(const PndfManifold& m, const Footprint& fp, double x0, double y0, double x1, double y1, int g,
                         F weight) {
    const double hx = (x1 - x0) / g, hy = (y1 - y0) / g;
    double sum = 0;
    for (int j = 0; j < g; ++j)
        for (int i = 0; i < g; ++i) {
            Vec2d s{x0 + (i + 0.5) * hx, y0 + (j + 0.5) * hy};
            if (s.x * s.x + s.y * s.y >= 1) continue;
            double d = evalPndfHierarchy(m, fp, s);
            if (d > 0) sum += d * weight(s);
        }
    return sum * hx * hy;
}

inline const char* kernelName(FootprintKernel k) {
    return k == FootprintKernel::Gaussian ? "gaussian" : k == FootprintKernel::Box ? "box" : "disk";
}

}  // namespace specula::pndf::testing
