// The GPU preview: shapes as triangle meshes, one program per material (its GLSL module plus the light loop of
// preview_lights.glsl), resources bound from the module's manifest, six AOVs in one pass, read back into an ImageSet.
// The light transport is render.integrator "raster" of the CPU (Integrator::rasterLighting): keep the two alike.
#define GL_GLEXT_PROTOTYPES 1
#include "plugin/preview/preview.h"

#include "core/codegen/glsl_emitter.h"
#include "core/codegen/glsl_manifest.h"
#include "core/graph/graph.h"
#include "core/render/camera.h"
#include "core/render/environment_prefilter.h"
#include "core/render/integrator.h"
#include "core/render/lights.h"
#include "core/render/shadow_maps.h"
#include "core/scene/scene.h"
#include "core/util/error.h"
#include "plugin/preview/gl_util.h"
#include "plugin/preview/preview_frame.h"

#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <cmath>
#include <limits>
#include <memory>

namespace specula::embedded {
extern const char* const kPreviewLightsGlsl;  // plugin/preview/preview_lights.glsl
}

namespace specula::preview {

namespace {

constexpr int kAovCount = 5;    // beauty, diffuse, specular, normal, (depth, u, v)

// Without the #version line: versionHeader() puts it and the frame block's binding first.
// The mesh attributes (uploadMesh's order) as a stage's inputs or outputs: <prefix>_position, _normal, _tangent, _uv.
std::string attributes(const char* qualifier, const char* prefix) {
    const char* decl[4][2] = {{"vec3", "position"}, {"vec3", "normal"}, {"vec4", "tangent"}, {"vec2", "uv"}};
    std::string s;
    for (int k = 0; k < 4; ++k)
        s += "layout(location = " + std::to_string(k) + ") " + qualifier + " " + decl[k][0] + " " + prefix + "_" + decl[k][1] +
             ";\n";
    return s;
}
// The AOV attachments every fragment stage writes (readBack's order).
const char* const kAovOutputs = R"(
layout(location = 0) out vec4 o_beauty;
layout(location = 1) out vec4 o_diffuse;
layout(location = 2) out vec4 o_specular;
layout(location = 3) out vec4 o_normal;
layout(location = 4) out vec4 o_aux;
)";

const std::string kVertex = frameBlockGlsl() + attributes("in", "a") + attributes("out", "v") + R"(
void main() {
    v_position = a_position;
    v_normal = a_normal;
    v_tangent = a_tangent;
    v_uv = a_uv;
    gl_Position = spc_view_proj * vec4(a_position, 1.0);
}
)";

// Appended to a material's module: plugin/preview/preview_lights.glsl (embedded by core/codegen/embed_glsl.cmake), the
// shading point from the interpolated attributes, then every light by its closed form, as Integrator::rasterLighting.
std::string surfaceMain() {
    return frameBlockGlsl() + shadowLookupGlsl() + attributes("in", "v") + kAovOutputs + embedded::kPreviewLightsGlsl;
}
// Quad-light geometry: its radiance towards the viewer on the emitting side (QuadLight::radiance), no scattering.
const std::string kEmitterFragment = frameBlockGlsl() + attributes("in", "v") + kAovOutputs + R"(
layout(location = 0) uniform vec4 u_radiance;   // rgb, two-sided
layout(location = 1) uniform vec3 u_light_normal;
void main() {
    vec3 wi = normalize(v_position - spc_eye.xyz);
    bool lit = u_radiance.w != 0.0 || -dot(wi, u_light_normal) > 0.0;
    vec3 Ng = normalize(cross(dFdx(v_position), dFdy(v_position)));
    if (dot(Ng, wi) > 0.0) Ng = -Ng;
    vec3 N = dot(v_normal, v_normal) > 0.0 ? normalize(gl_FrontFacing ? v_normal : -v_normal) : Ng;
    o_beauty = vec4(lit ? u_radiance.rgb : vec3(0.0), 1.0);
    o_diffuse = vec4(0.0, 0.0, 0.0, 1.0);
    o_specular = vec4(0.0, 0.0, 0.0, 1.0);
    o_normal = vec4(N, 1.0);
    o_aux = vec4(dot(v_position - spc_eye.xyz, spc_forward.xyz), v_uv, 1.0);
}
)";

