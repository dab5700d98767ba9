// Shadow maps of render.integrator "raster" and the GPU preview (docs/preview.md): a floor under a square occluder, lit
// by a point, a spot and a directional light, and beside a wall, lit by a quad light and a sky; the shadowed pixels are
// as dark as known on both sides, lit pixels keep the unshadowed value, the layout keeps its texel budget, and the
// frame block's GLSL layout is what the C++ packer writes.
#include "core/render/accel.h"
#include "core/render/renderer.h"
#include "core/render/shadow_maps.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "plugin/preview/gl_util.h"
#include "plugin/preview/preview.h"
#include "plugin/preview/preview_frame.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>

using namespace specula;

namespace {

const std::string kExamples = std::string(SPECULA_SOURCE_DIR) + "/examples";
constexpr int kW = 96, kH = 64;
// The camera looks straight down from 10 m with a 40° horizontal field: the floor's x spans ±10·tan 20° across the
// image, y = 0 is between the two middle rows.
const float kHalfWidth = 10.f * std::tan(glm::radians(20.f));

// A 20 m floor at z = 0 and, with 'occluder', a 1 m square at z = 1 over the origin, both diffuse; one light; black world.
std::string scene(const std::string& light, bool occluder) {
    std::string shapes = R"([{"type": "quad", "size": [20, 20], "material": "grey"})";
    if (occluder) shapes += R"(, {"type": "quad", "size": [1, 1], "transform": {"translate": [0, 0, 1]}, "material": "grey"})";
    shapes += "]";
    return R"({"version": 1,
        "render": {"width": )" + std::to_string(kW) + R"(, "height": )" + std::to_string(kH) +
           R"(, "spp": 1, "integrator": "raster", "shadow_map_size": 512},
        "camera": {"position": [0, 0, 10], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "fov_axis": "x"},
        "materials": {"grey": {"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": 0.5}}}, "output": "@d.bsdf"}},
        "shapes": )" + shapes + R"(,
        "lights": [)" + light + "]}";
}

struct Images {
    std::vector<float> cpu, gpu;  // beauty, RGB rows top to bottom
};

Images render(const std::string& json) {
    Images out;
    Scene s = loadSceneFromString(json, kExamples);
    out.cpu = renderScene(s).images.find("beauty")->pixels;
    const nlohmann::json doc = nlohmann::json::parse(json);
    preview::PreviewOutput p = preview::renderPreview(s, doc["materials"], kExamples, {});
    out.gpu = p.output.images.find("beauty")->pixels;
    return out;
}

// Beauty (channel sum) of the pixel that sees floor point (x, y ≈ 0).
float at(const std::vector<float>& px, float x) {
    const int col = int(std::floor((x / kHalfWidth * 0.5f + 0.5f) * kW));
    const int row = kH / 2;
    const float* p = &px[(size_t(row) * kW + size_t(col)) * 3];
    return p[0] + p[1] + p[2];
}

struct Case {
    const char* name;
    std::string light;
    float shadowX;  // a floor point in the occluder's shadow and not under it as the camera sees it (|x| > 0.5)
    float litX;     // a lit floor point
};

// Point and spot at (2, 0, 4): the shadow of the square spans x in [-4/3, 0]. Sun travelling along (-0.5, 0, -1): x in
// [-1, 0]. Lit: x = 1.5 (inside the spot's 45° half-angle, whose axis aims at the origin).
const Case kCases[] = {
    {"point", R"({"type": "point", "position": [2, 0, 4], "power": 800})", -1.f, 1.5f},
    {"spot", R"({"type": "spot", "position": [2, 0, 4], "look_at": [0, 0, 0], "cone_angle": 90, "blend": 0, "power": 800})",
     -1.f, 1.5f},
    {"directional", R"({"type": "directional", "direction": [-0.5, 0, -1], "irradiance": 3})", -0.75f, 1.5f},
};

}  // namespace

