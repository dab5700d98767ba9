// How many microfacets a cell holds and which dictionary level shows them (spec S4.1-S4.5; C20 Alg. 3): the cell's
// coherent seed and hashed uniforms, occupancy u_A, and the level l_c = lambda/ln 4 + l - (L-1) jittered by erfinv.
#pragma once

#include "core/math/math.h"
#include "nodes/bsdf/glint/glint_dictionary.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace specula::glint {

// ---- per-cell random numbers (spec S4.1-S4.2) ---------------------------------------------------------------
// Coherent seed S = s*2^l + 1549*t*2^l in wrapping uint32 arithmetic (level-l cell = its level-0 corner child).
inline uint32_t cellSeed(int l, int s, int t) {
    const uint32_t p = 1u << l;
    return uint32_t(s) * p + 1549u * uint32_t(t) * p;
}
// Hugo-Elias integer hash as used by Quilez; H(n) in [0, 1], clamped to [2^-24, 1 - 2^-24] (spec recommendation).
inline float hashUniform(uint32_t n) {
    n = (n << 13u) ^ n;
    n = n * (n * n * 15731u + 789221u) + 1376312589u;
    const float u = float(n & 0x7fffffffu) / float(0x7fffffff);
    return std::clamp(u, 5.9604645e-8f, 0.99999994f);
}
struct CellRandom {
    float uA, uZ, uTheta, uI, uJ;
};
inline CellRandom cellRandom(uint32_t S) {
    return {hashUniform(13u * S), hashUniform(2171u * S), hashUniform(S), hashUniform(16807u * S), hashUniform(48271u * S)};
}

// Single-precision erfinv (Giles 2010, "Approximating the erfinv function", GPU Gems 4); same in GLSL.
inline float erfinvF(float x) {
    float w = -std::log((1.f - x) * (1.f + x)), p;
    if (w < 5.f) {
        w = w - 2.5f;
        p = 2.81022636e-08f;
        p = 3.43273939e-07f + p * w;
        p = -3.5233877e-06f + p * w;
        p = -4.39150654e-06f + p * w;
        p = 0.00021858087f + p * w;
        p = -0.00125372503f + p * w;
        p = -0.00417768164f + p * w;
        p = 0.246640727f + p * w;
        p = 1.50140941f + p * w;
    } else {
        w = std::sqrt(w) - 3.f;
        p = -0.000200214257f;
        p = 0.000100950558f + p * w;
        p = 0.00134934322f + p * w;
        p = -0.00367342844f + p * w;
        p = 0.00573950773f + p * w;
        p = -0.0076224613f + p * w;
        p = 0.00943887047f + p * w;
        p = 1.00167406f + p * w;
        p = 2.83297682f + p * w;
    }
    return p * x;
}

// ---- per-thread memo of the cells' random numbers ---------------------------------------------------------------
// Every random number of a cell is a function of its seed S alone (S4.2), whatever the material, and consecutive
// shading points revisit the same cells (the samples of one pixel, neighbouring pixels, the coarser of the two
// LODs): a direct-mapped table per thread keeps u_A, erfinv(2 u_z - 1), cos/sin theta and the marginal indices of
// the last 4096 seeds. A memo of a pure function: results do not depend on its state, hence not on threads.
struct CellMemoEntry {
    uint32_t seed;
    float uA, erfZ;  // u_A and erfinv(2 u_z - 1) (the material scales it by zeta sqrt 2 and adds l_c, S4.5)
    float cosT, sinT;
    uint8_t i, j, filled, pad;
};
struct CellMemo {
    static constexpr int kBits = 12;
    CellMemoEntry entries[1 << kBits];  // zero-initialised thread_local storage: filled = 0
    const CellMemoEntry& get(uint32_t S) {
        CellMemoEntry& e = entries[(S * 0x9E3779B1u) >> (32 - kBits)];
        if (e.filled && e.seed == S) return e;
        e.seed = S;
        e.uA = hashUniform(13u * S);
        e.erfZ = erfinvF(2.f * hashUniform(2171u * S) - 1.f);
        const float theta = 2.f * kPi * hashUniform(S);  // as cellSdf: the same floats
        e.cosT = std::cos(theta);
        e.sinT = std::sin(theta);
        e.i = uint8_t(std::min(int(float(kMarginals) * hashUniform(16807u * S)), kMarginals - 1));
        e.j = uint8_t(std::min(int(float(kMarginals) * hashUniform(48271u * S)), kMarginals - 1));
        e.filled = 1;
        return e;
    }
};
inline CellMemo& cellMemo() {
    static thread_local CellMemo memo;
    return memo;
}

// The dictionary LOD k of a non-empty cell (S4.4-S4.5): l_d = l_c + zeta sqrt(2) erfinv(2 u_z - 1), k = clamp(round(l_d),
// 0, L); k = L means converged (analytic P_B). S is the cell seed; zeta = 0 skips the hash (0 * erfinv = 0).
// dictionaryLod takes erfinv(2 u_z - 1) already computed (CellMemoEntry::erfZ).
inline int dictionaryLod(float lc, float jitter, float erfZ) {
    const float ld = jitter != 0.f ? lc + jitter * 1.41421356f * erfZ : lc;
    return int(std::clamp(std::floor(ld + 0.5f), 0.f, float(kLevels)));
}
inline int cellDictionaryLod(uint32_t S, float lc, float jitter) {
    return dictionaryLod(lc, jitter, jitter != 0.f ? erfinvF(2.f * hashUniform(2171u * S) - 1.f) : 0.f);
}
inline int marginalIndex(float u) { return std::min(int(float(kMarginals) * u), kMarginals - 1); }

}  // namespace specula::glint