// Escaped rays: the environment map by the nearest texel (EnvironmentLight::radiance), behind everything.
const std::string kBackgroundVertex = std::string("#version 450 core\n") + R"(
layout(location = 0) out vec2 v_ndc;
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
    v_ndc = p;
    gl_Position = vec4(p, 0.0, 1.0);  // depth 0: infinitely far under the reversed-Z pass
}
)";
const std::string kBackgroundFragment = std::string("#version 450 core\n") + kAovOutputs + R"(
layout(location = 0) in vec2 v_ndc;
layout(binding = 0) uniform sampler2D u_map;
layout(location = 0) uniform vec3 u_forward;
layout(location = 1) uniform vec3 u_right;  // times the half width
layout(location = 2) uniform vec3 u_up;     // times the half height
layout(location = 3) uniform vec3 u_constant;
layout(location = 4) uniform vec4 u_map_scale;  // rgb scale, rotation (radians); u_map_size.x == 0: no map
layout(location = 5) uniform ivec2 u_map_size;
void main() {
    vec3 d = normalize(u_forward + v_ndc.x * u_right + v_ndc.y * u_up);
    vec3 L = u_constant;
    if (u_map_size.x > 0) {
        float c = cos(u_map_scale.w), s = sin(u_map_scale.w);
        vec3 r = vec3(c * d.x + s * d.y, -s * d.x + c * d.y, d.z);
        float u = 0.5 - atan(r.y, -r.x) * 0.15915494309189535;
        u -= floor(u);
        float v = acos(clamp(r.z, -1.0, 1.0)) * 0.3183098861837907;
        ivec2 t = clamp(ivec2(int(u * float(u_map_size.x)), int(v * float(u_map_size.y))), ivec2(0), u_map_size - 1);
        L += texelFetch(u_map, ivec2(t.x, u_map_size.y - 1 - t.y), 0).rgb * u_map_scale.rgb;
    }
    o_beauty = vec4(L, 1.0);
    o_diffuse = vec4(0.0, 0.0, 0.0, 1.0);
    o_specular = vec4(0.0, 0.0, 0.0, 1.0);
    o_normal = vec4(0.0, 0.0, 0.0, 1.0);
    o_aux = vec4(1e10, 0.0, 0.0, 1.0);
}
)";

// Shadow maps (core/render/shadow_maps.h): each layer stores the depth along its view axis of the nearest surface at its
// texel centres, interpolated world position minus the view origin dotted with the axis, as the CPU's rays compute it.
const std::string kShadowVertex = std::string("#version 450 core\n") + R"(
layout(location = 0) in vec3 a_position;
layout(location = 0) uniform mat4 u_clip;
layout(location = 0) out vec3 v_position;
void main() {
    v_position = a_position;
    gl_Position = u_clip * vec4(a_position, 1.0);
}
)";
const std::string kShadowFragment = std::string("#version 450 core\n") + R"(
layout(location = 0) in vec3 v_position;
layout(location = 1) uniform vec3 u_origin;
layout(location = 2) uniform vec3 u_axis;
layout(location = 0) out float o_depth;
void main() {
    precise float d = dot(v_position - u_origin, u_axis);
    o_depth = d;
}
)";

// A shadow view's clip transform: x, y = scale·(q·right, q·up), w = q·axis (perspective) or 1 (ortho), z mapping
// [zNear, zFar] along the axis to [-1, 1]; q = p - origin. Column-major.
void shadowClip(const ShadowView& v, float* out) {
    const float n = v.zNear, f = v.zFar;
    Vec3 rows[4];
    float add[4];
    rows[0] = v.right * v.scale, rows[1] = v.up * v.scale;
    add[0] = add[1] = 0.f;
    if (v.ortho) {
        rows[2] = v.axis * (2.f / (f - n)), add[2] = -(f + n) / (f - n);
        rows[3] = Vec3(0.f), add[3] = 1.f;
    } else {
        rows[2] = v.axis * ((f + n) / (f - n)), add[2] = -2.f * f * n / (f - n);
        rows[3] = v.axis, add[3] = 0.f;
    }
    for (int i = 0; i < 4; ++i) {
        out[0 * 4 + i] = rows[i].x;
        out[1 * 4 + i] = rows[i].y;
        out[2 * 4 + i] = rows[i].z;
        out[3 * 4 + i] = -glm::dot(rows[i], v.origin) + add[i];
    }
}

struct GpuMesh {
    GLuint vbo = 0, ebo = 0, vao = 0;
    GLsizei indexCount = 0;
};

