// Perspective camera with optional thin lens, generating rays with pixel-step differentials.
// Convention: raster (0,0) is the top-left corner of the image; +x right, +y down.
#pragma once

#include "core/render/ray.h"

namespace specula {

struct CameraDesc {
    Vec3 position{0, -5, 0};
    Vec3 lookAt{0, 0, 0};
    Vec3 up{0, 0, 1};
    float fovDegrees = 39.6f;
    bool fovIsHorizontal = true;  // "fov_axis": "x" (Blender's sensor fit horizontal) or "y"
    float apertureRadius = 0.f;   // thin lens; 0 = pinhole
    float focusDistance = 0.f;    // 0 = distance to lookAt
};

class PerspectiveCamera {
public:
    PerspectiveCamera() = default;
    PerspectiveCamera(const CameraDesc& desc, int width, int height);

    // Ray through raster position (x, y) in pixels, lens sample uLens in [0,1)^2.
    RayDifferential generateRay(float rasterX, float rasterY, const Vec2& uLens) const;

    // pbrt-v4's Camera::Approximate_dp_dxy: dp/dx and dp/dy of a point p with normal n as if it were seen directly
    // from the camera (the rays through p's pixel and its neighbours, pinhole, intersected with p's tangent plane),
    // times 'scale' (the renderer's 1/sqrt(spp) shrink). Secondary path vertices use it as their footprint.
    void approximateDpDxy(const Vec3& p, const Vec3& n, float scale, Vec3& dpdx, Vec3& dpdy) const;

    const Vec3& position() const { return pos_; }
    const Vec3& forward() const { return forward_; }
    const Vec3& right() const { return right_; }
    const Vec3& up() const { return upv_; }      // the image's up (right x forward)
    float halfWidth() const { return halfW_; }   // image-plane half extents at distance 1
    float halfHeight() const { return halfH_; }
    // OpenEXR's standard camera attributes (column-vector convention here; image_io writes them as Imath's row-vector
    // matrices): camera space is left-handed, +x right, +y up, +z the view direction; NDC has (0, 0) at the image's
    // top-left corner and (1, 1) at its bottom-right, after the division by the fourth (homogeneous) coordinate.
    Mat4 worldToCamera() const;
    Mat4 worldToNdc() const;
    const CameraDesc& desc() const { return desc_; }
    int width() const { return width_; }
    int height() const { return height_; }

private:
    Vec3 directionFor(float rasterX, float rasterY) const;  // unnormalised, camera basis
    CameraDesc desc_;
    int width_ = 1, height_ = 1;
    Vec3 pos_{0.f}, forward_{0, 1, 0}, right_{1, 0, 0}, upv_{0, 0, 1};
    float halfW_ = 1.f, halfH_ = 1.f;  // image-plane half extents at distance 1
    float focus_ = 1.f;
};

}  // namespace specula
