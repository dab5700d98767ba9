// The GPU preview: shapes as triangle meshes, one program per material (its GLSL module plus the light loop below),
// resources bound from the module's manifest, six AOVs in one pass, read back into the renderer's ImageSet.
// The light transport is render.integrator "raster" of the CPU (Integrator::rasterLighting): keep the two alike.
#define GL_GLEXT_PROTOTYPES 1
#include "plugin/preview/preview.h"

#include "core/codegen/glsl_emitter.h"
#include "core/codegen/glsl_manifest.h"
#include "core/graph/graph.h"
#include "core/render/camera.h"
#include "core/render/integrator.h"
#include "core/render/lights.h"
#include "core/scene/scene.h"
#include "core/util/error.h"
#include "plugin/preview/gl_util.h"

#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

namespace specula::preview {

namespace {

constexpr int kMaxLights = 64;
constexpr int kLightVec4s = 5;  // per light: (kind, cos outer, cos inner, two-sided), position, direction, edge v, value
constexpr int kAovCount = 5;    // beauty, diffuse, specular, normal, (depth, u, v)

// The per-frame block shared by the vertex and fragment stages (std140: mat4, vec4s, ivec4, vec4 array).
struct FrameBlock {
    float viewProj[16];
    float eye[4], forward[4];
    int counts[4];  // light count, LTC horizon, 0, 0
    float lights[kMaxLights * kLightVec4s][4];
};

const char* kFrameBlockGlsl = R"(
layout(std140, binding = 1) uniform SpeculaPreviewFrame {
    mat4 spc_view_proj;
    vec4 spc_eye;
    vec4 spc_forward;
    ivec4 spc_counts;
    vec4 spc_lights[64 * 5];
};
)";

const std::string kVertex = std::string("#version 450 core\n") + kFrameBlockGlsl + R"(
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_tangent;
layout(location = 3) in vec2 a_uv;
layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec4 v_tangent;
layout(location = 3) out vec2 v_uv;
void main() {
    v_position = a_position;
    v_normal = a_normal;
    v_tangent = a_tangent;
    v_uv = a_uv;
    gl_Position = spc_view_proj * vec4(a_position, 1.0);
}
)";

// Appended to a material's module: the shading point from the interpolated attributes (two-sided as on the CPU: the
// frame faces the viewer), then every light by its closed form, as Integrator::rasterLighting.
const std::string kSurfaceMain = std::string(kFrameBlockGlsl) + R"(
layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec4 v_tangent;
layout(location = 3) in vec2 v_uv;
layout(location = 0) out vec4 o_beauty;
layout(location = 1) out vec4 o_diffuse;
layout(location = 2) out vec4 o_specular;
layout(location = 3) out vec4 o_normal;
layout(location = 4) out vec4 o_aux;

vec3 spc_preview_diffuse, spc_preview_specular;
void spc_preview_add(SpeculaClosure c, vec3 L) {
    spc_preview_diffuse += c.f_diffuse * L;
    spc_preview_specular += (c.f - c.f_diffuse) * L;
}
float spc_preview_spot(float c, float cos_outer, float cos_inner) {
    if (c >= cos_inner) return 1.0;
    if (c <= cos_outer) return 0.0;
    float t = (c - cos_outer) / max(cos_inner - cos_outer, 1e-6);
    return t * t * (3.0 - 2.0 * t);
}