GpuMesh uploadMesh(const TriangleMesh& m) {
    const size_t n = m.positions.size();
    std::vector<float> v(n * 12, 0.f);
    for (size_t i = 0; i < n; ++i) {
        float* o = &v[i * 12];
        o[0] = m.positions[i].x, o[1] = m.positions[i].y, o[2] = m.positions[i].z;
        if (!m.normals.empty()) o[3] = m.normals[i].x, o[4] = m.normals[i].y, o[5] = m.normals[i].z;
        if (!m.tangents.empty()) o[6] = m.tangents[i].x, o[7] = m.tangents[i].y, o[8] = m.tangents[i].z, o[9] = m.tangents[i].w;
        if (!m.uvs.empty()) o[10] = m.uvs[i].x, o[11] = m.uvs[i].y;
    }
    GpuMesh g;
    glGenVertexArrays(1, &g.vao);
    glBindVertexArray(g.vao);
    glGenBuffers(1, &g.vbo);
    glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_STATIC_DRAW);
    const GLint sizes[4] = {3, 3, 4, 2};
    const size_t offsets[4] = {0, 3, 6, 10};
    for (GLuint a = 0; a < 4; ++a) {
        glEnableVertexAttribArray(a);
        glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, 12 * sizeof(float),
                              reinterpret_cast<const void*>(offsets[a] * sizeof(float)));
    }
    glGenBuffers(1, &g.ebo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(m.indices.size() * sizeof(glm::uvec3)), m.indices.data(),
                 GL_STATIC_DRAW);
    g.indexCount = GLsizei(m.indices.size() * 3);
    return g;
}

// The camera as a clip transform that puts frame pixel (x, y) (top-left origin) at GL window pixel (x, H-1-y): the
// CPU's pixel-centre rays pass through the same points as the rasteriser's fragment centres.
// Reversed-Z with an infinite far plane (used with glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE), a 32-bit float
// depth buffer, GL_GREATER): depth = zNear / distance along the view axis, 1 at the near plane, 0 at infinity. The
// float's relative precision then holds at every distance; the standard mapping with zNear = 1e-5 zFar resolved depth
// to about 0.6 % of the distance near the far plane, so back faces showed through the far silhouettes of thin tubes.
void viewProjection(const PerspectiveCamera& cam, float zNear, float* out) {
    const Vec3 f = cam.forward(), r = cam.right(), u = cam.up(), e = cam.position();
    const float sx = 1.f / cam.halfWidth(), sy = 1.f / cam.halfHeight();
    // Rows of clip = M (p - e): x = sx r·d, y = sy u·d, z = zNear, w = f·d.
    const Vec3 rows[4] = {r * sx, u * sy, Vec3(0.f), f};
    const float add[4] = {0.f, 0.f, zNear, 0.f};
    for (int i = 0; i < 4; ++i) {
        // column-major: out[col * 4 + row]
        out[0 * 4 + i] = rows[i].x;
        out[1 * 4 + i] = rows[i].y;
        out[2 * 4 + i] = rows[i].z;
        out[3 * 4 + i] = -glm::dot(rows[i], e) + add[i];
    }
}

// The preview's own defines, after a module (or after versionHeader): the frame block's uniform-buffer binding, the
// shadow maps' texture unit (the prefiltered environment's two follow it), the chain's levels and the CPU's hemisphere
// lift (integrator.h).
std::string glslDefines(int frameBinding, int shadowBinding) {
    char buf[300];
    std::snprintf(buf, sizeof buf,
                  "#define SPC_PREVIEW_FRAME_BINDING %d\n#define SPC_PREVIEW_SHADOW_BINDING %d\n"
                  "#define SPC_PREVIEW_ENV_BINDING %d\n#define SPC_PREVIEW_ENV_LEVELS %d\n"
                  "#define SPC_PREVIEW_HEMISPHERE_LIFT %.9g\n",
                  frameBinding, shadowBinding, shadowBinding + 1, kEnvironmentLevels, double(kRasterHemisphereLift));
    return buf;
}
// A module with the preview's prefiltered environment: SPECULA_HOST_ENVIRONMENT defined right after its #version line,
// before the prelude (which then declares spc_host_environment; surfaceMain defines it).
std::string withHostEnvironment(const std::string& module) {
    const size_t eol = module.find('\n');
    if (eol == std::string::npos || module.compare(0, 8, "#version") != 0)
        throw std::logic_error("a generated GLSL module does not start with its #version line");
    return module.substr(0, eol + 1) + "#define SPECULA_HOST_ENVIRONMENT\n" + module.substr(eol + 1);
}
std::string versionHeader(int frameBinding, int shadowBinding) {
    return "#version 450 core\n" + glslDefines(frameBinding, shadowBinding);
}

}  // namespace

