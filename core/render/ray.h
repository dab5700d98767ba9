// Rays with optional differentials (offset rays one pixel step in x and y, pbrt-style).
#pragma once

#include "core/math/math.h"

#include <limits>

namespace specula {

struct Ray {
    Vec3 o{0.f}, d{0, 0, 1};
    float tMin = 0.f;
    float tMax = std::numeric_limits<float>::infinity();
};

struct RayDifferential : Ray {
    bool hasDifferentials = false;
    Vec3 rxOrigin{0.f}, ryOrigin{0.f};
    Vec3 rxDirection{0.f}, ryDirection{0.f};
    // The factor the differentials were shrunk by (1 = one pixel step): per-pixel quantities divide by it.
    float differentialScale = 1.f;
    // Camera rays: the sample's raster offset from its pixel centre, in pixels (the pixel filter's draw); 0 for every
    // other ray. Lets a footprint filter centre its kernel on the pixel rather than on the sample (bsdf.glint_pndf).
    Vec2 pixelOffset{0.f};

    // Shrinks the differentials to the footprint of one of several samples per pixel.
    void scaleDifferentials(float s) {
        differentialScale *= s;
        rxOrigin = o + (rxOrigin - o) * s;
        ryOrigin = o + (ryOrigin - o) * s;
        rxDirection = d + (rxDirection - d) * s;
        ryDirection = d + (ryDirection - d) * s;
    }
};

}  // namespace specula
