// Shadow maps shared by render.integrator "raster" and the GPU preview: the layout both sides render, the lookup in C++
// and in GLSL (kept operation for operation alike, so that the two images agree at shadow edges), and the CPU's maps.
#include "core/render/shadow_maps.h"

#include "core/render/accel.h"
#include "core/scene/scene.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>

namespace specula {

const float kShadowCubeFace[6][3][3] = {
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},    // +x
    {{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}},  // -x
    {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}},   // +y
    {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},   // -y
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},    // +z
    {{0, 0, -1}, {1, 0, 0}, {0, -1, 0}},  // -z
};

namespace {

Vec3 faceVec(int f, int k) { return Vec3(kShadowCubeFace[f][k][0], kShadowCubeFace[f][k][1], kShadowCubeFace[f][k][2]); }

// The face whose axis is the major axis of v (ties go to x, then y), as spc_shadow_face.
int cubeFace(const Vec3& v) {
    const float ax = std::abs(v.x), ay = std::abs(v.y), az = std::abs(v.z);
    if (ax >= ay && ax >= az) return v.x >= 0.f ? 0 : 1;
    if (ay >= az) return v.y >= 0.f ? 2 : 3;
    return v.z >= 0.f ? 4 : 5;
}

// A right-handed frame around a unit axis (any one: only both sides' agreement matters).
void axisFrame(const Vec3& axis, Vec3& right, Vec3& up) {
    const Vec3 helper = std::abs(axis.z) < 0.9f ? Vec3(0.f, 0.f, 1.f) : Vec3(1.f, 0.f, 0.f);
    right = glm::normalize(glm::cross(helper, axis));
    up = glm::cross(axis, right);
}

}  // namespace

const ShadowFrame& shadowDirection(int k) {
    static const std::vector<ShadowFrame> frames = [] {
        std::vector<ShadowFrame> r;
        const float a = 1.f / std::sqrt(3.f);
        const Vec3 sky[kShadowDirections] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},   {0, -1, 0},  {0, 0, 1},
                                             {0, 0, -1}, {a, a, a},  {-a, a, a},  {a, -a, a},  {-a, -a, a},
                                             {a, a, -a}, {-a, a, -a}, {a, -a, -a}, {-a, -a, -a}};
        for (const Vec3& d : sky) {
            ShadowFrame f;
            f.axis = -d;
            axisFrame(f.axis, f.right, f.up);
            r.push_back(f);
        }
        return r;
    }();
    return frames[size_t(k)];
}