struct PreviewRenderer::State {
    const Scene& scene;
    std::vector<RasterLight> rasterLights;
    const RasterLight* map = nullptr;
    Color3 background{0.f};
    FrameBlock frame{};
    GLuint frameBuffer = 0;
    int frameBinding = 0;  // the frame block's uniform-buffer binding: after every module's block
    int shadowBinding = 0;  // the shadow maps' texture unit: after every module's resources
    ShadowLayout shadows;
    GLuint shadowTexture = 0;  // GL_TEXTURE_2D_ARRAY of R32F, one layer per shadow view (a 1x1 dummy without any)
    struct MaterialGpu {
        GLuint program = 0;
        std::unique_ptr<gl::ManifestBindings> bindings;
    };
    std::vector<MaterialGpu> mats;
    GLuint emitterProgram = 0, backgroundProgram = 0, mapTexture = 0;
    std::vector<GpuMesh> meshes;
    float sceneFar = 1e-3f;  // the largest distance from the scene camera to a vertex; bounds the far plane
    // The AOV target, made for the size of the last draw.
    int width = 0, height = 0;
    GLuint fbo = 0, depth = 0, colour[kAovCount] = {};
    GLuint query = 0;
    std::vector<std::string> warnings;

    explicit State(const Scene& s) : scene(s) {}
    void makeTarget(int W, int H);
    void freeTarget();
    void renderShadowMaps();
    // The environment map's split-sum textures (prefilterEnvironment, the CPU twin's data): the specular chain as the
    // mip levels of one texture, read with GL_LINEAR_MIPMAP_LINEAR, and the irradiance map; row 0 = +z, u repeats.
    GLuint envTextures[2] = {};
    void uploadEnvironment(const PrefilteredEnvironment& env);
};

void PreviewRenderer::State::uploadEnvironment(const PrefilteredEnvironment& env) {
    glGenTextures(2, envTextures);
    auto upload = [](const EnvironmentImage& img, int level) {
        std::vector<float> rgba(size_t(img.width) * img.height * 4, 1.f);
        for (size_t i = 0; i < size_t(img.width) * img.height; ++i)
            for (int c = 0; c < 3; ++c) rgba[i * 4 + size_t(c)] = img.rgb[i * 3 + size_t(c)];
        glTexSubImage2D(GL_TEXTURE_2D, level, 0, 0, img.width, img.height, GL_RGBA, GL_FLOAT, rgba.data());
    };
    auto params = [](GLint minFilter, int maxLevel) {
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, minFilter);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, maxLevel);
    };
    glBindTexture(GL_TEXTURE_2D, envTextures[0]);
    glTexStorage2D(GL_TEXTURE_2D, GLsizei(env.levels.size()), GL_RGBA32F, env.levels[0].width, env.levels[0].height);
    for (size_t k = 0; k < env.levels.size(); ++k) upload(env.levels[k], int(k));
    params(GL_LINEAR_MIPMAP_LINEAR, int(env.levels.size()) - 1);
    glBindTexture(GL_TEXTURE_2D, envTextures[1]);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, env.irradiance.width, env.irradiance.height);
    upload(env.irradiance, 0);
    params(GL_LINEAR, 0);
}