TEST(PreviewShadows, OccluderShadowIsBlackAndLitPixelsKeepTheirValueOnBothSides) {
    for (const Case& c : kCases) {
        SCOPED_TRACE(c.name);
        const Images lit = render(scene(c.light, false)), shadowed = render(scene(c.light, true));
        // The unshadowed floor is well lit at both points, so a missing shadow cannot pass.
        const float open = at(lit.cpu, c.shadowX), ref = at(lit.cpu, c.litX);
        ASSERT_GT(open, 0.01f);
        ASSERT_GT(ref, 0.01f);
        EXPECT_NEAR(at(lit.gpu, c.shadowX), open, 1e-4f * open);
        // In the shadow: no light on either side.
        EXPECT_LT(at(shadowed.cpu, c.shadowX), 1e-6f * open);
        EXPECT_LT(at(shadowed.gpu, c.shadowX), 1e-6f * open);
        // Lit: the unshadowed value (no acne, no leak of the bias into lit floor).
        EXPECT_NEAR(at(shadowed.cpu, c.litX), ref, 1e-6f * ref);
        EXPECT_NEAR(at(shadowed.gpu, c.litX), ref, 1e-4f * ref);
        // Every pixel that sees the floor (the occluder covers |x|, |y| <= 0.5·10/9 of it): never brighter than the
        // open floor; and the two sides agree per pixel except on the few pixels of the shadow's edge.
        int differ = 0;
        for (int row = 0; row < kH; ++row)
            for (int col = 0; col < kW; ++col) {
                const float x = ((col + 0.5f) / kW * 2.f - 1.f) * kHalfWidth;
                const float y = ((row + 0.5f) / kH * 2.f - 1.f) * kHalfWidth * kH / kW;
                const bool floor = std::abs(x) > 0.6f || std::abs(y) > 0.6f;
                for (int k = 0; k < 3; ++k) {
                    const size_t i = (size_t(row) * kW + size_t(col)) * 3 + size_t(k);
                    if (floor) EXPECT_LE(shadowed.cpu[i], lit.cpu[i] * (1.f + 1e-6f) + 1e-9f) << col << "," << row;
                    if (std::abs(shadowed.cpu[i] - shadowed.gpu[i]) > 1e-3f * std::max(shadowed.cpu[i], 1e-3f)) ++differ;
                }
            }
        EXPECT_LT(differ, int(shadowed.cpu.size()) / 100) << differ << " channels differ";
    }
}

TEST(PreviewShadows, QuadLightEmittersCastNoShadow) {
    // A quad light between the point light and the floor: its emitter is drawn but is not in the shadow maps (the
    // preview draws emitters in their own pass), so the floor under it keeps the point light's light on both sides.
    const std::string point = R"({"type": "point", "position": [0, 0, 4], "power": 800})";
    const std::string withQuad =
        point + R"(, {"type": "quad", "position": [1, 0, 2], "look_at": [1, 0, 0], "size": [0.8, 0.8], "power": 0.001})";
    const Images a = render(scene(point, false)), b = render(scene(withQuad, false));
    // Floor point x = 2: the point light's ray to it crosses z = 2 at x = 1 (through the emitter), the camera's at
    // x = 1.6 (past the emitter's edge at 1.4), so the pixel sees the floor, lit by the point light.
    const float x = 2.f;
    ASSERT_GT(at(a.cpu, x), 0.01f);
    EXPECT_GE(at(b.cpu, x), at(a.cpu, x) * (1.f - 1e-6f));
    EXPECT_GE(at(b.gpu, x), at(a.gpu, x) * (1.f - 1e-4f));
}