ShadowLayout planShadowMaps(const Scene& scene, const std::vector<RasterLight>& lights) {
    ShadowLayout layout;
    layout.lights.resize(lights.size());
    // The bounding sphere of every shape (its box's centre and half diagonal): the orthographic maps' extent and the
    // perspective maps' far plane.
    Vec3 lo(FLT_MAX), hi(-FLT_MAX);
    for (const ShapeInstance& sh : scene.shapes)
        for (const Vec3& p : sh.mesh.positions) {
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
    if (!(lo.x <= hi.x)) return layout;  // no geometry, nothing to shadow
    const Vec3 centre = (lo + hi) * 0.5f;
    const float radius = std::max(glm::length(hi - lo) * 0.5f, 1e-6f);

    int layers = 0;
    std::vector<int> wanted(lights.size(), 0);
    for (size_t i = 0; i < lights.size(); ++i) {
        const RasterLight& r = lights[i];
        if (r.kind == RasterLight::Kind::Point) wanted[i] = 6;
        else if (r.kind == RasterLight::Kind::Spot)
            wanted[i] = r.cosOuter > std::cos(glm::radians(kShadowMaxSpotFov * 0.5f)) ? 1 : 6;
        else if (r.kind == RasterLight::Kind::Directional) wanted[i] = 1;
        else if (r.kind == RasterLight::Kind::Quad) wanted[i] = 6;
        else if (r.kind == RasterLight::Kind::Environment && (r.hasMap || maxComponent(r.value) > 0.f))
            wanted[i] = kShadowDirections;
        layers += wanted[i];
    }
    if (layers == 0) return layout;
    int size = std::clamp(scene.render.shadowMapSize, 16, 8192);
    if (int64_t(size) * size * layers > kShadowMaxTexels)  // the largest edge within the budget (floor of the root)
        size = std::max(16, int(std::sqrt(double(kShadowMaxTexels) / layers)));
    layout.size = size;

    // An orthographic map over the bounding sphere, from 'origin' on its far side along 'axis' (directional, environment).
    auto orthoView = [&](const Vec3& origin, const Vec3& axis, const Vec3& right, const Vec3& up) {
        ShadowView v;
        v.origin = origin, v.axis = axis, v.right = right, v.up = up;
        v.scale = 1.f / radius;
        v.zNear = 0.f;
        v.zFar = radius * 2.02f;
        v.ortho = true;
        layout.views.push_back(v);
    };
    for (size_t i = 0; i < lights.size(); ++i) {
        if (wanted[i] == 0) continue;
        const RasterLight& r = lights[i];
        ShadowLight& s = layout.lights[i];
        s.firstLayer = int(layout.views.size());
        if (r.kind == RasterLight::Kind::Directional) {
            s.mode = ShadowMode::Ortho;
            s.axis = -glm::normalize(r.direction);
            axisFrame(s.axis, s.right, s.up);
            s.origin = centre - s.axis * (radius * 1.01f);  // on the light's side of the sphere
            s.scale = 1.f / radius;
            s.texelFactor = 2.f / (s.scale * float(size));
            orthoView(s.origin, s.axis, s.right, s.up);
            continue;
        }
        if (r.kind == RasterLight::Kind::Environment) {
            s.mode = ShadowMode::Directions;
            s.origin = centre;
            s.reach = radius * 1.01f;
            s.scale = 1.f / radius;
            s.texelFactor = 2.f / (s.scale * float(size));
            for (int k = 0; k < kShadowDirections; ++k) {
                const ShadowFrame& d = shadowDirection(k);
                orthoView(s.origin - d.axis * s.reach, d.axis, d.right, d.up);
            }
            continue;
        }
        // A quad light's cube sits at its centre (the corner plus half of each edge).
        s.origin = r.kind == RasterLight::Kind::Quad ? r.position + (r.direction + r.edgeV) * 0.5f : r.position;
        const float zFar = (glm::length(s.origin - centre) + radius) * 1.01f;
        const float zNear = zFar * 1e-4f;
        if (wanted[i] == 1) {
            s.mode = ShadowMode::Perspective;
            s.axis = glm::normalize(r.direction);
            axisFrame(s.axis, s.right, s.up);
            // The outer cone plus a margin, so that the PCF taps of points inside the cone stay inside the map.
            const float half = std::acos(std::clamp(r.cosOuter, -1.f, 1.f));
            s.scale = 1.f / (std::tan(half) * 1.05f + 1e-4f);
            s.texelFactor = 2.f / (s.scale * float(size));
            ShadowView v;
            v.origin = s.origin, v.axis = s.axis, v.right = s.right, v.up = s.up;
            v.scale = s.scale;
            v.zNear = zNear, v.zFar = zFar;
            layout.views.push_back(v);
        } else {
            s.mode = ShadowMode::Cube;
            s.scale = 1.f;  // 90° faces
            s.texelFactor = 2.f / float(size);
            for (int f = 0; f < 6; ++f) {
                ShadowView v;
                v.origin = s.origin, v.axis = faceVec(f, 0), v.right = faceVec(f, 1), v.up = faceVec(f, 2);
                v.scale = 1.f;
                v.zNear = zNear, v.zFar = zFar;
                layout.views.push_back(v);
            }
        }
    }
    return layout;
}

namespace {

// One map's visibility: v = p minus the view's origin, the 2x2 PCF of shadowVisibility. clipToMap: points outside the
// map are lit (every map but a cube's face, which covers its directions).
float viewVisibility(const ShadowLayout& layout, const float* texels, bool ortho, bool clipToMap, int layer, const Vec3& v,
                     const Vec3& axis, const Vec3& right, const Vec3& up, float scale, float texelFactor, const Vec3& ng) {
    const int N = layout.size;
    const float z0 = glm::dot(v, axis);
    if (!ortho && !(z0 > 0.f)) return 1.f;  // behind a spot
    const float w = ortho ? texelFactor : z0 * texelFactor;
    const Vec3 q = v + ng * (kShadowNormalBias * w);
    const float z = glm::dot(q, axis);
    float sx = glm::dot(q, right) * scale, sy = glm::dot(q, up) * scale;
    if (!ortho) {
        if (!(z > 0.f)) return 1.f;
        sx = sx / z;
        sy = sy / z;
    }
    if (clipToMap && !(std::abs(sx) <= 1.f && std::abs(sy) <= 1.f)) return 1.f;
    const float u = (sx * 0.5f + 0.5f) * float(N) - 0.5f, t = (sy * 0.5f + 0.5f) * float(N) - 0.5f;
    const float fu = std::floor(u), ft = std::floor(t);
    const float ax = u - fu, ay = t - ft;
    const int i0 = int(fu), j0 = int(ft);
    const float bias = kShadowDepthBias * w;
    auto lit = [&](int i, int j) {
        i = std::clamp(i, 0, N - 1);
        j = std::clamp(j, 0, N - 1);
        return texels[(size_t(layer) * size_t(N) + size_t(j)) * size_t(N) + size_t(i)] + bias >= z ? 1.f : 0.f;
    };
    const float l00 = lit(i0, j0), l10 = lit(i0 + 1, j0), l01 = lit(i0, j0 + 1), l11 = lit(i0 + 1, j0 + 1);
    return (1.f - ay) * ((1.f - ax) * l00 + ax * l10) + ay * ((1.f - ax) * l01 + ax * l11);
}

}  // namespace

float shadowVisibility(const ShadowLayout& layout, const float* texels, int light, const Vec3& p, const Vec3& ng) {
    const ShadowLight& s = layout.lights[size_t(light)];
    if (s.mode == ShadowMode::None || s.mode == ShadowMode::Directions) return 1.f;
    Vec3 axis = s.axis, right = s.right, up = s.up;
    int layer = s.firstLayer;
    const Vec3 v = p - s.origin;
    if (s.mode == ShadowMode::Cube) {
        const int f = cubeFace(v);
        axis = faceVec(f, 0), right = faceVec(f, 1), up = faceVec(f, 2);
        layer += f;
    }
    return viewVisibility(layout, texels, s.mode == ShadowMode::Ortho, s.mode != ShadowMode::Cube, layer, v, axis, right,
                          up, s.scale, s.texelFactor, ng);
}

float environmentShadowVisibility(const ShadowLayout& layout, const float* texels, int light, const Vec3& p,
                                  const Vec3& ng, const float* irradiance) {
    const ShadowLight& s = layout.lights[size_t(light)];
    if (s.mode != ShadowMode::Directions) return 1.f;
    float lit = 0.f, total = 0.f;
    for (int k = 0; k < kShadowDirections; ++k) {
        const ShadowFrame& d = shadowDirection(k);
        const float w = std::max(0.f, -glm::dot(d.axis, ng)) * irradiance[k];
        if (!(w > 0.f)) continue;
        const Vec3 origin = s.origin - d.axis * s.reach;
        const Vec3 v = p - origin;
        lit += w * viewVisibility(layout, texels, true, true, s.firstLayer + k, v, d.axis, d.right, d.up, s.scale,
                                  s.texelFactor, ng);
        total += w;
    }
    return total > 0.f ? lit / total : 1.f;
}

std::string shadowLookupGlsl() {
    std::string faces;
    char buf[256];
    for (int f = 0; f < 6; ++f)
        for (int k = 0; k < 3; ++k) {
            std::snprintf(buf, sizeof buf, "%svec3(%.1f, %.1f, %.1f)", faces.empty() ? "" : ", ", double(kShadowCubeFace[f][k][0]),
                          double(kShadowCubeFace[f][k][1]), double(kShadowCubeFace[f][k][2]));
            faces += buf;
        }
    std::string dirs;
    for (int k = 0; k < kShadowDirections; ++k) {
        const ShadowFrame& d = shadowDirection(k);
        for (const Vec3& e : {d.axis, d.right, d.up}) {
            std::snprintf(buf, sizeof buf, "%svec3(%.9g, %.9g, %.9g)", dirs.empty() ? "" : ", ", double(e.x), double(e.y),
                          double(e.z));
            dirs += buf;
        }
    }
    std::snprintf(buf, sizeof buf, "const float spc_shadow_normal_bias = %.9g;\nconst float spc_shadow_depth_bias = %.9g;\n",
                  double(kShadowNormalBias), double(kShadowDepthBias));
    return std::string(buf) + "const vec3 spc_shadow_cube[18] = vec3[18](" + faces + ");\n" +
           "const vec3 spc_shadow_dirs[42] = vec3[42](" + dirs + ");\n" + R"(
layout(binding = SPC_PREVIEW_SHADOW_BINDING) uniform sampler2DArray spc_shadow_maps;
int spc_shadow_face(vec3 v) {
    float ax = abs(v.x), ay = abs(v.y), az = abs(v.z);
    if (ax >= ay && ax >= az) return v.x >= 0.0 ? 0 : 1;
    if (ay >= az) return v.y >= 0.0 ? 2 : 3;
    return v.z >= 0.0 ? 4 : 5;
}
// One map, as viewVisibility.
float spc_shadow_view(bool ortho, bool clip_to_map, int layer, vec3 v, vec3 axis, vec3 right, vec3 up,
                      float scale, float texel_factor, vec3 Ng) {
    int N = textureSize(spc_shadow_maps, 0).x;
    precise float z0 = dot(v, axis);
    if (!ortho && !(z0 > 0.0)) return 1.0;
    precise float w = ortho ? texel_factor : z0 * texel_factor;
    precise vec3 q = v + Ng * (spc_shadow_normal_bias * w);
    precise float z = dot(q, axis);
    precise float sx = dot(q, right) * scale, sy = dot(q, up) * scale;
    if (!ortho) {
        if (!(z > 0.0)) return 1.0;
        sx = sx / z;
        sy = sy / z;
    }
    if (clip_to_map && !(abs(sx) <= 1.0 && abs(sy) <= 1.0)) return 1.0;
    precise float u = (sx * 0.5 + 0.5) * float(N) - 0.5, t = (sy * 0.5 + 0.5) * float(N) - 0.5;
    precise float fu = floor(u), ft = floor(t);
    precise float ax = u - fu, ay = t - ft;
    int i0 = int(fu), j0 = int(ft);
    precise float bias = spc_shadow_depth_bias * w;
    float l[4];
    for (int k = 0; k < 4; ++k) {
        ivec2 ij = clamp(ivec2(i0 + (k & 1), j0 + (k >> 1)), ivec2(0), ivec2(N - 1));
        precise float d = texelFetch(spc_shadow_maps, ivec3(ij, layer), 0).r + bias;
        l[k] = d >= z ? 1.0 : 0.0;
    }
    precise float vis = (1.0 - ay) * ((1.0 - ax) * l[0] + ax * l[1]) + ay * ((1.0 - ax) * l[2] + ax * l[3]);
    return vis;
}
// h = (mode: 0 none, 1 cube, 2 perspective, 3 ortho, 4 directions; first layer; scale; texel factor). As
// shadowVisibility.
float spc_shadow(vec4 h, vec3 origin, vec3 axis, vec3 right, vec3 up, vec3 P, vec3 Ng) {
    int mode = int(h.x);
    if (mode == 0 || mode == 4) return 1.0;
    int layer = int(h.y);
    precise vec3 v = P - origin;
    if (mode == 1) {
        int f = spc_shadow_face(v);
        axis = spc_shadow_cube[3 * f];
        right = spc_shadow_cube[3 * f + 1];
        up = spc_shadow_cube[3 * f + 2];
        layer += f;
    }
    return spc_shadow_view(mode == 3, mode != 1, layer, v, axis, right, up, h.z, h.w, Ng);
}
vec3 spc_shadow_direction(int k) { return -spc_shadow_dirs[3 * k]; }
// As environmentShadowVisibility: E[k] the environment's irradiance (channel sum) towards spc_shadow_direction(k).
float spc_shadow_environment(vec4 h, vec3 centre, float reach, float E[14], vec3 P, vec3 Ng) {
    if (int(h.x) != 4) return 1.0;
    precise float lit = 0.0, total = 0.0;
    for (int k = 0; k < 14; ++k) {
        vec3 axis = spc_shadow_dirs[3 * k];
        precise float w = max(0.0, -dot(axis, Ng)) * E[k];
        if (!(w > 0.0)) continue;
        precise vec3 origin = centre - axis * reach;
        precise vec3 v = P - origin;
        lit += w * spc_shadow_view(true, true, int(h.y) + k, v, axis, spc_shadow_dirs[3 * k + 1],
                                   spc_shadow_dirs[3 * k + 2], h.z, h.w, Ng);
        total += w;
    }
    return total > 0.0 ? lit / total : 1.0;
}
)";
}