// Every layer of the shadow layout, once (the maps do not depend on the camera): all shapes but the quad lights'
// emitters (drawn in their own pass, as the CPU's map rays pass through them), nearest surface by the depth test.
void PreviewRenderer::State::renderShadowMaps() {
    const int N = std::max(1, shadows.size), L = std::max(1, shadows.layers());
    glGenTextures(1, &shadowTexture);
    glBindTexture(GL_TEXTURE_2D_ARRAY, shadowTexture);
    glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_R32F, N, N, L);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    const float empty[4] = {std::numeric_limits<float>::max(), 0.f, 0.f, 0.f};
    if (shadows.layers() == 0) {
        glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, 0, 1, 1, 1, GL_RED, GL_FLOAT, empty);
        return;
    }
    std::string log;
    const GLuint prog = gl::program(kShadowVertex, kShadowFragment, &log);
    if (!prog) throw IoError("the preview's shadow-map shaders do not compile: " + log);
    GLuint fb = 0, depthBuffer = 0;
    glGenFramebuffers(1, &fb);
    glBindFramebuffer(GL_FRAMEBUFFER, fb);
    glGenRenderbuffers(1, &depthBuffer);
    glBindRenderbuffer(GL_RENDERBUFFER, depthBuffer);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, N, N);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depthBuffer);
    glUseProgram(prog);
    glViewport(0, 0, N, N);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    for (int layer = 0; layer < shadows.layers(); ++layer) {
        const ShadowView& v = shadows.views[size_t(layer)];
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, shadowTexture, 0, layer);
        glDrawBuffer(GL_COLOR_ATTACHMENT0);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            throw IoError("the preview's shadow-map target is incomplete (" + std::to_string(N) + "x" + std::to_string(N) + ")");
        glClearBufferfv(GL_COLOR, 0, empty);
        glClearDepth(1.0);
        glClear(GL_DEPTH_BUFFER_BIT);
        float clip[16];
        shadowClip(v, clip);
        glUniformMatrix4fv(0, 1, GL_FALSE, clip);
        glUniform3f(1, v.origin.x, v.origin.y, v.origin.z);
        glUniform3f(2, v.axis.x, v.axis.y, v.axis.z);
        for (size_t i = 0; i < scene.shapes.size(); ++i) {
            if (scene.shapes[i].areaLight >= 0) continue;
            glBindVertexArray(meshes[i].vao);
            glDrawElements(GL_TRIANGLES, meshes[i].indexCount, GL_UNSIGNED_INT, nullptr);
        }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteRenderbuffers(1, &depthBuffer);
    glDeleteFramebuffers(1, &fb);
    glDeleteProgram(prog);
}

void PreviewRenderer::State::freeTarget() {
    if (!fbo) return;
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(kAovCount, colour);
    glDeleteRenderbuffers(1, &depth);
    fbo = depth = 0;
    width = height = 0;
}

// Five RGBA32F attachments and a float depth buffer.
void PreviewRenderer::State::makeTarget(int W, int H) {
    if (fbo && W == width && H == height) return;
    freeTarget();
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glGenTextures(kAovCount, colour);
    GLenum drawBuffers[kAovCount];
    for (int i = 0; i < kAovCount; ++i) {
        glBindTexture(GL_TEXTURE_2D, colour[i]);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, W, H, 0, GL_RGBA, GL_FLOAT, nullptr);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + i), GL_TEXTURE_2D, colour[i], 0);
        drawBuffers[i] = GLenum(GL_COLOR_ATTACHMENT0 + i);
    }
    glGenRenderbuffers(1, &depth);
    glBindRenderbuffer(GL_RENDERBUFFER, depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, W, H);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    glDrawBuffers(kAovCount, drawBuffers);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw IoError("the preview's render target is incomplete (" + std::to_string(W) + "x" + std::to_string(H) + ")");
    width = W;
    height = H;
}

