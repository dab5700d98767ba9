// Light transport: a direct-lighting integrator (shadow rays + MIS with BSDF sampling) and a path
// tracer with next-event estimation and MIS; both split radiance into diffuse/specular AOVs.
#pragma once

#include "core/render/camera.h"
#include "core/render/environment_prefilter.h"
#include "core/render/lights.h"

#include "core/render/accel.h"
#include "core/render/bsdf.h"
#include "core/render/ray.h"
#include "core/render/sampler.h"
#include "core/render/shadow_maps.h"

#include <memory>

namespace specula {

struct Scene;

// Everything one camera sample contributes to the film.
struct SampleValue {
    Color3 beauty{0.f}, diffuse{0.f}, specular{0.f}, albedo{0.f};
    Vec3 normal{0.f};
    Vec2 uv{0.f};
    float depth = 1e10f;  // camera-space depth along the view axis; 1e10 where the ray escapes (as Cycles)
};

// Render setting "derivatives": "quad": the camera rays of a pixel's 2×2-quad partners along x ([0]) and y ([1])
// and the sign of the fine difference (+1 if the pixel is the quad's x0 / y0), filtered-ggx.md §5.2.
struct QuadRays {
    RayDifferential ray[2];
    float sign[2] = {1.f, 1.f};
};

// The preview's environment polygon: the hemisphere of the shading normal as a quad whose vertices sit this far
// above the horizon (a polygon exactly on the horizon degenerates under clipping); it misses ~1e-4 of the cosine.
inline constexpr float kRasterHemisphereLift = 0.01f;
// Spot cone falloff shared by SpotLight::sample and the raster paths: smoothstep between the cone cosines.
inline float rasterSpotFalloff(float cosAngle, const RasterLight& r) {
    if (cosAngle >= r.cosInner) return 1.f;
    if (cosAngle <= r.cosOuter) return 0.f;
    float t = (cosAngle - r.cosOuter) / std::max(r.cosInner - r.cosOuter, 1e-6f);
    return t * t * (3.f - 2.f * t);
}

// A camera sample's first vertex, traced and shaded ahead of Integrator::li by the batched camera stage
// (Integrator::shadeCameraHits, issue 37): what li would compute there itself, the same bits.
struct CameraVertex {
    bool found = false;   // the ray hit a surface the camera sees
    bool shaded = false;  // sp, closure and Le are set (false on a light's own geometry: lights do not scatter)
    Hit hit;
    ShadingPoint sp;
    Closure closure;      // its lobes live in the arena given to shadeCameraHits
    Color3 Le{0.f};       // emission towards the camera (emissive materials)
};

class Integrator {
public:
    Integrator(const Scene& scene, const Accel& accel);
    ~Integrator();
    // Radiance along a camera ray. 'arena' is reset at every path vertex. With 'quad', the camera hit's differentials
    // are the fine finite differences to the quad partners' hits and sp.quad holds their shaded frames. With 'first',
    // the camera vertex comes from shadeCameraHits for this ray (quad must be null then).
    SampleValue li(const RayDifferential& cameraRay, PixelSampler& sampler, ScratchArena& arena,
                   const QuadRays* quad = nullptr, const CameraVertex* first = nullptr) const;
    // The batched camera stage (issue 37 item 1): traces n camera rays as one coherent Embree stream, builds their
    // shading points, and shades them grouped by material, each material once per batch (Material::shadeBatch).
    // out[k] is what li(rays[k], ...) computes at its first vertex; the lobes go to 'arena', which must outlive the
    // li calls that use them.
    void shadeCameraHits(const RayDifferential* rays, size_t n, ScratchArena& arena, CameraVertex* out) const;

private:
    // Radiance arriving from escaped rays (sum over environment lights).
    Color3 environment(const Vec3& dir) const;
    // firstPass: the passes already made (shadeCameraHits makes the first one in its stream).
    bool intersectFromCamera(const Ray& cameraRay, Hit& hit, int firstPass = 0) const;
    Color3 meshLightEmission(const LightSample& ls, const Vec3& p, ScratchArena& arena) const;
    // render.integrator "raster": the GPU preview's direct lighting at a camera hit, delta lights shadowed by the
    // preview's shadow maps (docs/preview.md).
    void rasterLighting(const ShadingPoint& sp, const Closure& closure, SampleValue& out) const;
    // The raster integrator's shadow maps, built once per render when a pixel first needs them; the threads that
    // ask meanwhile help build them (tbb::collaborative_call_once).
    struct RasterShadows {
        std::vector<RasterLight> lights;  // scene.lights[i]->raster()
        ShadowLayout layout;
        std::vector<float> texels;
        std::vector<PrefilteredEnvironment> environments;  // per light; the environment lights' split-sum maps
    };
    struct RasterShadowState;
    const RasterShadows& rasterShadows() const;
    const Scene& scene_;
    const Accel& accel_;
    bool path_;
    bool raster_;
    int maxDepth_;
    uint32_t dimsPerBounce_;
    PerspectiveCamera camera_;  // footprints of secondary vertices (PerspectiveCamera::approximateDpDxy)
    float diffScale_;           // the renderer's differential shrink, max(1/8, 1/sqrt(spp))
    bool ltcLights_;            // render.area_lights == "ltc": polygon lights integrated by the lobes that can
    int ltcMaxDepth_;           // ... at path vertices up to this depth (0: camera hits), sampled deeper
    int ltcShadowRays_;         // shadow rays per analytic lobe and light (render.ltc_shadow_rays)
    std::unique_ptr<RasterShadowState> shadows_;
    // Per shape: whether its material reads differentials (Material::needsDerivatives; light geometry: true), so that
    // shading points of the others are built without them.
    std::vector<uint8_t> derivatives_;
};

}  // namespace specula
