// Helpers shared by the unit tests: temporary directories, running the CLI, reading files.
#pragma once

#include "core/render/bsdf.h"
#include "core/render/sampler.h"

#include <limits>
#include <string>

namespace specula::test {

// Deterministic uniform floats in [0, 1) for Monte Carlo checks (24-bit, from mix64 of a counter).
struct Rng {
    uint64_t s;
    float next() { return float(mix64(++s) >> 40) * (1.f / 16777216.f); }
    Vec2 next2() {
        float a = next();
        return {a, next()};
    }
};

// A direction query of a closure (world-space wo, wi), as the integrator asks it.
inline BsdfValue query(const Closure& c, const Vec3& wo, const Vec3& wi,
                       float lightDistance = std::numeric_limits<float>::infinity(), LobeMask lobes = kAllLobes) {
    BsdfQuery q;
    q.wo = wo;
    q.wi = wi;
    q.lightDistance = lightDistance;
    q.lobes = lobes;
    return c.evalPdf(q);
}
inline bool sample(const Closure& c, const Vec3& wo, float uLobe, const Vec2& u, BsdfSample& out) {
    BsdfQuery q;
    q.wo = wo;
    return c.sample(q, uLobe, u, out);
}

// A fresh empty directory under the system temp dir, removed at process exit.
std::string tempDir(const std::string& tag);
// Runs the specula CLI with 'args' (shell-quoted by the caller); returns the exit code and
// captures stdout+stderr into 'output'.
int runCli(const std::string& args, std::string* output = nullptr);
std::string readFile(const std::string& path);
void writeFile(const std::string& path, const std::string& text);
std::string sourcePath(const std::string& relative);  // path inside the source tree

}  // namespace specula::test