PreviewRenderer::PreviewRenderer(const Scene& scene, const nlohmann::json& materials, const std::string& baseDir)
    : s_(std::make_unique<State>(scene)) {
    State& st = *s_;
    {
        PerspectiveCamera camera(scene.camera, std::max(1, scene.render.width), std::max(1, scene.render.height));
        for (const ShapeInstance& sh : scene.shapes)
            for (const Vec3& p : sh.mesh.positions) st.sceneFar = std::max(st.sceneFar, glm::length(p - camera.position()));
    }
    for (const auto& light : scene.lights) st.rasterLights.push_back(light->raster());
    int count = 0;
    for (const RasterLight& r : st.rasterLights) {
        if (r.kind == RasterLight::Kind::Mesh) break;  // mesh lights come last; the preview does not light with them
        if (r.kind == RasterLight::Kind::Environment) {
            if (r.hasMap) {
                if (st.map) throw InputError("/lights", "the preview shows one environment map (the scene has several)");
                st.map = &r;
            } else {
                st.background += r.value;
            }
        }
        if (count == kMaxLights) throw InputError("/lights", "the preview takes at most 64 lights");
        ++count;
    }
    st.shadows = planShadowMaps(scene, st.rasterLights);
    for (int i = 0; i < count; ++i) st.frame.lights[i] = packLight(st.rasterLights[size_t(i)], st.shadows.lights[size_t(i)]);
    st.frame.counts[0] = count;
    st.frame.counts[1] = scene.render.ltcHorizon;
    glGenBuffers(1, &st.frameBuffer);
    glBindBuffer(GL_UNIFORM_BUFFER, st.frameBuffer);
    glBufferData(GL_UNIFORM_BUFFER, sizeof st.frame, &st.frame, GL_DYNAMIC_DRAW);

    // One program per material: its module (its uniform block and resources where its manifest says) plus the light
    // loop. The frame block takes the first uniform-buffer binding after every module's block.
    st.mats.resize(scene.materials.size());
    std::vector<std::string> sources(scene.materials.size());
    for (size_t m = 0; m < scene.materials.size(); ++m) {
        const std::string& name = scene.materials[m]->name();
        const std::string pointer = "/materials/" + pointerEscape(name);
        if (!materials.contains(name)) throw InputError(pointer, "material '" + name + "' is not in the document");
        graph::GraphDesc g = graph::parseGraph(materials.at(name), pointer);
        codegen::GlslModule mod = codegen::emitGlsl(g, {});
        for (const std::string& w : mod.warnings) st.warnings.push_back("material '" + name + "': " + w);
        std::vector<graph::ResourceImage> images =
            codegen::exportGlslResources(g, mod, GraphLoadContext{scene.textures.get(), baseDir});
        const nlohmann::json manifest = codegen::glslManifest(mod, images, {});
        if (manifest.contains("uniform_block") && manifest["uniform_block"].is_object())
            st.frameBinding = std::max(st.frameBinding, manifest["uniform_block"].value("binding", 0) + 1);
        if (manifest.contains("resources") && manifest["resources"].is_array())
            for (const nlohmann::json& res : manifest["resources"])
                st.shadowBinding = std::max(st.shadowBinding, res.value("binding", 0) + 1);
        st.mats[m].bindings = std::make_unique<gl::ManifestBindings>();
        st.mats[m].bindings->add(manifest, images);
        sources[m] = std::move(mod.source);
    }
    const std::string vertex = versionHeader(st.frameBinding, st.shadowBinding) + kVertex;
    for (size_t m = 0; m < scene.materials.size(); ++m) {
        // The module starts with its #version line; the defines and the main go after the whole module.
        std::string log;
        st.mats[m].program = gl::program(
            vertex, withHostEnvironment(sources[m]) + glslDefines(st.frameBinding, st.shadowBinding) + surfaceMain(), &log);
        if (!st.mats[m].program) {
            const std::string& name = scene.materials[m]->name();
            throw InputError("/materials/" + pointerEscape(name),
                             "the preview shader of material '" + name + "' does not compile: " + log);
        }
    }
    std::string log;
    st.emitterProgram = gl::program(vertex, versionHeader(st.frameBinding, st.shadowBinding) + kEmitterFragment, &log);
    st.backgroundProgram = st.emitterProgram ? gl::program(kBackgroundVertex, kBackgroundFragment, &log) : 0;
    if (!st.backgroundProgram) throw IoError("the preview's own shaders do not compile: " + log);
    if (const RasterLight* map = st.map) {
        std::vector<float> rgba(size_t(map->mapWidth) * map->mapHeight * 4, 1.f);
        for (int y = 0; y < map->mapHeight; ++y)  // GL row 0 is the bottom row
            for (int x = 0; x < map->mapWidth; ++x)
                for (int c = 0; c < 3; ++c)
                    rgba[(size_t(map->mapHeight - 1 - y) * map->mapWidth + x) * 4 + c] =
                        map->map[(size_t(y) * map->mapWidth + x) * 3 + c];
        glGenTextures(1, &st.mapTexture);
        glBindTexture(GL_TEXTURE_2D, st.mapTexture);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, map->mapWidth, map->mapHeight, 0, GL_RGBA, GL_FLOAT, rgba.data());
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        st.uploadEnvironment(prefilterEnvironment(*map));
    }
    for (const ShapeInstance& sh : scene.shapes) st.meshes.push_back(uploadMesh(sh.mesh));
    st.renderShadowMaps();
    glGenQueries(1, &st.query);
}

PreviewRenderer::~PreviewRenderer() {
    State& st = *s_;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    st.freeTarget();
    glDeleteQueries(1, &st.query);
    glDeleteBuffers(1, &st.frameBuffer);
    if (st.mapTexture) glDeleteTextures(1, &st.mapTexture);
    if (st.envTextures[0]) glDeleteTextures(2, st.envTextures);
    if (st.shadowTexture) glDeleteTextures(1, &st.shadowTexture);
    for (GpuMesh& m : st.meshes) {
        glDeleteBuffers(1, &m.vbo);
        glDeleteBuffers(1, &m.ebo);
        glDeleteVertexArrays(1, &m.vao);
    }
    for (State::MaterialGpu& m : st.mats) glDeleteProgram(m.program);
    glDeleteProgram(st.emitterProgram);
    glDeleteProgram(st.backgroundProgram);
}

