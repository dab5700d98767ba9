// Light sources: point, spot, directional (delta lights), one-sided quad area lights (also hit by
// rays, with a polygon hook for analytic integration) and constant / image environment lights.
#pragma once

#include "core/render/distribution.h"
#include "core/render/ray.h"

#include <memory>
#include <string>
#include <vector>

namespace specula {

struct LightSample {
    Vec3 wi{0.f};       // unit direction from the shading point towards the light
    float distance = 0.f;  // distance to the sampled point (infinity for directional/environment)
    Color3 L{0.f};      // incident radiance (delta lights: intensity/d² or irradiance, with pdf = 1)
    float pdf = 0.f;    // solid-angle pdf; 1 for delta lights
    bool delta = false;
    // Mesh lights: the sampled point (shape, triangle, barycentrics of its vertices 1 and 2). L is left 0: the
    // integrator shades the shape's material there for its emission.
    int shape = -1;
    uint32_t prim = 0;
    Vec2 bary{0.f};
};

// A light as a rasteriser sees it (the GPU preview and the CPU "raster" integrator that matches it): the parameters
// of the closed-form light models, no sampling. Environment maps are described by their constant part only.
struct RasterLight {
    // Mesh: an emissive mesh, which the rasteriser does not light with (docs/preview.md); always after the others.
    enum class Kind { Point, Spot, Directional, Quad, Environment, Mesh } kind = Kind::Point;
    Vec3 position{0.f};                // point, spot; quad: the corner
    Vec3 direction{0.f, 0.f, -1.f};    // spot: cone axis; directional: towards the light; quad: edge u
    Vec3 edgeV{0.f};                   // quad: edge v (emits on the side of cross(edgeU, edgeV), or both)
    Color3 value{0.f};                 // W/sr (point, spot), W/m² (directional), W/(m²·sr) (quad, environment)
    float cosOuter = -1.f, cosInner = -1.f;  // spot cone
    bool twoSided = false;
    bool cameraVisible = true;         // quad: drawn as an emitter for the camera (Light::cameraVisible)
    bool hasMap = false;               // environment with an image (the rasteriser lights with its mean radiance)
    // Environment map (hasMap): the lat-long texels (rows top to bottom, RGB), looked up by the nearest texel as
    // EnvironmentLight::radiance does, times mapScale, the map turned by mapRotation (radians) about +z.
    const float* map = nullptr;
    int mapWidth = 0, mapHeight = 0;
    float mapRotation = 0.f;
    Color3 mapScale{1.f};
};

class Light {
public:
    virtual ~Light() = default;
    virtual bool sample(const Vec3& p, const Vec2& u, LightSample& s) const = 0;
    // Solid-angle pdf that sample() would produce wi from p, given the ray hit the light at distance t
    // (area lights) or escaped (environment). Delta lights: 0.
    virtual float pdf(const Vec3& p, const Vec3& wi, float t) const { return 0.f; }
    // Radiance leaving the light towards -wi when a ray from p in direction wi hits it (area) or escapes (env).
    virtual Color3 radiance(const Vec3& wi, bool frontSide = true) const { return Color3(0.f); }
    virtual bool isDelta() const { return false; }
    virtual bool isEnvironment() const { return false; }
    virtual bool isMesh() const { return false; }  // MeshLight: its emission comes from the shape's material
    // Polygonal emitters: if p sees the emitting side, writes the polygon (world space, at most 4
    // vertices, counter-clockwise seen from p), its constant radiance, and returns the vertex count.
    virtual int polygon(const Vec3& p, Vec3* vertices, Color3& radiance) const { return 0; }
    virtual RasterLight raster() const = 0;
    std::string name;
    // Seen by camera rays (Blender's ray visibility "Camera"): an invisible quad light still lights the scene and shows
    // in reflections, but camera rays pass through its geometry (its front and its black back).
    bool cameraVisible = true;
};

class PointLight final : public Light {
public:
    PointLight(const Vec3& p, const Color3& intensity) : p_(p), I_(intensity) {}
    bool sample(const Vec3& p, const Vec2& u, LightSample& s) const override;
    bool isDelta() const override { return true; }
    RasterLight raster() const override;

private:
    Vec3 p_;
    Color3 I_;  // W/sr
};

class SpotLight final : public Light {
public:
    // Full cone angle in degrees; blend in [0,1] softens the edge (Blender's spot_blend).
    SpotLight(const Vec3& p, const Vec3& dir, float coneDegrees, float blend, const Color3& intensity);
    bool sample(const Vec3& p, const Vec2& u, LightSample& s) const override;
    bool isDelta() const override { return true; }
    RasterLight raster() const override;

private:
    Vec3 p_, dir_;
    float cosOuter_, cosInner_;
    Color3 I_;
};

class DirectionalLight final : public Light {
public:
    DirectionalLight(const Vec3& direction, const Color3& irradiance)
        : toLight_(-glm::normalize(direction)), E_(irradiance) {}
    bool sample(const Vec3& p, const Vec2& u, LightSample& s) const override;
    bool isDelta() const override { return true; }
    RasterLight raster() const override;

private:
    Vec3 toLight_;
    Color3 E_;  // W/m² perpendicular to the direction
};

class QuadLight final : public Light {
public:
    // Parallelogram corner + edge vectors; emits on the side of cross(edgeU, edgeV) (or both).
    QuadLight(const Vec3& corner, const Vec3& edgeU, const Vec3& edgeV, const Color3& radiance, bool twoSided);
    bool sample(const Vec3& p, const Vec2& u, LightSample& s) const override;
    float pdf(const Vec3& p, const Vec3& wi, float t) const override;
    Color3 radiance(const Vec3& wi, bool frontSide) const override;
    int polygon(const Vec3& p, Vec3* vertices, Color3& radiance) const override;
    RasterLight raster() const override;
    const Vec3& corner() const { return corner_; }
    const Vec3& edgeU() const { return eu_; }
    const Vec3& edgeV() const { return ev_; }
    const Vec3& normal() const { return n_; }
    float area() const { return area_; }

private:
    Vec3 corner_, eu_, ev_, n_;
    float area_;
    Color3 L_;
    bool twoSided_;
};

// An emissive mesh as a light (issue 17 item 3): next-event estimation picks a triangle in proportion to its area and
// a uniform point on it; the emission there is the shape's material's (shaded by the integrator), so textured
// emission works. Its triangles are the shape's world-space mesh.
class MeshLight final : public Light {
public:
    MeshLight(int shape, const std::vector<Vec3>& positions, const std::vector<glm::uvec3>& indices);
    bool sample(const Vec3& p, const Vec2& u, LightSample& s) const override;
    // Solid-angle pdf of sampling the point a ray along wi hits at distance t on triangle 'prim' (its own normal, as
    // sample() uses, not the exact surface's of a built-in shape).
    float pdfAt(const Vec3& wi, float t, uint32_t prim) const;
    RasterLight raster() const override;
    bool isMesh() const override { return true; }
    int shape() const { return shape_; }
    float area() const { return area_; }

private:
    int shape_;
    std::vector<Vec3> p0_, e1_, e2_;  // per triangle: vertex 0 and the edges to vertices 1 and 2
    Distribution1D byArea_;
    float area_ = 0.f;
};

class EnvironmentLight final : public Light {
public:
    // Constant environment.
    explicit EnvironmentLight(const Color3& radiance);
    // Equirectangular (lat-long) image, rows top to bottom, 3 floats/pixel, z-up: the top row is +z,
    // u follows Blender/Cycles (u = 0.5 looks along -x), rotated by rotationDegrees about z; scaled by 'scale'.
    EnvironmentLight(std::vector<float> rgb, int width, int height, float rotationDegrees, const Color3& scale);
    bool sample(const Vec3& p, const Vec2& u, LightSample& s) const override;
    float pdf(const Vec3& p, const Vec3& wi, float t) const override;
    Color3 radiance(const Vec3& wi, bool frontSide) const override;
    bool isEnvironment() const override { return true; }
    RasterLight raster() const override;  // the constant, or the map's solid-angle mean times the scale

private:
    Vec2 dirToUv(const Vec3& d) const;
    Vec3 uvToDir(const Vec2& uv) const;
    Color3 lookup(const Vec2& uv) const;
    Color3 constant_{0.f};
    std::vector<float> rgb_;
    int w_ = 0, h_ = 0;
    float rotation_ = 0.f;  // radians
    Color3 scale_{1.f};
    Distribution2D dist_;
};

}  // namespace specula
