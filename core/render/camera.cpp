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

}  // namespace specula