const std::vector<std::string>& PreviewRenderer::warnings() const { return s_->warnings; }
unsigned PreviewRenderer::beautyTexture() const { return s_->colour[0]; }
unsigned PreviewRenderer::framebuffer() const { return s_->fbo; }
unsigned PreviewRenderer::aovTexture(int attachment) const {
    return attachment >= 0 && attachment < kAovCount ? s_->colour[attachment] : 0;
}

double PreviewRenderer::draw(const CameraDesc& cameraDesc, int W, int H) {
    State& st = *s_;
    const Scene& scene = st.scene;
    st.makeTarget(W, H);
    PerspectiveCamera camera(cameraDesc, W, H);
    // The near plane from the scene's extent (seen from the scene camera; a moved camera adds its offset).
    const float zFar = (st.sceneFar + glm::length(camera.position() - PerspectiveCamera(scene.camera, W, H).position())) * 1.01f;
    const float zNear = std::max(zFar * 1e-5f, 1e-5f);
    FrameBlock& frame = st.frame;
    viewProjection(camera, zNear, frame.view_proj);
    frame.eye[0] = camera.position().x, frame.eye[1] = camera.position().y, frame.eye[2] = camera.position().z;
    frame.forward[0] = camera.forward().x, frame.forward[1] = camera.forward().y, frame.forward[2] = camera.forward().z;
    glBindBuffer(GL_UNIFORM_BUFFER, st.frameBuffer);
    glBufferSubData(GL_UNIFORM_BUFFER, 0, sizeof frame, &frame);

    glBindFramebuffer(GL_FRAMEBUFFER, st.fbo);
    glBeginQuery(GL_TIME_ELAPSED, st.query);
    glViewport(0, 0, W, H);
    glEnable(GL_DEPTH_TEST);
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);  // reversed-Z (viewProjection); restored after the pass
    glDepthFunc(GL_GREATER);
    glDisable(GL_CULL_FACE);
    glClearDepth(0.0);
    glClear(GL_DEPTH_BUFFER_BIT);
    glBindBufferBase(GL_UNIFORM_BUFFER, GLuint(st.frameBinding), st.frameBuffer);
    glActiveTexture(GLenum(GL_TEXTURE0 + st.shadowBinding));
    glBindTexture(GL_TEXTURE_2D_ARRAY, st.shadowTexture);
    for (int k = 0; k < 2; ++k) {
        glActiveTexture(GLenum(GL_TEXTURE0 + st.shadowBinding + 1 + k));
        glBindTexture(GL_TEXTURE_2D, st.envTextures[k]);
    }
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
        const ShapeInstance& sh = scene.shapes[i];
        if (sh.areaLight >= 0) {
            const RasterLight& r = st.rasterLights[size_t(sh.areaLight)];
            if (!r.cameraVisible) continue;  // the camera sees through it (Light::cameraVisible)
            glUseProgram(st.emitterProgram);
            glUniform4f(0, r.value.x, r.value.y, r.value.z, r.twoSided ? 1.f : 0.f);
            Vec3 n = glm::normalize(glm::cross(r.direction, r.edgeV));
            glUniform3f(1, n.x, n.y, n.z);
        } else {
            glUseProgram(st.mats[size_t(sh.material)].program);
            st.mats[size_t(sh.material)].bindings->bind();
            glBindBufferBase(GL_UNIFORM_BUFFER, GLuint(st.frameBinding), st.frameBuffer);
        }
        glBindVertexArray(st.meshes[i].vao);
        glDrawElements(GL_TRIANGLES, st.meshes[i].indexCount, GL_UNSIGNED_INT, nullptr);
    }
    // Background where no surface is: depth 0 (infinity) passes GL_GEQUAL only where the depth buffer is still clear.
    glDepthFunc(GL_GEQUAL);
    glUseProgram(st.backgroundProgram);
    const Vec3 fw = camera.forward(), rt = camera.right() * camera.halfWidth(), up = camera.up() * camera.halfHeight();
    const RasterLight* map = st.map;
    glUniform3f(0, fw.x, fw.y, fw.z);
    glUniform3f(1, rt.x, rt.y, rt.z);
    glUniform3f(2, up.x, up.y, up.z);
    glUniform3f(3, st.background.x, st.background.y, st.background.z);
    glUniform4f(4, map ? map->mapScale.x : 0.f, map ? map->mapScale.y : 0.f, map ? map->mapScale.z : 0.f,
                map ? map->mapRotation : 0.f);
    glUniform2i(5, map ? map->mapWidth : 0, map ? map->mapHeight : 0);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, st.mapTexture);
    glBindVertexArray(st.meshes.empty() ? 0 : st.meshes[0].vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glEndQuery(GL_TIME_ELAPSED);
    glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);  // GL's default again for the shadow passes and hosts
    GLuint64 ns = 0;
    glGetQueryObjectui64v(st.query, GL_QUERY_RESULT, &ns);
    return double(ns);
}

