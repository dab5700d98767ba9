// Light sampling: delta lights, area-sampled quads, importance-sampled environment maps.
#include "core/render/lights.h"

#include <algorithm>

#include "core/render/environment_prefilter.h"

#include "core/render/sampling.h"

#include <limits>

namespace specula {

bool PointLight::sample(const Vec3& p, const Vec2&, LightSample& s) const {
    Vec3 d = p_ - p;
    float d2 = glm::dot(d, d);
    if (d2 <= 0.f) return false;
    s.distance = std::sqrt(d2);
    s.wi = d / s.distance;
    s.L = I_ / d2;
    s.pdf = 1.f;
    s.delta = true;
    return true;
}

SpotLight::SpotLight(const Vec3& p, const Vec3& dir, float coneDegrees, float blend, const Color3& intensity)
    : p_(p), dir_(glm::normalize(dir)), I_(intensity) {
    float half = 0.5f * glm::radians(std::clamp(coneDegrees, 0.f, 180.f));
    cosOuter_ = std::cos(half);
    cosInner_ = std::cos(half * (1.f - std::clamp(blend, 0.f, 1.f)));
}

bool SpotLight::sample(const Vec3& p, const Vec2&, LightSample& s) const {
    Vec3 d = p_ - p;
    float d2 = glm::dot(d, d);
    if (d2 <= 0.f) return false;
    s.distance = std::sqrt(d2);
    s.wi = d / s.distance;
    float c = glm::dot(-s.wi, dir_);
    float falloff;
    if (c >= cosInner_)
        falloff = 1.f;
    else if (c <= cosOuter_)
        falloff = 0.f;
    else {
        float t = (c - cosOuter_) / std::max(cosInner_ - cosOuter_, 1e-6f);
        falloff = t * t * (3.f - 2.f * t);  // smoothstep edge
    }
    if (falloff <= 0.f) return false;
    s.L = I_ * (falloff / d2);
    s.pdf = 1.f;
    s.delta = true;
    return true;
}

bool DirectionalLight::sample(const Vec3&, const Vec2&, LightSample& s) const {
    s.wi = toLight_;
    s.distance = std::numeric_limits<float>::infinity();
    s.L = E_;
    s.pdf = 1.f;
    s.delta = true;
    return true;
}

QuadLight::QuadLight(const Vec3& corner, const Vec3& edgeU, const Vec3& edgeV, const Color3& radiance, bool twoSided)
    : corner_(corner), eu_(edgeU), ev_(edgeV), L_(radiance), twoSided_(twoSided) {
    Vec3 c = glm::cross(eu_, ev_);
    area_ = glm::length(c);
    n_ = area_ > 0.f ? c / area_ : Vec3(0, 0, 1);
}

bool QuadLight::sample(const Vec3& p, const Vec2& u, LightSample& s) const {
    // Uniform area sampling, converted to solid angle: pdf = d² / (A |cos θl|).
    Vec3 q = corner_ + u.x * eu_ + u.y * ev_;
    Vec3 d = q - p;
    float d2 = glm::dot(d, d);
    if (d2 <= 0.f || area_ <= 0.f) return false;
    s.distance = std::sqrt(d2);
    s.wi = d / s.distance;
    float cosL = -glm::dot(s.wi, n_);
    if (!twoSided_ && cosL <= 0.f) return false;
    cosL = std::abs(cosL);
    if (cosL <= 1e-7f) return false;
    s.pdf = d2 / (area_ * cosL);
    s.L = L_;
    s.delta = false;
    return true;
}

float QuadLight::pdf(const Vec3& p, const Vec3& wi, float t) const {
    float cosL = -glm::dot(wi, n_);
    if (!twoSided_ && cosL <= 0.f) return 0.f;
    cosL = std::abs(cosL);
    if (cosL <= 1e-7f || area_ <= 0.f) return 0.f;
    return t * t / (area_ * cosL);
}

Color3 QuadLight::radiance(const Vec3& wi, bool) const {
    float cosL = -glm::dot(wi, n_);
    return (twoSided_ || cosL > 0.f) ? L_ : Color3(0.f);
}

int QuadLight::polygon(const Vec3& p, Vec3* v, Color3& radiance) const {
    float side = glm::dot(p - corner_, n_);  // > 0: p is on the emitting (front) side
    if (side == 0.f || (!twoSided_ && side < 0.f)) return 0;
    // cross(eu, ev) = n points towards a front-side p, so (c, c+eu, c+eu+ev, c+ev) runs clockwise seen
    // from p; reverse it for a counter-clockwise polygon (and keep it for a back-side p).
    if (side > 0.f) {
        v[0] = corner_;
        v[1] = corner_ + ev_;
        v[2] = corner_ + eu_ + ev_;
        v[3] = corner_ + eu_;
    } else {
        v[0] = corner_;
        v[1] = corner_ + eu_;
        v[2] = corner_ + eu_ + ev_;
        v[3] = corner_ + ev_;
    }
    radiance = L_;
    return 4;
}

EnvironmentLight::EnvironmentLight(const Color3& radiance) : constant_(radiance) {}

EnvironmentLight::EnvironmentLight(std::vector<float> rgb, int width, int height, float rotationDegrees,
                                   const Color3& scale)
    : rgb_(std::move(rgb)), w_(width), h_(height), rotation_(glm::radians(rotationDegrees)), scale_(scale) {
    // Importance ∝ luminance · sin θ (the Jacobian of the lat-long mapping).
    std::vector<float> f(size_t(w_) * h_);
    for (int y = 0; y < h_; ++y) {
        float sinTheta = std::sin(kPi * (y + 0.5f) / h_);
        for (int x = 0; x < w_; ++x) {
            const float* px = &rgb_[(size_t(y) * w_ + x) * 3];
            f[size_t(y) * w_ + x] = std::max(0.f, luminance({px[0], px[1], px[2]})) * sinTheta;
        }
    }
    dist_ = Distribution2D(f, w_, h_);
}

// Blender's equirectangular convention (Cycles direction_to_equirectangular): u = 0.5 - atan2(y, -x)/(2π),
// so the image centre (u = 0.5) looks along -x and u grows clockwise seen from above; v = 0 is +z.
// 'rotation' turns the map about +z like a Mapping node's Z rotation.
Vec2 EnvironmentLight::dirToUv(const Vec3& d) const { return environmentUv(d, rotation_); }

Vec3 EnvironmentLight::uvToDir(const Vec2& uv) const {
    float a = (0.5f - uv.x) * 2.f * kPi;
    float theta = uv.y * kPi;
    float st = std::sin(theta);
    Vec3 r(-std::cos(a) * st, std::sin(a) * st, std::cos(theta));
    float c = std::cos(rotation_), s = std::sin(rotation_);
    return {c * r.x - s * r.y, s * r.x + c * r.y, r.z};  // rotate by +rotation
}

Color3 EnvironmentLight::lookup(const Vec2& uv) const {
    int x = std::clamp(int(uv.x * w_), 0, w_ - 1);
    int y = std::clamp(int(uv.y * h_), 0, h_ - 1);
    const float* px = &rgb_[(size_t(y) * w_ + x) * 3];
    return Color3(px[0], px[1], px[2]) * scale_;
}

bool EnvironmentLight::sample(const Vec3&, const Vec2& u, LightSample& s) const {
    s.distance = std::numeric_limits<float>::infinity();
    s.delta = false;
    if (rgb_.empty()) {
        s.wi = sampleUniformSphere(u);
        s.pdf = kInv4Pi;
        s.L = constant_;
        return true;
    }
    float pdfUv;
    Vec2 uv = dist_.sample(u, pdfUv);
    float sinTheta = std::sin(uv.y * kPi);
    if (pdfUv <= 0.f || sinTheta <= 0.f) return false;
    s.wi = uvToDir(uv);
    // Density and radiance through the same direction -> texel mapping as pdf()/radiance(), so that
    // MIS weights agree exactly even where float round trips land on a neighbouring texel.
    s.pdf = pdf(Vec3(0.f), s.wi, 0.f);
    s.L = lookup(dirToUv(s.wi));
    return s.pdf > 0.f;
}

float EnvironmentLight::pdf(const Vec3&, const Vec3& wi, float) const {
    if (rgb_.empty()) return kInv4Pi;
    Vec2 uv = dirToUv(wi);
    float sinTheta = std::sin(uv.y * kPi);
    if (sinTheta <= 0.f) return 0.f;
    return dist_.pdf(uv) / (2.f * kPi * kPi * sinTheta);
}

Color3 EnvironmentLight::radiance(const Vec3& wi, bool) const {
    if (rgb_.empty()) return constant_;
    return lookup(dirToUv(wi));
}

}  // namespace specula