void main() {
    vec3 P = v_position;
    vec3 wo = normalize(spc_eye.xyz - P);
    vec3 Ng = normalize(cross(dFdx(P), dFdy(P)));  // faces the viewer (screen x cross screen y)
    if (dot(Ng, wo) < 0.0) Ng = -Ng;
    vec3 N = dot(v_normal, v_normal) > 0.0 ? normalize(gl_FrontFacing ? v_normal : -v_normal) : Ng;
    vec4 T = v_tangent;
    if (dot(T.xyz, T.xyz) <= 0.0) {
        vec3 t0, b0, n0;
        spc_frame(N, vec3(0.0), t0, b0, n0);
        T = vec4(t0, 1.0);
    }
    SpeculaShadingInputs s = specula_shading_inputs(P, N, Ng, T, v_uv, wo);
    SpeculaClosure c;
    specula_material(specula_direction_query(wo, wo, 1.0 / 0.0), s, c);
    vec3 emission = c.emission;
    spc_preview_diffuse = vec3(0.0);
    spc_preview_specular = vec3(0.0);
    const float inf = 1.0 / 0.0;
    for (int i = 0; i < spc_counts.x; ++i) {
        vec4 h = spc_lights[5 * i];
        vec3 a = spc_lights[5 * i + 1].xyz, b = spc_lights[5 * i + 2].xyz, e = spc_lights[5 * i + 3].xyz;
        vec3 value = spc_lights[5 * i + 4].xyz;
        int kind = int(h.x);
        if (kind <= 1) {  // point, spot
            vec3 d = a - P;
            float d2 = dot(d, d);
            if (!(d2 > 0.0)) continue;
            float dist = sqrt(d2);
            vec3 wi = d / dist;
            if (dot(wi, s.geometric_normal) <= 0.0) continue;
            float falloff = kind == 1 ? spc_preview_spot(dot(-wi, b), h.y, h.z) : 1.0;
            if (falloff <= 0.0) continue;
            specula_material(specula_direction_query(wo, wi, dist), s, c);
            spc_preview_add(c, value * (falloff / d2));
        } else if (kind == 2) {  // directional: b = towards the light
            if (dot(b, s.geometric_normal) <= 0.0) continue;
            specula_material(specula_direction_query(wo, b, inf), s, c);
            spc_preview_add(c, value);
        } else if (kind == 3) {  // quad: corner a, edges b and e (QuadLight::polygon's winding)
            vec3 n = normalize(cross(b, e));
            float side = dot(P - a, n);
            if (side == 0.0 || (h.w == 0.0 && side < 0.0)) continue;
            vec3 p[4];
            if (side > 0.0) p = vec3[4](a, a + e, a + b + e, a + b);
            else p = vec3[4](a, a + b, a + b + e, a + e);
            for (int k = 0; k < 4; ++k) p[k] -= P;
            specula_material(specula_polygon_query(wo, p, 4, spc_counts.y), s, c);
            if (!c.partial) {
                spc_preview_add(c, value);
                continue;
            }
            vec3 ctr = (p[0] + p[1] + p[2] + p[3]) * 0.25;
            float dist = length(ctr);
            vec3 wi = ctr / dist;
            vec3 nl = cross(b, e);
            float area = length(nl);
            float solid_angle = area * abs(dot(wi, nl / area)) / (dist * dist);
            if (dot(wi, s.geometric_normal) <= 0.0) continue;
            specula_material(specula_direction_query(wo, wi, inf), s, c);
            spc_preview_add(c, value * solid_angle);
        } else {  // environment: its mean radiance over the hemisphere of the shading normal
            vec3 tt, bb, nn;
            spc_frame(s.normal, s.tangent.xyz, tt, bb, nn);
            const float lift = SPC_PREVIEW_HEMISPHERE_LIFT;
            vec3 p[4] = vec3[4](normalize(tt + lift * nn), normalize(bb + lift * nn), normalize(-tt + lift * nn),
                                normalize(-bb + lift * nn));
            specula_material(specula_polygon_query(wo, p, 4, spc_counts.y), s, c);
            if (!c.partial) {
                spc_preview_add(c, value);
            } else {
                specula_material(specula_direction_query(wo, nn, inf), s, c);
                spc_preview_add(c, value * 3.14159265358979);
            }
        }
    }
    o_beauty = vec4(emission + spc_preview_diffuse + spc_preview_specular, 1.0);
    o_diffuse = vec4(spc_preview_diffuse, 1.0);
    o_specular = vec4(spc_preview_specular, 1.0);
    o_normal = vec4(s.normal, 1.0);
    o_aux = vec4(dot(P - spc_eye.xyz, spc_forward.xyz), v_uv, 1.0);
}
)";