TEST(PreviewShadows, LayoutKeepsTheTexelBudget) {
    Scene s = loadSceneFromString(scene(R"({"type": "point", "position": [2, 0, 4], "power": 800})", true),
                                  kExamples);
    std::vector<RasterLight> lights(64, s.lights[0]->raster());
    s.render.shadowMapSize = 8192;
    ShadowLayout big = planShadowMaps(s, lights);
    EXPECT_EQ(big.layers(), 64 * 6);
    EXPECT_LE(int64_t(big.texelCount()), kShadowMaxTexels);
    EXPECT_GT(int64_t(big.texelCount()), kShadowMaxTexels / 2);
    lights.resize(1);
    s.render.shadowMapSize = 300;
    ShadowLayout one = planShadowMaps(s, lights);
    EXPECT_EQ(one.size, 300);
    EXPECT_EQ(one.layers(), 6);
    // A directional light's map covers the bounding sphere of the scene; a quad light gets a cube from its centre, an
    // environment kShadowDirections maps, an emissive mesh none.
    RasterLight quad;
    quad.kind = RasterLight::Kind::Quad;
    RasterLight sun;
    sun.kind = RasterLight::Kind::Directional;
    sun.direction = Vec3(0.f, 0.f, 1.f);
    quad.position = Vec3(1.f, 2.f, 3.f);
    quad.direction = Vec3(2.f, 0.f, 0.f);
    quad.edgeV = Vec3(0.f, 4.f, 0.f);
    RasterLight sky;
    sky.kind = RasterLight::Kind::Environment;
    sky.value = Color3(1.f);
    RasterLight mesh;
    mesh.kind = RasterLight::Kind::Mesh;
    ShadowLayout mixed = planShadowMaps(s, {quad, sun, sky, mesh});
    EXPECT_EQ(mixed.layers(), 6 + 1 + kShadowDirections);
    EXPECT_EQ(mixed.lights[0].mode, ShadowMode::Cube);
    EXPECT_EQ(mixed.lights[0].origin, Vec3(2.f, 4.f, 3.f));
    EXPECT_EQ(mixed.lights[1].mode, ShadowMode::Ortho);
    EXPECT_EQ(mixed.lights[2].mode, ShadowMode::Directions);
    EXPECT_EQ(mixed.lights[2].firstLayer, 7);
    EXPECT_EQ(mixed.lights[3].mode, ShadowMode::None);
}

namespace {

// A point or spot light at the origin inside a 5 m sphere, six 0.4 m spheres about 2 m away towards ±x, ±y, ±z: one
// shadow in every cube face's direction.
std::string enclosure(const std::string& light, const std::string& camera) {
    std::string shapes = R"([{"type": "sphere", "radius": 5, "segments": 96, "material": "grey"})";
    // Off the face axes, so that a mirrored face or a swapped row order moves the shadows.
    const char* centres[6] = {"[2, 0.5, 0.3]", "[-2, -0.4, 0.6]", "[0.3, 2, -0.5]", "[-0.6, -2, 0.2]", "[0.5, -0.3, 2]",
                              "[-0.2, 0.6, -2]"};
    for (const char* c : centres)
        shapes += std::string(R"(, {"type": "sphere", "radius": 0.4, "segments": 48, "transform": {"translate": )") + c +
                  R"(}, "material": "grey"})";
    shapes += "]";
    return R"({"version": 1,
        "render": {"width": 64, "height": 48, "spp": 1, "integrator": "raster", "shadow_map_size": 512},
        "camera": )" + camera + R"(,
        "materials": {"grey": {"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": 0.5}}}, "output": "@d.bsdf"}},
        "shapes": )" + shapes + R"(,
        "lights": [)" + light + "]}";
}

const char* kEnclosureLights[] = {
    R"({"type": "point", "position": [0, 0, 0], "power": 800})",
    R"({"type": "spot", "position": [0, 0, 0], "look_at": [1, 0.2, 0.1], "cone_angle": 120, "blend": 0, "power": 800})",
    R"({"type": "spot", "position": [0, 0, 0], "look_at": [1, 0.2, 0.1], "cone_angle": 175, "blend": 0, "power": 800})",
};

}  // namespace

