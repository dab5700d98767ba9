// Procedural normal maps: integer hashing (lowbias32), periodic Perlin gradient noise with analytic
// derivatives, periodic Voronoi cells and rasterised V-groove scratches; all arithmetic in double with
// +, -, *, /, sqrt and floor only, so a (kind, size, seed) triple always yields the same map.
#include "core/texture/normal_map_gen.h"

#include "core/io/image_io.h"

#include <OpenImageIO/imageio.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>
#include <cmath>
#include <filesystem>

namespace specula {

namespace {

// ---- hashing -------------------------------------------------------------------------------------
// lowbias32 (C. Wellons, "Prospecting for hash functions", 2018): a full-avalanche 32-bit mixer.
inline uint32_t mix32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352dU;
    x ^= x >> 15;
    x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

struct Hash {
    uint32_t seed;
    uint32_t operator()(uint32_t a, uint32_t b = 0, uint32_t c = 0) const {
        return mix32(seed ^ mix32(a + 0x9e3779b9U * mix32(b ^ mix32(c + 0x85ebca6bU))));
    }
    // Uniform in [0, 1) with 24 bits.
    double u(uint32_t a, uint32_t b = 0, uint32_t c = 0) const { return double((*this)(a, b, c) >> 8) * (1.0 / 16777216.0); }
    // Approximately N(0, 1): Irwin-Hall sum of four uniforms, rescaled to unit variance (only + and *).
    double gauss(uint32_t a, uint32_t b, uint32_t c) const {
        double s = u(a, b, c * 4 + 0) + u(a, b, c * 4 + 1) + u(a, b, c * 4 + 2) + u(a, b, c * 4 + 3);
        return (s - 2.0) * 1.7320508075688772;  // var(sum of 4 U(0,1)) = 1/3
    }
};

Hash makeHash(uint64_t seed, NormalMapKind kind, uint32_t salt) {
    uint32_t s = uint32_t(seed) ^ mix32(uint32_t(seed >> 32) + 0x632be5abU);
    return Hash{mix32(s + 0x27d4eb2fU * (uint32_t(kind) + 1U) + 0x165667b1U * salt)};
}

inline int wrapInt(long long i, int p) {
    long long r = i % p;
    return int(r < 0 ? r + p : r);
}

// ---- periodic gradient noise (Perlin 2002 quintic fade) with analytic derivatives ---------------------
// 16 gradient directions at 22.5 degree steps (literal values: no libm in the generator).
constexpr double kGrad[16][2] = {{1.0, 0.0},
                                 {0.9238795325112867, 0.3826834323650898},
                                 {0.7071067811865476, 0.7071067811865476},
                                 {0.3826834323650898, 0.9238795325112867},
                                 {0.0, 1.0},
                                 {-0.3826834323650898, 0.9238795325112867},
                                 {-0.7071067811865476, 0.7071067811865476},
                                 {-0.9238795325112867, 0.3826834323650898},
                                 {-1.0, 0.0},
                                 {-0.9238795325112867, -0.3826834323650898},
                                 {-0.7071067811865476, -0.7071067811865476},
                                 {-0.3826834323650898, -0.9238795325112867},
                                 {0.0, -1.0},
                                 {0.3826834323650898, -0.9238795325112867},
                                 {0.7071067811865476, -0.7071067811865476},
                                 {0.9238795325112867, -0.3826834323650898}};

struct NoiseSample {
    double value, dx, dy;  // value and derivatives in lattice units
};

// Gradient noise on a lattice periodic with (px, py) cells; 'octave' decorrelates layers.
NoiseSample gradientNoise(double x, double y, int px, int py, const Hash& H, uint32_t octave) {
    double fx0 = std::floor(x), fy0 = std::floor(y);
    long long ix = (long long)fx0, iy = (long long)fy0;
    double fx = x - fx0, fy = y - fy0;
    int x0 = wrapInt(ix, px), x1 = wrapInt(ix + 1, px), y0 = wrapInt(iy, py), y1 = wrapInt(iy + 1, py);
    auto g = [&](int i, int j) { return kGrad[H(uint32_t(i), uint32_t(j), octave) & 15U]; };
    const double* g00 = g(x0, y0);
    const double* g10 = g(x1, y0);
    const double* g01 = g(x0, y1);
    const double* g11 = g(x1, y1);
    double n00 = g00[0] * fx + g00[1] * fy;
    double n10 = g10[0] * (fx - 1) + g10[1] * fy;
    double n01 = g01[0] * fx + g01[1] * (fy - 1);
    double n11 = g11[0] * (fx - 1) + g11[1] * (fy - 1);
    auto fade = [](double t) { return t * t * t * (t * (t * 6 - 15) + 10); };
    auto dfade = [](double t) { return 30 * t * t * (t - 1) * (t - 1); };
    double a = fade(fx), b = fade(fy), da = dfade(fx), db = dfade(fy);
    double k = n00 - n10 - n01 + n11;
    NoiseSample s;
    s.value = n00 + a * (n10 - n00) + b * (n01 - n00) + a * b * k;
    s.dx = g00[0] + a * (g10[0] - g00[0]) + b * (g01[0] - g00[0]) + a * b * (g00[0] - g10[0] - g01[0] + g11[0]) +
           da * ((n10 - n00) + b * k);
    s.dy = g00[1] + a * (g10[1] - g00[1]) + b * (g01[1] - g00[1]) + a * b * (g00[1] - g10[1] - g01[1] + g11[1]) +
           db * ((n01 - n00) + a * k);
    return s;
}

// Height gradient field (dh/du, dh/dv) on the texel grid, indexed [yv * N + x] with yv = 0 the BOTTOM row.
struct Gradients {
    int n = 0;
    std::vector<double> gx, gy;
    explicit Gradients(int size) : n(size), gx(size_t(size) * size, 0.0), gy(size_t(size) * size, 0.0) {}
    size_t idx(int x, int yv) const { return size_t(yv) * size_t(n) + size_t(x); }
    double rmsPerAxis() const {
        double s = 0;
        for (size_t i = 0; i < gx.size(); ++i) s += gx[i] * gx[i] + gy[i] * gy[i];
        return std::sqrt(s / (2.0 * double(gx.size())));
    }
    // Scales the field so that its per-axis RMS slope equals 'target' (a flat field stays flat).
    void normalize(double target) {
        double r = rmsPerAxis();
        if (r <= 0) return;
        double k = target / r;
        for (size_t i = 0; i < gx.size(); ++i) gx[i] *= k, gy[i] *= k;
    }
    void add(const Gradients& o) {
        for (size_t i = 0; i < gx.size(); ++i) gx[i] += o.gx[i], gy[i] += o.gy[i];
    }
};

template <class F>
void forEachRow(int n, F f) {
    tbb::parallel_for(0, n, [&](int yv) { f(yv); });
}

// Isotropic fractal gradient noise: octaves with lattice periods p0, 2 p0, ... (while >= 'minTexels' texels
// per lattice cell); octave o has height weight 'persistence'^o / period (slope weight 'persistence'^o).
Gradients fractalNoise(int n, int p0, int octaves, double persistence, double minTexels, const Hash& H, uint32_t salt) {
    Gradients G(n);
    struct Oct {
        int p;
        double w;
    };
    std::vector<Oct> octs;
    double w = 1.0;
    for (int o = 0, p = std::max(1, p0); o < octaves; ++o, p *= 2, w *= persistence) {
        if (o > 0 && double(n) / p < minTexels) break;
        octs.push_back({p, w});
    }
    forEachRow(n, [&](int yv) {
        for (int x = 0; x < n; ++x) {
            double u = (x + 0.5) / n, v = (yv + 0.5) / n;
            double sx = 0, sy = 0;
            for (size_t o = 0; o < octs.size(); ++o) {
                NoiseSample s = gradientNoise(u * octs[o].p, v * octs[o].p, octs[o].p, octs[o].p, H, salt + uint32_t(o));
                // height = w/p * noise(u p, v p): dh/du = w * dnoise/dx.
                sx += octs[o].w * s.dx;
                sy += octs[o].w * s.dy;
            }
            G.gx[G.idx(x, yv)] = sx;
            G.gy[G.idx(x, yv)] = sy;
        }
    });
    return G;
}

// ---- kinds -------------------------------------------------------------------------------------------
Gradients bumps(int n, uint64_t seed) {
    Hash H = makeHash(seed, NormalMapKind::Bumps, 0);
    Gradients G = fractalNoise(n, std::max(2, int(n / 64)), 4, 0.6, 4.0, H, 0);
    G.normalize(0.25);
    return G;
}

Gradients brushed(int n, uint64_t seed, int A = 2, int B = 1) {
    Hash H = makeHash(seed, NormalMapKind::Brushed, 0);
    // Grooves run along d = (A, B)/|(A, B)|, (2, 1) by default. Across-coordinate w = -B u + A v, along-coordinate
    // a = A u + B v: integer coefficients keep every octave periodic over the unit tile. One lattice cell across spans
    // n/(P |(A, B)|) texels, so P is scaled by sqrt(5)/|(A, B)| to keep the default direction's groove width.
    struct Oct {
        int pw, pa;
        double w;
    };
    std::vector<Oct> octs;
    const double across[4] = {6.0, 12.0, 24.0, 48.0};  // n / (P_w) ... finest first
    const int along[4] = {1, 1, 1, 1};
    const double weight[4] = {1.0, 0.7, 0.5, 0.35};
    for (int o = 0; o < 4; ++o) {
        const double widthScale = std::sqrt(5.0) / std::sqrt(double(A * A + B * B));
        int pw = std::max(1, int(std::floor(n / across[o] * widthScale + 0.5)));
        octs.push_back({pw, along[o], weight[o]});
    }
    Gradients G(n);
    forEachRow(n, [&](int yv) {
        for (int x = 0; x < n; ++x) {
            double u = (x + 0.5) / n, v = (yv + 0.5) / n;
            double w = -B * u + A * v, a = A * u + B * v;
            double sx = 0, sy = 0;
            for (size_t o = 0; o < octs.size(); ++o) {
                const Oct& O = octs[o];
                NoiseSample s = gradientNoise(w * O.pw, a * O.pa, O.pw, O.pa, H, uint32_t(o));
                // h = c/pw * noise(pw w, pa a): dh/du = c (-B ds + A pa/pw dt), dh/dv = c (A ds + B pa/pw dt).
                double r = double(O.pa) / O.pw;
                sx += O.w * (-B * s.dx + A * r * s.dy);
                sy += O.w * (A * s.dx + B * r * s.dy);
            }
            G.gx[G.idx(x, yv)] = sx;
            G.gy[G.idx(x, yv)] = sy;
        }
    });
    // Principal RMS slope across the grooves ~0.2 (normalize() uses the per-axis RMS: |g|^2/2).
    G.normalize(0.2 / std::sqrt(2.0));
    Gradients fine = fractalNoise(n, std::max(2, int(n / 16)), 2, 0.7, 3.0, makeHash(seed, NormalMapKind::Brushed, 1), 0);
    fine.normalize(0.025);
    G.add(fine);
    return G;
}

Gradients scratches(int n, uint64_t seed) {
    Hash H = makeHash(seed, NormalMapKind::Scratches, 0);
    Gradients G = fractalNoise(n, std::max(2, int(n / 32)), 2, 0.5, 4.0, makeHash(seed, NormalMapKind::Scratches, 1), 0);
    G.normalize(0.008);  // faint base roughness: a polished, not mathematically flat, surface
    std::vector<double> depth(size_t(n) * n, 0.0);  // deepest groove so far (negative height), 0 = none
    const int count = std::max(4, int((double(n) * n) / 1200.0));
    for (int k = 0; k < count; ++k) {
        uint32_t id = uint32_t(k);
        double cx = H.u(id, 1) * n, cy = H.u(id, 2) * n;
        // Direction: rejection sample in the unit disk with a deterministic hash stream, then normalise.
        double dx = 1, dy = 0;
        for (uint32_t t = 0; t < 64; ++t) {
            double a = 2 * H.u(id, 3, t) - 1, b = 2 * H.u(id, 4, t) - 1, l2 = a * a + b * b;
            if (l2 > 1e-4 && l2 <= 1) {
                double l = std::sqrt(l2);
                dx = a / l, dy = b / l;
                break;
            }
        }
        double len = n * (0.05 + 0.35 * H.u(id, 5));
        double hw = 1.0 + 0.75 * H.u(id, 6);               // half width, texels
        double dep = hw * (0.3 + 0.5 * H.u(id, 7));        // wall slope dep/hw in [0.3, 0.8]
        double taper = 0.15 * len;
        double ex = std::abs(dx) * len / 2 + hw + 1, ey = std::abs(dy) * len / 2 + hw + 1;
        int x0 = int(std::floor(cx - ex)), x1 = int(std::ceil(cx + ex)), y0 = int(std::floor(cy - ey)), y1 = int(std::ceil(cy + ey));
        for (int yy = y0; yy <= y1; ++yy)
            for (int xx = x0; xx <= x1; ++xx) {
                double px = xx + 0.5 - cx, py = yy + 0.5 - cy;
                double along = px * dx + py * dy, across = -px * dy + py * dx;
                double aa = std::abs(along), ac = std::abs(across);
                if (aa > len / 2 || ac >= hw) continue;
                // Taper T(along) ramps the depth over the last 'taper' texels; profile P = 1 - |across|/hw.
                double rem = len / 2 - aa;
                double T = rem >= taper ? 1.0 : rem / taper;
                double dT = rem >= taper ? 0.0 : -(along >= 0 ? 1.0 : -1.0) / taper;  // dT/d(along)
                double P = 1 - ac / hw, dP = -(across >= 0 ? 1.0 : -1.0) / hw;      // dP/d(across)
                double h = -dep * T * P;
                size_t i = G.idx(wrapInt(xx, n), wrapInt(yy, n));
                if (!(h < depth[i])) continue;
                depth[i] = h;
                // grad h = -dep (dT P dir + T dP perp), perp = (-dy, dx); texel units (slope per texel).
                double gxs = -dep * (dT * P * dx + T * dP * -dy);
                double gys = -dep * (dT * P * dy + T * dP * dx);
                G.gx[i] = gxs;
                G.gy[i] = gys;
            }
    }
    return G;
}

// Jittered-grid Voronoi on the unit torus with m x m cells: nearest and second-nearest feature points.
struct Voronoi {
    int m;
    Hash H;
    double jitter;
    void point(int ci, int cj, double& px, double& py) const {
        int wi = wrapInt(ci, m), wj = wrapInt(cj, m);
        px = ci + 0.5 + jitter * (H.u(uint32_t(wi), uint32_t(wj), 11) - 0.5);
        py = cj + 0.5 + jitter * (H.u(uint32_t(wi), uint32_t(wj), 12) - 0.5);
    }
    // q in cell units; returns the nearest cell (wrapped) and distances.
    void query(double qx, double qy, int& id1, double& f1, double& edge) const {
        int ci = int(std::floor(qx)), cj = int(std::floor(qy));
        double b1 = 1e30, b2 = 1e30;
        double p1x = 0, p1y = 0, p2x = 0, p2y = 0;
        int c1 = 0;
        for (int dj = -2; dj <= 2; ++dj)
            for (int di = -2; di <= 2; ++di) {
                double px, py;
                point(ci + di, cj + dj, px, py);
                double d2 = (px - qx) * (px - qx) + (py - qy) * (py - qy);
                if (d2 < b1) {
                    b2 = b1, p2x = p1x, p2y = p1y;
                    b1 = d2, p1x = px, p1y = py;
                    c1 = wrapInt(cj + dj, m) * m + wrapInt(ci + di, m);
                } else if (d2 < b2) {
                    b2 = d2, p2x = px, p2y = py;
                }
            }
        id1 = c1;
        f1 = std::sqrt(b1);
        double sep = std::sqrt((p2x - p1x) * (p2x - p1x) + (p2y - p1y) * (p2y - p1y));
        edge = sep > 0 ? (b2 - b1) / (2 * sep) : 0.0;  // exact distance to the bisector of the two nearest points
    }
};

NormalMap flakes(int n, uint64_t seed) {
    Hash H = makeHash(seed, NormalMapKind::Flakes, 0);
    Voronoi V{std::max(2, int(std::floor(n / 8.0 + 0.5))), H, 0.9};
    NormalMap map;
    map.size = n;
    map.normals.resize(size_t(n) * n);
    const double sigma = 0.35;
    forEachRow(n, [&](int yv) {
        for (int x = 0; x < n; ++x) {
            int id;
            double f1, edge;
            V.query((x + 0.5) / n * V.m, (yv + 0.5) / n * V.m, id, f1, edge);
            double sx = sigma * H.gauss(uint32_t(id), 21, 0), sy = sigma * H.gauss(uint32_t(id), 22, 0);
            DVec3 nn(-sx, -sy, 1.0);
            nn /= std::sqrt(nn.x * nn.x + nn.y * nn.y + 1.0);
            map.normals[size_t(n - 1 - yv) * n + x] = Vec3(nn);
        }
    });
    return map;
}

Gradients stone(int n, uint64_t seed) {
    Hash H = makeHash(seed, NormalMapKind::Stone, 0);
    Voronoi V{std::max(2, int(std::floor(n / 40.0 + 0.5))), H, 0.8};
    std::vector<double> h(size_t(n) * n);
    const double r = 0.22;  // bevel radius, cell units
    forEachRow(n, [&](int yv) {
        for (int x = 0; x < n; ++x) {
            int id;
            double f1, e;
            V.query((x + 0.5) / n * V.m, (yv + 0.5) / n * V.m, id, f1, e);
            double t = std::min(e, r) / r;                 // 0 at the mortar line, 1 inside
            double bevel = std::sqrt(t * (2 - t));          // quarter-circle profile
            double crown = 1.0 + 0.6 * H.u(uint32_t(id), 31);  // stone-specific height
            double dome = 0.35 * std::min(e, 0.5);          // gentle crown towards the middle
            h[size_t(yv) * n + x] = crown * (0.25 * bevel + dome);
        }
    });
    // Central differences (periodic), in units of cell height per texel; scaled by normalize() below.
    Gradients G(n);
    forEachRow(n, [&](int yv) {
        for (int x = 0; x < n; ++x) {
            auto at = [&](int xx, int yy) { return h[size_t(wrapInt(yy, n)) * n + size_t(wrapInt(xx, n))]; };
            G.gx[G.idx(x, yv)] = 0.5 * (at(x + 1, yv) - at(x - 1, yv));
            G.gy[G.idx(x, yv)] = 0.5 * (at(x, yv + 1) - at(x, yv - 1));
        }
    });
    G.normalize(0.24);
    Gradients grain = fractalNoise(n, std::max(2, int(n / 32)), 3, 0.6, 3.0, makeHash(seed, NormalMapKind::Stone, 1), 0);
    grain.normalize(0.12);
    G.add(grain);
    return G;
}

NormalMap fromGradients(const Gradients& G) {
    NormalMap map;
    const int n = G.n;
    map.size = n;
    map.normals.resize(size_t(n) * n);
    for (int yv = 0; yv < n; ++yv)
        for (int x = 0; x < n; ++x) {
            // Slope (x~, y~) = (-nx/nz, -ny/nz) = grad h  =>  n = (-dh/du, -dh/dv, 1)/|.| (glint-brdf.md §1).
            double gx = G.gx[G.idx(x, yv)], gy = G.gy[G.idx(x, yv)];
            double inv = 1.0 / std::sqrt(gx * gx + gy * gy + 1.0);
            map.normals[size_t(n - 1 - yv) * n + x] = Vec3(float(-gx * inv), float(-gy * inv), float(inv));
        }
    return map;
}

uint16_t quantize16(float n) {
    double c = (double(n) + 1.0) * 0.5;
    c = std::min(1.0, std::max(0.0, c));
    return uint16_t(std::floor(c * 65535.0 + 0.5));
}

}  // namespace

const char* normalMapKindName(NormalMapKind k) {
    switch (k) {
        case NormalMapKind::Bumps: return "bumps";
        case NormalMapKind::Brushed: return "brushed";
        case NormalMapKind::Scratches: return "scratches";
        case NormalMapKind::Flakes: return "flakes";
        case NormalMapKind::Stone: return "stone";
    }
    return "?";
}

const std::vector<NormalMapKind>& allNormalMapKinds() {
    static const std::vector<NormalMapKind> k = {NormalMapKind::Bumps, NormalMapKind::Brushed, NormalMapKind::Scratches,
                                                 NormalMapKind::Flakes, NormalMapKind::Stone};
    return k;
}

NormalMapKind parseNormalMapKind(const std::string& name) {
    for (NormalMapKind k : allNormalMapKinds())
        if (name == normalMapKindName(k)) return k;
    throw NormalMapError("unknown normal-map kind '" + name + "' (expected bumps, brushed, scratches, flakes or stone)");
}

NormalMap generateNormalMap(NormalMapKind kind, int size, uint64_t seed) {
    if (size < 8 || size > 8192) throw NormalMapError("normal-map size " + std::to_string(size) + " is outside 8..8192");
    switch (kind) {
        case NormalMapKind::Bumps: return fromGradients(bumps(size, seed));
        case NormalMapKind::Brushed: return fromGradients(brushed(size, seed));
        case NormalMapKind::Scratches: return fromGradients(scratches(size, seed));
        case NormalMapKind::Flakes: return flakes(size, seed);
        case NormalMapKind::Stone: return fromGradients(stone(size, seed));
    }
    throw NormalMapError("invalid normal-map kind");
}

NormalMap generateBrushedNormalMap(int size, uint64_t seed, double angleDegrees, double* usedAngleDegrees) {
    if (size < 8 || size > 8192) throw NormalMapError("normal-map size " + std::to_string(size) + " is outside 8..8192");
    if (!std::isfinite(angleDegrees)) throw NormalMapError("brush angle must be a finite number of degrees");
    // A groove direction repeats after 180 degrees; the tile stays seamless only for integer directions (A, B), so the
    // nearest one with |A|, B <= 8 is used (the default 26.565 degrees is (2, 1) exactly).
    const double want = std::fmod(std::fmod(angleDegrees, 180.0) + 180.0, 180.0);
    int bestA = 2, bestB = 1;
    double bestErr = 1e9;
    for (int b = 0; b <= 8; ++b)
        for (int a = -8; a <= 8; ++a) {
            if ((a == 0 && b == 0) || std::gcd(std::abs(a), b) != 1 || (b == 0 && a < 0)) continue;
            const double angle = std::atan2(double(b), double(a)) * 180.0 / 3.14159265358979323846;
            double err = std::abs(angle - want);
            err = std::min(err, 180.0 - err);
            if (err < bestErr - 1e-9 || (std::abs(err - bestErr) <= 1e-9 && std::abs(a) + b < std::abs(bestA) + bestB))
                bestErr = err, bestA = a, bestB = b;
        }
    if (usedAngleDegrees) *usedAngleDegrees = std::atan2(double(bestB), double(bestA)) * 180.0 / 3.14159265358979323846;
    return fromGradients(brushed(size, seed, bestA, bestB));
}

void writeNormalMap(const NormalMap& map, const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (auto& c : ext) c = char(std::tolower((unsigned char)c));
    const bool isFloat = ext == ".exr";
    if (!isFloat && ext != ".png" && ext != ".tif" && ext != ".tiff")
        throw NormalMapError("normal map '" + path + "': unsupported extension (use .exr, .png or .tif)");
    const int n = map.size;
    if (n <= 0 || map.normals.size() != size_t(n) * n) throw NormalMapError("normal map '" + path + "': empty map");
    std::string tmp;
    try {
        tmp = createTempFileNear(path);
    } catch (const ImageIoError& e) {
        throw NormalMapError("normal map '" + path + "': " + e.what());
    }
    auto out = OIIO::ImageOutput::create(path);  // format from the final name, data to the temp file
    if (!out) throw NormalMapError("normal map '" + path + "': no writer: " + OIIO::geterror());
    OIIO::ImageSpec spec(n, n, 3, isFloat ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT16);
    spec.attribute("Software", "specula normalmap");
    spec.attribute("specula:normalmap", "tangent space, OpenGL (+Y = +v), colour = (n + 1)/2");
    if (isFloat) spec.attribute("compression", "zip");
    bool ok = out->open(tmp, spec);
    if (ok) {
        if (isFloat) {
            std::vector<float> px(size_t(n) * n * 3);
            for (size_t i = 0; i < map.normals.size(); ++i)
                for (int k = 0; k < 3; ++k) px[i * 3 + size_t(k)] = (map.normals[i][k] + 1.f) * 0.5f;
            ok = out->write_image(OIIO::TypeDesc::FLOAT, px.data());
        } else {
            std::vector<uint16_t> px(size_t(n) * n * 3);
            for (size_t i = 0; i < map.normals.size(); ++i)
                for (int k = 0; k < 3; ++k) px[i * 3 + size_t(k)] = quantize16(map.normals[i][k]);
            ok = out->write_image(OIIO::TypeDesc::UINT16, px.data());
        }
        ok = out->close() && ok;
    }
    if (!ok) {
        std::string err = out->geterror();
        std::error_code ec;
        std::filesystem::remove(tmp, ec);
        throw NormalMapError("cannot write normal map '" + path + "': " + err);
    }
    try {
        commitTempFile(tmp, path);
    } catch (const ImageIoError& e) {
        throw NormalMapError("normal map '" + path + "': " + e.what());
    }
}

uint64_t normalMapHash(const NormalMap& map) {
    uint64_t h = 0xcbf29ce484222325ULL;
    auto byte = [&](uint8_t b) {
        h ^= b;
        h *= 0x100000001b3ULL;
    };
    for (int k = 0; k < 4; ++k) byte(uint8_t(uint32_t(map.size) >> (8 * k)));
    for (const Vec3& v : map.normals)
        for (int k = 0; k < 3; ++k) {
            uint16_t q = quantize16(v[k]);
            byte(uint8_t(q & 0xff));
            byte(uint8_t(q >> 8));
        }
    return h;
}

double SlopeStats::sigmaX() const { return std::sqrt(std::max(varX, 0.0)); }
double SlopeStats::sigmaY() const { return std::sqrt(std::max(varY, 0.0)); }
double SlopeStats::rho() const {
    double d = sigmaX() * sigmaY();
    return d > 0 ? covXY / d : 0.0;
}
double SlopeStats::sigmaMajor() const {
    double tr = varX + varY, det = varX * varY - covXY * covXY;
    double disc = std::sqrt(std::max(tr * tr / 4 - det, 0.0));
    return std::sqrt(std::max(tr / 2 + disc, 0.0));
}
double SlopeStats::sigmaMinor() const {
    double tr = varX + varY, det = varX * varY - covXY * covXY;
    double disc = std::sqrt(std::max(tr * tr / 4 - det, 0.0));
    return std::sqrt(std::max(tr / 2 - disc, 0.0));
}

SlopeStats slopeStats(const NormalMap& map) {
    SlopeStats s;
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    for (const Vec3& v : map.normals) {
        double x = -double(v.x) / v.z, y = -double(v.y) / v.z;
        sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y;
    }
    double inv = map.normals.empty() ? 0.0 : 1.0 / double(map.normals.size());
    s.meanX = sx * inv, s.meanY = sy * inv;
    s.varX = sxx * inv - s.meanX * s.meanX;
    s.varY = syy * inv - s.meanY * s.meanY;
    s.covXY = sxy * inv - s.meanX * s.meanY;
    return s;
}

}  // namespace specula