std::vector<float> buildShadowMaps(const Scene& scene, const Accel& accel, const ShadowLayout& layout) {
    const int N = layout.size;
    std::vector<float> texels(layout.texelCount(), FLT_MAX);
    const int rows = layout.layers() * N;
    // Isolated: a worker waiting here must not pick up another tile, which would ask for these maps again.
    tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(0, rows, [&](int row) {
            const ShadowView& v = layout.views[size_t(row / N)];
            const int j = row % N;
            const float y = float(2 * j + 1) / float(N) - 1.f;
            for (int i = 0; i < N; ++i) {
                const float x = float(2 * i + 1) / float(N) - 1.f;
                Ray ray;
                if (v.ortho) {
                    ray.o = v.origin + v.right * (x / v.scale) + v.up * (y / v.scale);
                    ray.d = v.axis;
                } else {
                    // Not normalised: t is the depth along the axis, so [tMin, tMax] is the GPU's near/far range.
                    ray.o = v.origin;
                    ray.d = v.axis + v.right * (x / v.scale) + v.up * (y / v.scale);
                }
                ray.tMin = v.zNear;
                ray.tMax = v.zFar;
                Hit hit;
                bool found = false;
                // Emitters of quad lights are passed through (bounded: a ray crosses few of them).
                for (int pass = 0; pass < 64; ++pass) {
                    if (!accel.intersect(ray, hit)) break;
                    if (scene.shapes[hit.shape].areaLight < 0) {
                        found = true;
                        break;
                    }
                    ray.tMin = std::nextafter(hit.t, FLT_MAX);
                }
                if (!found) continue;
                const Vec3 p = ray.o + ray.d * hit.t;
                texels[size_t(row) * size_t(N) + size_t(i)] = glm::dot(p - v.origin, v.axis);
            }
        });
    });
    return texels;
}

}  // namespace specula