TEST(PreviewShadows, MapVisibilityMatchesShadowRaysInEveryDirection) {
    // 20000 points of the enclosing sphere (a Fibonacci lattice of directions from the light): the CPU maps' lookup
    // against an exact shadow ray to the light. They may differ only along shadow edges (within a texel or two): measured
    // 6, 2 and 5 points; a mirrored or misplaced face gives hundreds.
    const char* cam = R"({"position": [0, 0, 0.5], "look_at": [1, 0, 0.5]})";
    for (const char* light : kEnclosureLights) {
        SCOPED_TRACE(light);
        Scene s = loadSceneFromString(enclosure(light, cam), kExamples);
        Accel accel(s);
        std::vector<RasterLight> lights{s.lights[0]->raster()};
        const ShadowLayout layout = planShadowMaps(s, lights);
        ASSERT_EQ(layout.layers(), std::string(light).find("175") != std::string::npos ||
                                           std::string(light).find("point") != std::string::npos
                                       ? 6
                                       : 1);
        const std::vector<float> texels = buildShadowMaps(s, accel, layout);
        const int n = 20000;
        int shadowed = 0, mismatched = 0, considered = 0;
        for (int k = 0; k < n; ++k) {
            const float z = 1.f - (2.f * k + 1.f) / n, r = std::sqrt(std::max(0.f, 1.f - z * z));
            const float phi = 2.39996323f * k;
            const Vec3 d(r * std::cos(phi), r * std::sin(phi), z);
            if (lights[0].kind == RasterLight::Kind::Spot && glm::dot(d, glm::normalize(lights[0].direction)) <= lights[0].cosOuter)
                continue;  // outside the cone: no light to shadow
            // The wall's tessellated point in direction d, from outside, and its geometric normal towards the light.
            RayDifferential in;
            in.o = d * 6.f;
            in.d = -d;
            Hit hit;
            ASSERT_TRUE(accel.intersect(in, hit));
            const ShadingPoint sp = accel.shadingPoint(in, hit);
            const Vec3 p = sp.p, ng = -sp.ng;
            Ray toLight;
            toLight.o = offsetRayOrigin(p, ng, -d);
            toLight.d = glm::normalize(-toLight.o);
            toLight.tMax = glm::length(toLight.o) * (1.f - 1e-4f);
            const bool visible = !accel.occluded(toLight);
            const float vis = shadowVisibility(layout, texels.data(), 0, p, ng);
            ++considered;
            shadowed += visible ? 0 : 1;
            if (visible ? vis < 0.5f : vis > 0.5f) ++mismatched;
        }
        std::printf("shadow rays vs maps: %d of %d points shadowed, %d disagree (%s)\n", shadowed, considered, mismatched,
                    light);
        // Each small sphere hides (1 - cos(asin 0.2)) / 2 = 1 % of the directions; the cone sees at least one.
        EXPECT_GT(shadowed, considered / 200);
        EXPECT_LT(mismatched, considered / 1000 + 2) << mismatched << " of " << considered << ", " << shadowed << " shadowed";
    }
}

