// Perspective/thin-lens camera ray generation with differentials.
#include "core/render/camera.h"

#include "core/render/sampling.h"

namespace specula {

PerspectiveCamera::PerspectiveCamera(const CameraDesc& desc, int width, int height)
    : desc_(desc), width_(width), height_(height) {
    pos_ = desc.position;
    forward_ = glm::normalize(desc.lookAt - desc.position);
    right_ = glm::normalize(glm::cross(forward_, desc.up));
    upv_ = glm::cross(right_, forward_);
    if (!isFinite(forward_) || !isFinite(right_) || !isFinite(upv_)) {
        // Positions up to ±1e30 (the scene's range) overflow a float's squared length: the basis in double then
        // (only then, so every other camera keeps its bits).
        const glm::dvec3 f = glm::normalize(glm::dvec3(desc.lookAt) - glm::dvec3(desc.position));
        const glm::dvec3 r = glm::normalize(glm::cross(f, glm::dvec3(desc.up)));
        forward_ = Vec3(f);
        right_ = Vec3(r);
        upv_ = Vec3(glm::cross(r, f));
    }
    float t = std::tan(0.5f * glm::radians(desc.fovDegrees));
    float aspect = float(width) / float(height);
    if (desc.fovIsHorizontal) {
        halfW_ = t;
        halfH_ = t / aspect;
    } else {
        halfH_ = t;
        halfW_ = t * aspect;
    }
    focus_ = desc.focusDistance > 0.f ? desc.focusDistance : glm::length(desc.lookAt - desc.position);
}

Mat4 PerspectiveCamera::worldToCamera() const {
    Mat4 m(1.f);  // glm: m[column][row]
    for (int c = 0; c < 3; ++c) {
        m[c][0] = right_[c];
        m[c][1] = upv_[c];
        m[c][2] = forward_[c];
    }
    m[3][0] = -glm::dot(right_, pos_);
    m[3][1] = -glm::dot(upv_, pos_);
    m[3][2] = -glm::dot(forward_, pos_);
    return m;
}

// directionFor's inverse: a camera-space point (x, y, z) lands at raster x = (x / (z halfW) + 1) W / 2 and
// y = (1 - y / (z halfH)) H / 2, so NDC = (0.5 + 0.5 x / (z halfW), 0.5 - 0.5 y / (z halfH)) with w = z.
Mat4 PerspectiveCamera::worldToNdc() const {
    Mat4 p(0.f);
    p[0][0] = 0.5f / halfW_;
    p[2][0] = 0.5f;
    p[1][1] = -0.5f / halfH_;
    p[2][1] = 0.5f;
    p[2][2] = 1.f;  // z kept (EXR readers discard it)
    p[2][3] = 1.f;  // w = z
    return p * worldToCamera();
}

Vec3 PerspectiveCamera::directionFor(float rasterX, float rasterY) const {
    float sx = (2.f * rasterX / float(width_) - 1.f) * halfW_;
    float sy = (1.f - 2.f * rasterY / float(height_)) * halfH_;
    return forward_ + sx * right_ + sy * upv_;
}

RayDifferential PerspectiveCamera::generateRay(float rasterX, float rasterY, const Vec2& uLens) const {
    RayDifferential r;
    Vec3 d = directionFor(rasterX, rasterY);
    Vec3 dx = directionFor(rasterX + 1.f, rasterY);
    Vec3 dy = directionFor(rasterX, rasterY + 1.f);
    if (desc_.apertureRadius > 0.f) {
        // Thin lens: all rays through a pixel converge on the plane of focus (distance along forward).
        Vec2 lens = desc_.apertureRadius * sampleConcentricDisk(uLens);
        Vec3 o = pos_ + lens.x * right_ + lens.y * upv_;
        auto through = [&](const Vec3& dir) { return pos_ + dir * focus_; };  // dir has unit forward component
        r.o = o;
        r.d = glm::normalize(through(d) - o);
        r.rxOrigin = o;
        r.ryOrigin = o;
        r.rxDirection = glm::normalize(through(dx) - o);
        r.ryDirection = glm::normalize(through(dy) - o);
    } else {
        r.o = r.rxOrigin = r.ryOrigin = pos_;
        r.d = glm::normalize(d);
        r.rxDirection = glm::normalize(dx);
        r.ryDirection = glm::normalize(dy);
    }
    r.hasDifferentials = true;
    return r;
}

void PerspectiveCamera::approximateDpDxy(const Vec3& p, const Vec3& n, float scale, Vec3& dpdx, Vec3& dpdy) const {
    dpdx = dpdy = Vec3(0.f);
    const Vec3 d = p - pos_;
    const float z = glm::dot(d, forward_);
    if (!(z > 1e-8f)) return;  // behind the camera: no footprint to borrow
    const float ix = glm::dot(d, right_) / z, iy = glm::dot(d, upv_) / z;  // image-plane position at distance 1
    const float sx = 2.f * halfW_ / float(width_), sy = 2.f * halfH_ / float(height_);  // one pixel there
    auto along = [&](float ox, float oy) {
        const Vec3 dir = (ix + ox) * right_ + (iy + oy) * upv_ + forward_;
        const float den = glm::dot(n, dir);
        if (std::abs(den) < 1e-8f) return Vec3(0.f);
        const float t = glm::dot(n, d) / den;
        return (pos_ + t * dir - p) * scale;
    };
    dpdx = along(sx, 0.f);   // raster +x: right
    dpdy = along(0.f, -sy);  // raster +y: down
}

}  // namespace specula