ImageSet PreviewRenderer::readBack() const {
    const State& st = *s_;
    const int W = st.width, H = st.height;
    ImageSet img;
    img.width = W;
    img.height = H;
    if (!st.fbo) return img;
    glBindFramebuffer(GL_READ_FRAMEBUFFER, st.fbo);
    std::vector<float> px(size_t(W) * H * 4);
    auto addAov = [&](const char* name, std::vector<std::string> channels, int attachment, int firstChannel) {
        glReadBuffer(GLenum(GL_COLOR_ATTACHMENT0 + attachment));
        glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px.data());
        AovBuffer b;
        b.name = name;
        b.channelNames = std::move(channels);
        const size_t nc = b.channelNames.size();
        b.pixels.resize(size_t(W) * H * nc);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (size_t c = 0; c < nc; ++c)
                    b.pixels[(size_t(y) * W + x) * nc + c] = px[(size_t(H - 1 - y) * W + x) * 4 + size_t(firstChannel) + c];
        img.aovs.push_back(std::move(b));
    };
    img.aovs.reserve(6);
    addAov("beauty", {"R", "G", "B"}, 0, 0);
    addAov("diffuse", {"R", "G", "B"}, 1, 0);
    addAov("specular", {"R", "G", "B"}, 2, 0);
    addAov("normal", {"X", "Y", "Z"}, 3, 0);
    addAov("uv", {"U", "V"}, 4, 1);
    addAov("depth", {"Z"}, 4, 0);
    return img;
}

PreviewScene loadPreviewScene(const std::string& path, const SceneOverrides& overrides) {
    const std::string text = readJsonText(path);  // bounded, as every reader of scene files (issue 35)
    PreviewScene ps;
    ps.baseDir = std::filesystem::path(path).parent_path().string();
    if (ps.baseDir.empty()) ps.baseDir = ".";
    ps.scene = loadSceneFromString(text, ps.baseDir, overrides, path);
    const nlohmann::json doc = nlohmann::json::parse(text);  // valid: the loader accepted it
    if (doc.contains("materials")) ps.materials = doc["materials"];
    return ps;
}

PreviewOutput renderPreview(const Scene& scene, const nlohmann::json& materials, const std::string& baseDir,
                            const PreviewOptions& options) {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    std::string why;
    if (!gl::context(&why)) throw IoError("no OpenGL 4.5 context for the preview: " + why);
    PreviewOutput result;
    result.renderer = gl::renderer();
    const int W = scene.render.width, H = scene.render.height;
    PreviewRenderer renderer(scene, materials, baseDir);
    result.warnings = renderer.warnings();
    result.setupSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
    double gpuNs = 0.0, wallNs = 0.0;
    const int frames = std::max(1, options.frames);
    glFinish();
    auto frameStart = Clock::now();
    for (int f = 0; f < frames; ++f) {
        gpuNs += renderer.draw(scene.camera, W, H);
        glFinish();
        const auto now = Clock::now();
        wallNs += std::chrono::duration<double, std::nano>(now - frameStart).count();
        frameStart = now;
    }
    result.gpuMsPerFrame = gpuNs / frames * 1e-6;
    result.wallMsPerFrame = wallNs / frames * 1e-6;
    ImageSet& img = result.output.images;
    img = renderer.readBack();
    img.metadata["specula:renderer"] = "preview (" + result.renderer + ")";
    img.metadata["specula:spp"] = "1";
    img.metadata["specula:version"] = SPECULA_VERSION;
    result.output.stats.samples = uint64_t(W) * H;
    result.output.stats.tilesDone = result.output.stats.tilesTotal = 1;
    result.output.stats.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return result;
}

}  // namespace specula::preview