TEST(PreviewShadows, EnclosureImagesAgreeOnBothSidesInEveryDirection) {
    // Six views out of the enclosure (the camera beside the light, so that shadows show): GPU and CPU per pixel.
    // Measured 6, 0 and 0 pixels; the GPU lookup with its rows flipped gives 1435, 55 and 576.
    const char* looks[6] = {"[3, -1, 0.8]", "[-3, -1, 0.8]", "[-1, 3, 0.8]", "[-1, -3, 0.8]", "[-1, -1, 3]", "[-1, -1, -3]"};
    for (const char* light : kEnclosureLights) {
        int dark = 0, differ = 0, total = 0;
        for (const char* look : looks) {
            SCOPED_TRACE(std::string(light) + " looking at " + look);
            const Images img = render(enclosure(light, std::string(R"({"position": [-1, -1, 0.8], "look_at": )") + look +
                                                           R"(, "up": [0.3, 0.2, 1], "fov": 90})"));
            for (size_t i = 0; i < img.cpu.size(); i += 3) {
                const float c = img.cpu[i] + img.cpu[i + 1] + img.cpu[i + 2];
                const float g = img.gpu[i] + img.gpu[i + 1] + img.gpu[i + 2];
                dark += c == 0.f ? 1 : 0;
                differ += std::abs(c - g) > 1e-3f * std::max(c, 1e-2f) ? 1 : 0;
                ++total;
            }
        }
        SCOPED_TRACE(light);
        std::printf("enclosure views: %d of %d pixels differ, %d black (shadow, or outside a cone) (%s)\n", differ, total, dark, light);
        EXPECT_GT(dark, total / 200);  // shadows are in view
        EXPECT_LT(differ, total / 1000) << differ << " of " << total << " pixels differ, " << dark << " dark";
    }
}

namespace {

// The floor of scene() with a wall standing on it along the y axis (x = 0, 2 m high, 4 m long); one light.
std::string wallScene(const std::string& light, bool wall) {
    std::string s = scene(light, false);
    if (wall) {
        const std::string floor = R"("material": "grey"})";
        s.replace(s.find(floor), floor.size(),
                  floor + R"(, {"type": "quad", "size": [2, 4], "transform": {"translate": [0, 0, 1], "rotate": [0, 90, 0]},
                  "material": "grey"})");
    }
    return s;
}

}  // namespace

TEST(PreviewShadows, QuadAndEnvironmentLightsAreShadowedOnBothSides) {
    // A quad light at (2, 0, 3) facing down and a sky: the wall at x = 0 hides the quad's centre from the floor at
    // x < 0 up to x = -3 (the line from (2, 0, 3) over the wall's top at (0, 0, 2) meets the floor there), and hides the
    // sky's +x diagonals from floor points near it.
    struct EnvCase {
        const char* name;
        std::string light;
        float maxRatio;  // at x = -1: the shadowed beauty over the open one, at most
        float minRatio;  // ... at least
    };
    const EnvCase cases[] = {
        // The quad, seen from its centre: a hard shadow.
        {"quad", R"({"type": "quad", "position": [2, 0, 3], "look_at": [2, 0, 0], "size": [0.5, 0.5], "power": 200})", 1e-6f,
         0.f},
        // The sky: of the five shadow directions above the floor (+z with weight 1, four diagonals with cos = 0.577 each),
        // the wall hides the two towards +x: (1 + 2·0.577) / (1 + 4·0.577) = 0.651 of the open floor's light.
        {"environment", R"({"type": "environment", "color": [0.55, 0.65, 0.85], "strength": 1})", 0.652f, 0.650f},
    };
    for (const EnvCase& c : cases) {
        SCOPED_TRACE(c.name);
        const Images open = render(wallScene(c.light, false)), walled = render(wallScene(c.light, true));
        const float x = -1.f;
        const float o = at(open.cpu, x);
        ASSERT_GT(o, 0.01f);
        EXPECT_NEAR(at(open.gpu, x), o, 1e-3f * o);
        const float cpu = at(walled.cpu, x), gpu = at(walled.gpu, x);
        std::printf("%s: floor at x = -1 open %.6g, behind the wall %.6g (CPU) %.6g (GPU): %.4f of the open value\n",
                    c.name, double(o), double(cpu), double(gpu), double(cpu / o));
        EXPECT_LE(cpu, c.maxRatio * o);
        EXPECT_GE(cpu, c.minRatio * o);
        EXPECT_NEAR(gpu, cpu, 1e-3f * o);
        // Lit floor far from the wall (x = 3, beyond every shadow): the open value on both sides.
        EXPECT_NEAR(at(walled.cpu, 3.f), at(open.cpu, 3.f), 1e-6f * at(open.cpu, 3.f));
        EXPECT_NEAR(at(walled.gpu, 3.f), at(open.gpu, 3.f), 1e-3f * at(open.gpu, 3.f));
        // Per pixel, the two sides agree except along the edges of the shadow (the walled floor of every view).
        int differ = 0;
        for (size_t i = 0; i < walled.cpu.size(); ++i)
            if (std::abs(walled.cpu[i] - walled.gpu[i]) > 1e-3f * std::max(walled.cpu[i], 1e-3f)) ++differ;
        EXPECT_LT(differ, int(walled.cpu.size()) / 100) << differ << " channels differ";
    }
}

