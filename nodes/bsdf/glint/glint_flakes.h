// Explicit flakes for the glint lobe at close range (issue 38 item 3): a Voronoi tiling of UV space into flakes of a
// given size, each a flat platelet whose slope is drawn from the converged lobe, and the hand-over to C20's counting.
//
// Why: C20's glints are counted per pixel footprint, so a sparkle is always about one pixel wide however close the
// camera comes (grain, not flakes). Real flake paints and glitter hold platelets of a fixed size on the surface. Where
// the footprint is smaller than a flake, this header gives each shading point the one flake it lies on: a Gaussian
// lobe of RMS slope sigma_f in slope space around the flake's slope m_c. With m_c ~ N(0, Sigma - sigma_f^2 I) (Sigma
// the converged lobe's covariance, C21 Eq. 16) and a flake in a Voronoi cell with probability A (relative_area), the
// mean over the surface is A N(0, Sigma) = A P_B exactly (a Gaussian convolved with a Gaussian), the same mean as C20's
// cells with occupancy A, so the explicit flakes, the counted glints and the converged lobe agree in expectation.
// The weight of the explicit flakes falls from 1 to 0 as the footprint grows from half a flake to one flake
// (flakeWeight); C20 then counts one microfacet per flake area (log_density = ln(1 / flake_size^2)).
// The GLSL twin is spc_glint_flake in glint.glsl (same operations).
#pragma once

#include "core/math/math.h"
#include "nodes/bsdf/glint/glint_correlation.h"
#include "nodes/bsdf/glint/glint_counting.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace specula::glint {

// The footprint (in flake sizes) below which only explicit flakes show, and the one at which only C20's counting does.
constexpr float kFlakeExplicitBelow = 0.5f;
constexpr float kFlakeCountedFrom = 1.f;

// Weight of the explicit flakes for a footprint of geometric-mean width `width` (UV units) and flakes of size `size`:
// 1 - smoothstep(kFlakeExplicitBelow, kFlakeCountedFrom, width / size); 1 for a zero footprint (rays without
// differentials see the flake they hit), 0 when flakes are off (size <= 0).
inline float flakeWeight(float width, float size) {
    if (!(size > 0.f)) return 0.f;
    if (!(width > 0.f)) return 1.f;
    const float t = (width / size - kFlakeExplicitBelow) / (kFlakeCountedFrom - kFlakeExplicitBelow);
    const float x = std::clamp(t, 0.f, 1.f);
    return 1.f - x * x * (3.f - 2.f * x);
}

// Flakes are found in float cell coordinates uv / size: beyond 2^23 cells (or at a NaN uv) a float no longer tells
// neighbouring cells apart, and such points use C20's counting alone (flakeCoordinatesValid false).
constexpr float kFlakeCoordLimit = 8388608.f;
inline bool flakeCoordinatesValid(Vec2 uv, float size) {
    return std::abs(uv.x / size) < kFlakeCoordLimit && std::abs(uv.y / size) < kFlakeCoordLimit;
}

// The microfacet density C20 counts with when flakes are on: one per flake area, lambda = ln(1 / size^2).
inline float flakeLogDensity(float size) { return -2.f * std::log(size); }

// The flake lobe's RMS slope: at least 1e-3 (a NaN reads as 1e-3), then kept below sqrt(0.8) of the smallest principal
// RMS slope of Sigma so that the flake slopes' covariance Sigma - sigma_f^2 I stays positive definite (and the flakes'
// slopes still spread), and never below 1e-4 (a finite peak where Sigma is nearly singular, rho -> 0.99).
inline float flakeSigma(float sigmaF, const GlintShape& s) {
    const float a = s.sx * s.sx, c = s.sy * s.sy, b = s.rho * s.sx * s.sy;
    const float minEigen = 0.5f * (a + c - std::sqrt((a - c) * (a - c) + 4.f * b * b));
    const float hi = std::sqrt(0.8f * std::max(minEigen, 0.f));
    const float lo = sigmaF >= 1e-3f ? sigmaF : 1e-3f;
    return std::max(std::min(lo, hi), 1e-4f);
}

// The flake a point lies on: whether the Voronoi cell holds a flake, its slope m_c and its id (the cell).
struct Flake {
    bool present = false;
    Vec2 slope{0.f};  // m_c: the flake normal's slope (-n.x / n.z, -n.y / n.z) in the lobe's frame
    int cellX = 0, cellY = 0;
};

// The seed of Voronoi cell (x, y): wrapping uint32 arithmetic, distinct from C20's coherent cell seeds.
inline uint32_t flakeSeed(int x, int y) { return uint32_t(x) * 73856093u + uint32_t(y) * 19349663u + 83492791u; }

// F1 Voronoi over jittered points, one per unit cell of uv / size (3 x 3 neighbourhood, ties to the first found in
// row order): the cell whose point is nearest to uv.
inline void nearestFlakeCell(Vec2 uv, float size, int& cellX, int& cellY) {
    const float px = uv.x / size, py = uv.y / size;
    const float fx = std::floor(px), fy = std::floor(py);
    const int ix = int(fx), iy = int(fy);
    float best = 1e30f;
    cellX = ix, cellY = iy;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            const uint32_t S = flakeSeed(ix + dx, iy + dy);
            const float ox = (fx + float(dx)) + hashUniform(92821u * S) - px;
            const float oy = (fy + float(dy)) + hashUniform(68917u * S) - py;
            const float d2 = ox * ox + oy * oy;
            if (d2 < best) {
                best = d2;
                cellX = ix + dx;
                cellY = iy + dy;
            }
        }
}