// ---- raster descriptions (the GPU preview and the CPU "raster" integrator) ----------------------------
namespace specula {

namespace {
// A raster description of one kind: its value, and where it sits and points (RasterLight's defaults for a kind
// without a position or a direction). The fields only some kinds have are set by those kinds.
RasterLight rasterLight(RasterLight::Kind kind, const Color3& value, const Vec3& position = RasterLight{}.position,
                        const Vec3& direction = RasterLight{}.direction) {
    RasterLight r;
    r.kind = kind;
    r.position = position;
    r.direction = direction;
    r.value = value;
    return r;
}
}  // namespace

RasterLight PointLight::raster() const { return rasterLight(RasterLight::Kind::Point, I_, p_); }

RasterLight SpotLight::raster() const {
    RasterLight r = rasterLight(RasterLight::Kind::Spot, I_, p_, dir_);
    r.cosOuter = cosOuter_;
    r.cosInner = cosInner_;
    return r;
}

RasterLight DirectionalLight::raster() const {
    return rasterLight(RasterLight::Kind::Directional, E_, RasterLight{}.position, toLight_);
}

RasterLight QuadLight::raster() const {
    RasterLight r = rasterLight(RasterLight::Kind::Quad, L_, corner_, eu_);
    r.edgeV = ev_;
    r.twoSided = twoSided_;
    r.cameraVisible = cameraVisible;
    return r;
}

MeshLight::MeshLight(int shape, const std::vector<Vec3>& positions, const std::vector<glm::uvec3>& indices)
    : shape_(shape) {
    std::vector<float> areas;
    areas.reserve(indices.size());
    double total = 0.0;
    for (const auto& t : indices) {
        const Vec3 p0 = positions[t.x], e1 = positions[t.y] - p0, e2 = positions[t.z] - p0;
        p0_.push_back(p0);
        e1_.push_back(e1);
        e2_.push_back(e2);
        const float a = 0.5f * glm::length(glm::cross(e1, e2));
        areas.push_back(std::isfinite(a) ? a : 0.f);
        total += areas.back();
    }
    area_ = float(total);
    if (area_ > 0.f) byArea_ = Distribution1D(std::move(areas));
}

bool MeshLight::sample(const Vec3& p, const Vec2& u, LightSample& s) const {
    if (!(area_ > 0.f)) return false;
    float cellPdf = 0.f;
    int tri = 0;
    const float x = byArea_.sample(u.x, cellPdf, tri);
    // The first coordinate's position inside its cell, reused (it is uniform there), and the second: a uniform point
    // on the triangle by the square-root map (pbrt-v4's SampleUniformTriangle).
    const int n = byArea_.size();
    const float ux = std::clamp(x * float(n) - float(tri), 0.f, 1.f - 1e-7f);
    const float su = std::sqrt(ux);
    const float b1 = su * (1.f - u.y), b2 = su * u.y;  // weights of vertices 1 and 2 (b0 = 1 - su)
    const Vec3 q = p0_[size_t(tri)] + b1 * e1_[size_t(tri)] + b2 * e2_[size_t(tri)];
    const Vec3 d = q - p;
    const float dist2 = glm::dot(d, d);
    if (!(dist2 > 0.f)) return false;
    const float dist = std::sqrt(dist2);
    s.wi = d / dist;
    s.distance = dist;
    s.pdf = pdfAt(s.wi, dist, uint32_t(tri));
    s.L = Color3(0.f);
    s.delta = false;
    s.shape = shape_;
    s.prim = uint32_t(tri);
    s.bary = Vec2(b1, b2);
    return s.pdf > 0.f && std::isfinite(s.pdf);
}

// Area pdf 1/A turned into solid angle at p: t² / (|cos θ_light| A). Both sides emit (bsdf.emission is two-sided).
float MeshLight::pdfAt(const Vec3& wi, float t, uint32_t prim) const {
    if (prim >= e1_.size() || !(area_ > 0.f)) return 0.f;
    const Vec3 ng = glm::cross(e1_[prim], e2_[prim]);
    const float len = glm::length(ng);
    const float c = len > 0.f ? std::abs(glm::dot(wi, ng)) / len : 0.f;
    if (!(c > 0.f)) return 0.f;
    return t * t / (c * area_);
}

RasterLight MeshLight::raster() const {
    RasterLight r;
    r.kind = RasterLight::Kind::Mesh;
    return r;
}

RasterLight EnvironmentLight::raster() const {
    RasterLight r = rasterLight(RasterLight::Kind::Environment, constant_);
    if (!rgb_.empty()) {
        // Mean radiance over the sphere: texels weighted by their solid angle (∝ sin θ in the lat-long layout).
        double sum[3] = {0, 0, 0}, weight = 0;
        for (int y = 0; y < h_; ++y) {
            double sinTheta = std::sin(kPi * (y + 0.5) / h_);
            for (int x = 0; x < w_; ++x)
                for (int c = 0; c < 3; ++c) sum[c] += sinTheta * rgb_[(size_t(y) * w_ + x) * 3 + c];
            weight += sinTheta * w_;
        }
        r.value = Color3(float(sum[0] / weight), float(sum[1] / weight), float(sum[2] / weight)) * scale_;
        r.hasMap = true;
        r.map = rgb_.data();
        r.mapWidth = w_;
        r.mapHeight = h_;
        r.mapRotation = rotation_;
        r.mapScale = scale_;
    }
    return r;
}

}  // namespace specula