TEST(PreviewShadows, FrameBlockLayoutIsWhatThePackerWrites) {
    // The std140 offsets a GL program reports for frameBlockGlsl() (the light loop's view of the block) against the C++
    // offsets packLight and the frame upload write: every frame member and every light field of lights 0 and 1.
    std::string why;
    ASSERT_TRUE(gl::context(&why)) << why;
    const std::string vertex = "#version 450 core\n#define SPC_PREVIEW_FRAME_BINDING 0\n" + preview::frameBlockGlsl() + R"(
void main() {
    SpcPreviewLight l = spc_lights[spc_counts.x];
    gl_Position = spc_view_proj * (spc_eye + spc_forward + l.header + l.position + l.direction + l.edge_v + l.value +
                                   l.shadow + l.shadow_origin + l.shadow_right + l.shadow_up + l.shadow_axis);
}
)";
    const std::string fragment = "#version 450 core\nlayout(location = 0) out vec4 o;\nvoid main() { o = vec4(1.0); }\n";
    std::string log;
    const GLuint prog = gl::program(vertex, fragment, &log);
    ASSERT_NE(prog, 0u) << log;
    const std::vector<preview::FieldOffset> fields = preview::frameBlockOffsets();
    ASSERT_EQ(fields.size(), size_t(4 + 2 * 10));
    for (const preview::FieldOffset& f : fields) {
        const GLuint index = glGetProgramResourceIndex(prog, GL_UNIFORM, f.glslName.c_str());
        ASSERT_NE(index, GL_INVALID_INDEX) << f.glslName;
        const GLenum prop = GL_OFFSET;
        GLint offset = -1;
        glGetProgramResourceiv(prog, GL_UNIFORM, index, 1, &prop, 1, nullptr, &offset);
        EXPECT_EQ(size_t(offset), f.offset) << f.glslName;
    }
    const GLuint block = glGetProgramResourceIndex(prog, GL_UNIFORM_BLOCK, "SpeculaPreviewFrame");
    ASSERT_NE(block, GL_INVALID_INDEX);
    const GLenum prop = GL_BUFFER_DATA_SIZE;
    GLint size = 0;
    glGetProgramResourceiv(prog, GL_UNIFORM_BLOCK, block, 1, &prop, 1, nullptr, &size);
    EXPECT_EQ(size_t(size), sizeof(preview::FrameBlock));
    glDeleteProgram(prog);
    // packLight puts each fact in its named field.
    RasterLight r;
    r.kind = RasterLight::Kind::Quad;
    r.position = Vec3(1.f, 2.f, 3.f);
    r.edgeV = Vec3(4.f, 5.f, 6.f);
    r.twoSided = true;
    ShadowLight sh;
    sh.mode = ShadowMode::Directions;
    sh.firstLayer = 7;
    sh.reach = 8.f;
    const preview::PreviewLight l = preview::packLight(r, sh);
    EXPECT_EQ(l.header[0], float(int(RasterLight::Kind::Quad)));
    EXPECT_EQ(l.header[3], 1.f);
    EXPECT_EQ(l.position[1], 2.f);
    EXPECT_EQ(l.edge_v[2], 6.f);
    EXPECT_EQ(l.shadow[0], 4.f);
    EXPECT_EQ(l.shadow[1], 7.f);
    EXPECT_EQ(l.shadow_origin[3], 8.f);
}