// Quad-light geometry: its radiance towards the viewer on the emitting side (QuadLight::radiance), no scattering.
const std::string kEmitterFragment = std::string("#version 450 core\n") + kFrameBlockGlsl + R"(
layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec4 v_tangent;
layout(location = 3) in vec2 v_uv;
layout(location = 0) out vec4 o_beauty;
layout(location = 1) out vec4 o_diffuse;
layout(location = 2) out vec4 o_specular;
layout(location = 3) out vec4 o_normal;
layout(location = 4) out vec4 o_aux;
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
    gl_Position = vec4(p, 1.0, 1.0);
}
)";
const std::string kBackgroundFragment = std::string("#version 450 core\n") + R"(
layout(location = 0) in vec2 v_ndc;
layout(location = 0) out vec4 o_beauty;
layout(location = 1) out vec4 o_diffuse;
layout(location = 2) out vec4 o_specular;
layout(location = 3) out vec4 o_normal;
layout(location = 4) out vec4 o_aux;
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
void viewProjection(const PerspectiveCamera& cam, float zNear, float zFar, float* out) {
    const Vec3 f = cam.forward(), r = cam.right(), u = cam.up(), e = cam.position();
    const float sx = 1.f / cam.halfWidth(), sy = 1.f / cam.halfHeight();
    const float A = (zFar + zNear) / (zFar - zNear), B = -2.f * zFar * zNear / (zFar - zNear);
    // Rows of clip = M (p - e): x = sx r·d, y = sy u·d, z = A f·d + B, w = f·d.
    const Vec3 rows[4] = {r * sx, u * sy, f * A, f};
    const float add[4] = {0.f, 0.f, B, 0.f};
    for (int i = 0; i < 4; ++i) {
        // column-major: out[col * 4 + row]
        out[0 * 4 + i] = rows[i].x;
        out[1 * 4 + i] = rows[i].y;
        out[2 * 4 + i] = rows[i].z;
        out[3 * 4 + i] = -glm::dot(rows[i], e) + add[i];
    }
}

void packLight(const RasterLight& r, float (*dst)[4]) {
    dst[0][0] = float(int(r.kind));
    dst[0][1] = r.cosOuter;
    dst[0][2] = r.cosInner;
    dst[0][3] = r.twoSided ? 1.f : 0.f;
    const Vec3 vs[3] = {r.position, r.direction, r.edgeV};
    for (int k = 0; k < 3; ++k) dst[1 + k][0] = vs[k].x, dst[1 + k][1] = vs[k].y, dst[1 + k][2] = vs[k].z, dst[1 + k][3] = 0.f;
    dst[4][0] = r.value.x, dst[4][1] = r.value.y, dst[4][2] = r.value.z, dst[4][3] = 0.f;
}

std::string glslDefines() {
    char buf[128];
    std::snprintf(buf, sizeof buf, "#define SPC_PREVIEW_HEMISPHERE_LIFT %.9g\n", double(kRasterHemisphereLift));
    return buf;
}

}  // namespace