// The flake of Voronoi cell (x, y): present with probability A, slope L_f z with L_f the Cholesky factor of
// Sigma - sigma_f^2 I and z ~ N(0, I) by Box-Muller from the cell's hashes.
inline Flake flakeOfCell(int cellX, int cellY, float relArea, const GlintShape& s, float sigmaF) {
    Flake f;
    f.cellX = cellX, f.cellY = cellY;
    const uint32_t S = flakeSeed(cellX, cellY);
    f.present = hashUniform(7919u * S) <= relArea;
    const float r = std::sqrt(-2.f * std::log(hashUniform(104729u * S)));
    const float phi = 2.f * kPi * hashUniform(1299709u * S);
    const float z1 = r * std::cos(phi), z2 = r * std::sin(phi);
    const float sf2 = sigmaF * sigmaF;
    const float l00 = std::sqrt(s.sx * s.sx - sf2);
    const float l10 = s.rho * s.sx * s.sy / l00;
    const float l11 = std::sqrt(std::max(s.sy * s.sy - sf2 - l10 * l10, 0.f));
    f.slope = Vec2(l00 * z1, l10 * z1 + l11 * z2);
    return f;
}

// The flake a point lies on.
inline Flake findFlake(Vec2 uv, float size, float relArea, const GlintShape& s, float sigmaF) {
    int cx, cy;
    nearestFlakeCell(uv, size, cx, cy);
    return flakeOfCell(cx, cy, relArea, s, sigmaF);
}

// The flakes of one pixel footprint, so that which flakes a pixel shows comes from the surface and not from where
// its samples fall: the footprint's box uv + duvdx s + duvdy t, s, t in [-1/2, 1/2], read at 4 x 4 points
// (s, t in {-3/8, -1/8, 1/8, 3/8}; one point, the centre, for a zero footprint), each flake weighted by its share of
// the points. The slope density is sum_k weight_k N(h~; m_k, sigma_f^2 I): the box-filtered flakes of the footprint,
// whose edges are antialiased by the points instead of by the pixel's samples (with footprint_centre "pixel", every
// sample of a pixel shades the same flakes). Points on a cell without a flake add nothing (sum of weights < 1).
struct FlakeSet {
    static constexpr int kPointsPerAxis = 4;
    static constexpr int kMaxFlakes = kPointsPerAxis * kPointsPerAxis;
    int count = 0;                 // distinct flakes with a platelet under the points
    float covered = 0.f;           // the sum of their weights
    Flake flakes[kMaxFlakes];
    float weight[kMaxFlakes] = {};
};
inline FlakeSet findFlakes(Vec2 uv, Vec2 duvdx, Vec2 duvdy, float size, float relArea, const GlintShape& s,
                           float sigmaF) {
    FlakeSet set;
    const bool point = duvdx == Vec2(0.f) && duvdy == Vec2(0.f);
    const int n = point ? 1 : FlakeSet::kPointsPerAxis;
    const float w = 1.f / float(n * n);
    int cells[FlakeSet::kMaxFlakes][2];
    int distinct = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const float ox = point ? 0.f : -0.375f + 0.25f * float(i), oy = point ? 0.f : -0.375f + 0.25f * float(j);
            const Vec2 p(uv.x + duvdx.x * ox + duvdy.x * oy, uv.y + duvdx.y * ox + duvdy.y * oy);
            int cx, cy;
            nearestFlakeCell(p, size, cx, cy);
            int k = 0;
            while (k < distinct && (cells[k][0] != cx || cells[k][1] != cy)) ++k;
            if (k == distinct) {
                cells[k][0] = cx, cells[k][1] = cy;
                ++distinct;
                const Flake f = flakeOfCell(cx, cy, relArea, s, sigmaF);
                if (!f.present) {
                    set.flakes[k].present = false;
                    continue;
                }
                set.flakes[k] = f;
            }
            if (set.flakes[k].present) set.weight[k] += w;
        }
    // Compact the present flakes to the front, in first-seen order.
    for (int k = 0; k < distinct; ++k) {
        if (!set.flakes[k].present) continue;
        set.flakes[set.count] = set.flakes[k];
        set.weight[set.count] = set.weight[k];
        set.covered += set.weight[k];
        ++set.count;
    }
    for (int k = set.count; k < FlakeSet::kMaxFlakes; ++k) set.weight[k] = 0.f;
    return set;
}

// The flake's slope density at half slope h~: N(h~; m_c, sigma_f^2 I), normalised over slope space like P_B.
inline float flakeSdf(Vec2 h, Vec2 slope, float sigmaF) {
    const Vec2 d = h - slope;
    const float v = sigmaF * sigmaF;
    return std::exp(-0.5f * (d.x * d.x + d.y * d.y) / v) / (2.f * kPi * v);
}

// The footprint's flake density sum_k weight_k N(h~; m_k, sigma_f^2 I).
inline float flakeSetSdf(const FlakeSet& set, Vec2 h, float sigmaF) {
    float p = 0.f;
    for (int k = 0; k < set.count; ++k) p += set.weight[k] * flakeSdf(h, set.flakes[k].slope, sigmaF);
    return p;
}

// A half slope with density flakeSdf: m_c + sigma_f z, z from Box-Muller on u in [0, 1)^2.
inline Vec2 sampleFlakeSlope(Vec2 slope, float sigmaF, Vec2 u) {
    const float r = std::sqrt(-2.f * std::log(std::max(1.f - u.x, 1e-12f)));
    const float phi = 2.f * kPi * u.y;
    return slope + sigmaF * Vec2(r * std::cos(phi), r * std::sin(phi));
}

}  // namespace specula::glint
