// Helpers shared by the shading and render tests: a shading point with ray differentials, rendering one AOV of a
// scene, and the image statistics the render and validation tests compare (header-only, so only the tests that use
// it rebuild).
#pragma once

#include "core/render/renderer.h"
#include "core/render/shading.h"
#include "core/scene/scene_loader.h"
#include "plugin/cli/validation_metrics.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace specula::test {

// A shading point at p = (1, 2, 3) with the world frame (normal +z, tangent +x), uv (0.25, 0.75), viewed from wo, with
// ray differentials dp = (0.01, 0.02), duv = (0.001, 0.002) and dn = (normalDerivative, normalDerivative) along x and
// y (dwo left zero), so that footprint-driven nodes and lobes filter.
inline ShadingPoint shadingPointWithDifferentials(const Vec3& wo, float normalDerivative) {
    ShadingPoint sp;
    sp.p = Vec3(1, 2, 3);
    sp.n = sp.ng = Vec3(0, 0, 1);
    sp.tangent = Vec4(1, 0, 0, 1);
    sp.uv = Vec2(0.25f, 0.75f);
    sp.frame = Frame();
    sp.wo = wo;
    sp.hasDifferentials = true;
    sp.dpdx = Vec3(0.01f, 0, 0);
    sp.dpdy = Vec3(0, 0.02f, 0);
    sp.duvdx = Vec2(0.001f, 0);
    sp.duvdy = Vec2(0, 0.002f);
    sp.dndx = Vec3(normalDerivative, 0, 0);
    sp.dndy = Vec3(0, normalDerivative, 0);
    return sp;
}

// Loads scene text (relative paths against baseDir), renders it and returns the pixels of one AOV ("beauty",
// "specular", ...); throws std::runtime_error when the render has no such AOV. pixelCentres: every sample at its
// pixel's centre (no coverage noise), whatever the scene says; false leaves the scene's choice.
inline std::vector<float> renderAov(const std::string& sceneText, const std::string& baseDir, const std::string& aov,
                                    bool pixelCentres = false) {
    Scene s = loadSceneFromString(sceneText, baseDir);
    if (pixelCentres) s.render.pixelCenter = true;
    RenderOutput r = renderScene(s);
    const AovBuffer* a = r.images.find(aov);
    if (!a) throw std::runtime_error("no " + aov + " AOV");
    return a->pixels;
}

// The specular AOV of a scene, as the validation tests compare it.
inline std::vector<float> specularAov(const std::string& sceneText, const std::string& baseDir) {
    return renderAov(sceneText, baseDir, "specular");
}

// RMSE over every pixel and channel of two RGB images: the code of `specula compare --mask all`.
inline double compareRmse(const std::vector<float>& a, const std::vector<float>& b) {
    return maskedError(a, b, 3).rmse;
}

// The mean green value of the pixels of a size x size RGB image whose centres lie at a distance in (r0, r1) from the
// image centre (the furnace tests' disc and ring of a centred sphere); *count: how many pixels that is.
inline double greenMeanInRing(const std::vector<float>& rgb, int size, double r0, double r1, int* count) {
    double sum = 0;
    int n = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double d = std::hypot(x + 0.5 - size / 2.0, y + 0.5 - size / 2.0);
            if (d <= r0 || d >= r1) continue;
            sum += rgb[(size_t(y) * size + x) * 3 + 1];
            ++n;
        }
    *count = n;
    return sum / n;
}

// Root mean square of a - b over every element (a double sum in element order).
inline double rmseOf(const std::vector<float>& a, const std::vector<float>& b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    return std::sqrt(s / a.size());
}

// The mean of a (a double sum in element order).
inline double meanOf(const std::vector<float>& a) {
    double s = 0;
    for (float v : a) s += v;
    return s / a.size();
}

}  // namespace specula::test