PreviewOutput renderPreview(const Scene& scene, const nlohmann::json& materials, const std::string& baseDir,
                            const PreviewOptions& options) {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    std::string why;
    if (!gl::context(&why)) throw IoError("no OpenGL 4.5 context for the preview: " + why);
    PreviewOutput result;
    result.renderer = gl::renderer();
    const RenderSettings& rs = scene.render;
    const int W = rs.width, H = rs.height;
    PerspectiveCamera camera(scene.camera, W, H);

    // Near and far planes from the scene's extent along the view axis.
    float zFar = 1e-3f;
    for (const ShapeInstance& sh : scene.shapes)
        for (const Vec3& p : sh.mesh.positions) zFar = std::max(zFar, glm::dot(p - camera.position(), camera.forward()));
    zFar *= 1.01f;
    const float zNear = std::max(zFar * 1e-5f, 1e-5f);

    // Frame block: camera and lights.
    FrameBlock frame{};
    viewProjection(camera, zNear, zFar, frame.viewProj);
    frame.eye[0] = camera.position().x, frame.eye[1] = camera.position().y, frame.eye[2] = camera.position().z;
    frame.forward[0] = camera.forward().x, frame.forward[1] = camera.forward().y, frame.forward[2] = camera.forward().z;
    Color3 background(0.f);
    const RasterLight* map = nullptr;
    std::vector<RasterLight> rasterLights;
    for (const auto& light : scene.lights) rasterLights.push_back(light->raster());
    int count = 0;
    for (const RasterLight& r : rasterLights) {
        if (r.kind == RasterLight::Kind::Environment) {
            if (r.hasMap) {
                if (map) throw InputError("/lights", "the preview shows one environment map (the scene has several)");
                map = &r;
            } else {
                background += r.value;
            }
        }
        if (count == kMaxLights) throw InputError("/lights", "the preview takes at most 64 lights");
        packLight(r, &frame.lights[count * kLightVec4s]);
        ++count;
    }
    frame.counts[0] = count;
    frame.counts[1] = rs.ltcHorizon;
    GLuint frameBuffer;
    glGenBuffers(1, &frameBuffer);
    glBindBuffer(GL_UNIFORM_BUFFER, frameBuffer);
    glBufferData(GL_UNIFORM_BUFFER, sizeof frame, &frame, GL_STATIC_DRAW);

    // One program per material: its module (uniform block at binding 0, resources at 1, 2, ...) plus the light loop.
    struct MaterialGpu {
        GLuint program = 0;
        std::unique_ptr<gl::ManifestBindings> bindings;
    };
    std::vector<MaterialGpu> mats(scene.materials.size());
    for (size_t m = 0; m < scene.materials.size(); ++m) {
        const std::string& name = scene.materials[m]->name();
        const std::string pointer = "/materials/" + pointerEscape(name);
        if (!materials.contains(name)) throw InputError(pointer, "material '" + name + "' is not in the document");
        graph::GraphDesc g = graph::parseGraph(materials.at(name), pointer);
        codegen::GlslModule mod = codegen::emitGlsl(g, {});
        for (const std::string& w : mod.warnings) result.warnings.push_back("material '" + name + "': " + w);
        std::vector<graph::ResourceImage> images =
            codegen::exportGlslResources(g, mod, GraphLoadContext{scene.textures.get(), baseDir});
        std::string source = mod.source;
        // The module starts with its #version line; the defines and the main go after the whole module.
        std::string log;
        mats[m].program = gl::program(kVertex, source + glslDefines() + kSurfaceMain, &log);
        if (!mats[m].program) throw InputError(pointer, "the preview shader of material '" + name + "' does not compile: " + log);
        mats[m].bindings = std::make_unique<gl::ManifestBindings>();
        mats[m].bindings->add(codegen::glslManifest(mod, images, {}), images);
    }
    std::string log;
    GLuint emitterProgram = gl::program(kVertex, kEmitterFragment, &log);
    GLuint backgroundProgram = emitterProgram ? gl::program(kBackgroundVertex, kBackgroundFragment, &log) : 0;
    if (!backgroundProgram) throw IoError("the preview's own shaders do not compile: " + log);
    GLuint mapTexture = 0;
    if (map) {
        std::vector<float> rgba(size_t(map->mapWidth) * map->mapHeight * 4, 1.f);
        for (int y = 0; y < map->mapHeight; ++y)  // GL row 0 is the bottom row
            for (int x = 0; x < map->mapWidth; ++x)
                for (int c = 0; c < 3; ++c)
                    rgba[(size_t(map->mapHeight - 1 - y) * map->mapWidth + x) * 4 + c] =
                        map->map[(size_t(y) * map->mapWidth + x) * 3 + c];
        glGenTextures(1, &mapTexture);
        glBindTexture(GL_TEXTURE_2D, mapTexture);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, map->mapWidth, map->mapHeight, 0, GL_RGBA, GL_FLOAT, rgba.data());
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }

    std::vector<GpuMesh> meshes;
    for (const ShapeInstance& sh : scene.shapes) meshes.push_back(uploadMesh(sh.mesh));

    // Render target: five RGBA32F attachments and a float depth buffer.
    GLuint fbo, depth, colour[kAovCount];
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glGenTextures(kAovCount, colour);
    GLenum drawBuffers[kAovCount];
    for (int i = 0; i < kAovCount; ++i) {
        glBindTexture(GL_TEXTURE_2D, colour[i]);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, W, H, 0, GL_RGBA, GL_FLOAT, nullptr);
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
    result.setupSeconds = std::chrono::duration<double>(Clock::now() - t0).count();

    GLuint query;
    glGenQueries(1, &query);
    double gpuNs = 0.0, wallNs = 0.0;
    const int frames = std::max(1, options.frames);
    glFinish();
    auto frameStart = Clock::now();
    for (int f = 0; f < frames; ++f) {
        glBeginQuery(GL_TIME_ELAPSED, query);
        glViewport(0, 0, W, H);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDisable(GL_CULL_FACE);
        glClearDepth(1.0);
        glClear(GL_DEPTH_BUFFER_BIT);
        glBindBufferBase(GL_UNIFORM_BUFFER, 1, frameBuffer);
        for (size_t i = 0; i < scene.shapes.size(); ++i) {
            const ShapeInstance& sh = scene.shapes[i];
            if (sh.areaLight >= 0) {
                const RasterLight& r = rasterLights[size_t(sh.areaLight)];
                glUseProgram(emitterProgram);
                glUniform4f(0, r.value.x, r.value.y, r.value.z, r.twoSided ? 1.f : 0.f);
                Vec3 n = glm::normalize(glm::cross(r.direction, r.edgeV));
                glUniform3f(1, n.x, n.y, n.z);
            } else {
                glUseProgram(mats[size_t(sh.material)].program);
                mats[size_t(sh.material)].bindings->bind();
                glBindBufferBase(GL_UNIFORM_BUFFER, 1, frameBuffer);
            }
            glBindVertexArray(meshes[i].vao);
            glDrawElements(GL_TRIANGLES, meshes[i].indexCount, GL_UNSIGNED_INT, nullptr);
        }
        // Background where no surface is: depth 1 passes GL_LEQUAL only where the depth buffer is still clear.
        glDepthFunc(GL_LEQUAL);
        glUseProgram(backgroundProgram);
        const Vec3 fw = camera.forward(), rt = camera.right() * camera.halfWidth(), up = camera.up() * camera.halfHeight();
        glUniform3f(0, fw.x, fw.y, fw.z);
        glUniform3f(1, rt.x, rt.y, rt.z);
        glUniform3f(2, up.x, up.y, up.z);
        glUniform3f(3, background.x, background.y, background.z);
        glUniform4f(4, map ? map->mapScale.x : 0.f, map ? map->mapScale.y : 0.f, map ? map->mapScale.z : 0.f,
                    map ? map->mapRotation : 0.f);
        glUniform2i(5, map ? map->mapWidth : 0, map ? map->mapHeight : 0);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, mapTexture);
        glBindVertexArray(meshes.empty() ? 0 : meshes[0].vao);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glEndQuery(GL_TIME_ELAPSED);
        GLuint64 ns = 0;
        glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
        gpuNs += double(ns);
        glFinish();
        const auto now = Clock::now();
        wallNs += std::chrono::duration<double, std::nano>(now - frameStart).count();
        frameStart = now;
    }
    result.gpuMsPerFrame = gpuNs / frames * 1e-6;
    result.wallMsPerFrame = wallNs / frames * 1e-6;

    // Read back into the renderer's AOV layout (rows top first).
    ImageSet& img = result.output.images;
    img.width = W;
    img.height = H;
    std::vector<float> px(size_t(W) * H * 4);
    auto readAttachment = [&](int i) {
        glReadBuffer(GLenum(GL_COLOR_ATTACHMENT0 + i));
        glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px.data());
    };
    auto addAov = [&](const char* name, std::vector<std::string> channels, int attachment, int firstChannel) {
        readAttachment(attachment);
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
    img.metadata["specula:renderer"] = "preview (" + result.renderer + ")";
    img.metadata["specula:spp"] = "1";
    img.metadata["specula:version"] = SPECULA_VERSION;
    result.output.stats.samples = uint64_t(W) * H;
    result.output.stats.tilesDone = result.output.stats.tilesTotal = 1;
    result.output.stats.seconds = std::chrono::duration<double>(Clock::now() - t0).count();

    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteQueries(1, &query);
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(kAovCount, colour);
    glDeleteRenderbuffers(1, &depth);
    glDeleteBuffers(1, &frameBuffer);
    if (mapTexture) glDeleteTextures(1, &mapTexture);
    for (GpuMesh& m : meshes) {
        glDeleteBuffers(1, &m.vbo);
        glDeleteBuffers(1, &m.ebo);
        glDeleteVertexArrays(1, &m.vao);
    }
    for (MaterialGpu& m : mats) glDeleteProgram(m.program);
    glDeleteProgram(emitterProgram);
    glDeleteProgram(backgroundProgram);
    return result;
}

}  // namespace specula::preview
