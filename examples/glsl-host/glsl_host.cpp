// How a game engine uses one generated GLSL module (docs/glsl.md): it loads the module and its manifest as cooked by
// `specula glsl --resources`, binds the uniform block and textures from the manifest alone, and lights it itself.
//
//   specula glsl scene.json -o cooked/module.glsl --resources cooked     # the asset pipeline (once per material)
//   glsl_host_example cooked/module.glsl cooked/manifest.json -o host.exr [--size WxH] [--set NAME=V[,V,V]]
//
// Nothing here links libspecula: the program needs GL 4.5, EGL (only because it has no window), OpenImageIO (EXR
// in and out) and a JSON parser. Its camera, sphere and lights are the engine's own; examples/glsl-host/scene.json
// describes the same picture for `specula render --integrator raster`, and the ctest glsl_host compares the two.
#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

// ---- 1. A GL 4.5 core context. An engine already has one; a headless program makes it through EGL: Mesa's
// surfaceless platform (llvmpipe in CI), else the first EGL device (NVIDIA's driver). No surface: we draw into an FBO.
bool makeCurrent(EGLDisplay dpy) {
    const EGLint cfgAttrs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    const EGLint ctxAttrs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                               EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLConfig cfg;
    EGLint n = 0;
    if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, nullptr, nullptr) || !eglBindAPI(EGL_OPENGL_API) ||
        !eglChooseConfig(dpy, cfgAttrs, &cfg, 1, &n) || n < 1)
        return false;
    EGLContext ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctxAttrs);
    return ctx != EGL_NO_CONTEXT && eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx);
}

void headlessContext() {
    auto display = (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
    auto devices = (PFNEGLQUERYDEVICESEXTPROC)eglGetProcAddress("eglQueryDevicesEXT");
    if (display && makeCurrent(display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr))) return;
    EGLDeviceEXT dev[8];
    EGLint count = 0;
    if (display && devices && devices(8, dev, &count))
        for (EGLint i = 0; i < count; ++i)
            if (makeCurrent(display(EGL_PLATFORM_DEVICE_EXT, dev[i], nullptr))) return;
    fail("no OpenGL 4.5 core context through EGL");
}

std::string readText(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) fail("cannot read '" + path + "'");
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

// Fails with the info log unless a shader or program reached 'status'.
void check(GLuint obj, GLenum status, void (*getiv)(GLuint, GLenum, GLint*),
           void (*infoLog)(GLuint, GLsizei, GLsizei*, GLchar*), const char* what) {
    GLint ok = 0;
    getiv(obj, status, &ok);
    if (ok) return;
    char log[8192];
    infoLog(obj, sizeof log, nullptr, log);
    fail(std::string(what) + log);
}

GLuint compile(GLenum type, const std::string& src) {
    GLuint s = glCreateShader(type);
    const char* c = src.c_str();
    glShaderSource(s, 1, &c, nullptr);
    glCompileShader(s);
    check(s, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog, "shader does not compile: ");
    return s;
}

GLuint link(const std::string& vertex, const std::string& fragment) {
    GLuint p = glCreateProgram();
    glAttachShader(p, compile(GL_VERTEX_SHADER, vertex));
    glAttachShader(p, compile(GL_FRAGMENT_SHADER, fragment));
    glLinkProgram(p);
    check(p, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog, "program does not link: ");
    return p;
}

// ---- 2. The host's shaders. The engine's per-frame block sits at a uniform-buffer binding the manifest does not
// use (HOST_FRAME_BINDING, defined from the manifest below); its lights are in the engine's units.
const char* kFrameBlock = R"(
layout(std140, binding = HOST_FRAME_BINDING) uniform HostFrame {
    mat4 view_proj;
    vec4 eye;
    vec4 point_position, point_intensity;    // W/sr
    vec4 sun_to_light, sun_irradiance;       // unit vector towards the sun; W/m² on a surface facing it
    vec4 quad_corner, quad_edge_u, quad_edge_v, quad_radiance;  // W/(m²·sr), one-sided: emits along cross(u, v)
};
)";

const char* kVertex = R"(
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_tangent;  // xyz, w = bitangent sign
layout(location = 3) in vec2 a_uv;
layout(location = 0) out Varyings { vec3 v_position; vec3 v_normal; vec4 v_tangent; vec2 v_uv; };
void main() {
    v_position = a_position;  // world space: the sphere has no transform
    v_normal = a_normal;
    v_tangent = a_tangent;
    v_uv = a_uv;
    gl_Position = view_proj * vec4(a_position, 1.0);
}
)";

// The host's fragment main, appended after the module. HOST_MATERIAL is the manifest's entry point "material"
// (specula_material, or specula_<prefix>_material for a prefixed module). Every specula_material call below is made
// in uniform control flow, and lights that do not reach the point are zeroed *after* the call: nodes may take
// dFdxFine/dFdyFine of their own values (bsdf.ggx_filtered with derivatives "quad"), which needs the whole 2x2 quad.
const char* kFragmentMain = R"(
layout(location = 0) in Varyings { vec3 v_position; vec3 v_normal; vec4 v_tangent; vec2 v_uv; };  // one block
layout(location = 0) out vec4 o_color;

void main() {
    const float inf = 1.0 / 0.0;
    vec3 P = v_position;
    vec3 wo = normalize(eye.xyz - P);
    // The flat triangle normal, facing the viewer (the CPU renderer shades both sides alike).
    vec3 Ng = normalize(cross(dFdx(P), dFdy(P)));
    if (dot(Ng, wo) < 0.0) Ng = -Ng;
    vec3 N = normalize(gl_FrontFacing ? v_normal : -v_normal);
    // The derivatives: specula_shading_inputs differences P, uv, N and wo over the 2x2 pixel quad (dFdxFine,
    // dFdyFine) into s.dPdx/dPdy, s.duvdx/duvdy, s.dNdx/dNdy, s.dwodx/dwody. Texture nodes filter with s.duvdx/duvdy
    // (anisotropic probes at an explicit LOD), normal maps turn them into dN/dx, dN/dy, filtered GGX widens its lobe with them.
    SpeculaShadingInputs s = specula_shading_inputs(P, N, Ng, v_tangent, v_uv, wo);

    SpeculaClosure c;
    HOST_MATERIAL(specula_direction_query(wo, wo, inf), s, c);
    vec3 L = c.emission;

    // Point light: one direction query; light_distance lets filtered lobes differentiate wi along the surface.
    vec3 d = point_position.xyz - P;
    float dist = length(d);
    vec3 wi = d / dist;
    HOST_MATERIAL(specula_direction_query(wo, wi, dist), s, c);
    if (dot(wi, s.geometric_normal) > 0.0) L += c.f * point_intensity.rgb / (dist * dist);

    // Directional light: a direction query at infinite distance.
    HOST_MATERIAL(specula_direction_query(wo, sun_to_light.xyz, inf), s, c);
    if (dot(sun_to_light.xyz, s.geometric_normal) > 0.0) L += c.f * sun_irradiance.rgb;

    // Quad light: a polygon query, the vertices as offsets from P, counter-clockwise seen from P. A point behind the
    // one-sided light asks for an empty polygon (count 0), so that the call stays in uniform control flow.
    vec3 a = quad_corner.xyz - P, u = quad_edge_u.xyz, v = quad_edge_v.xyz;
    bool front = dot(-a, cross(u, v)) > 0.0;
    HOST_MATERIAL(specula_polygon_query(wo, a, a + v, a + u + v, a + u, front ? 4 : 0, SPC_HORIZON_CLIP), s, c);
    if (!c.partial) {
        L += c.f * quad_radiance.rgb;  // every lobe has a closed form (LTC): the unshadowed integral
    } else {
        // Some lobe (glints) has no closed form: a real engine samples the light; like specula preview, we ask one
        // direction query towards the centre, times the solid angle of the quad.
        vec3 ctr = a + 0.5 * (u + v);
        float r = length(ctr);
        vec3 w = ctr / r, n = cross(u, v);
        HOST_MATERIAL(specula_direction_query(wo, w, inf), s, c);
        float solid_angle = abs(dot(w, n)) / (r * r);  // |n| = area
        if (front && dot(w, s.geometric_normal) > 0.0) L += c.f * quad_radiance.rgb * solid_angle;
    }
    o_color = vec4(L, 1.0);
}
)";

// ---- 3. The material's uniform block: a buffer of uniform_block.size bytes, each member's value at its std140
// offset. --set NAME=V[,V,V] changes a member by name, as an engine's material editor would.
GLuint uniformBlock(const json& block, const std::vector<std::pair<std::string, std::vector<float>>>& overrides) {
    std::vector<char> bytes(std::max<size_t>(block.at("size").get<size_t>(), 16), 0);
    auto put = [&](const json& member, const std::vector<float>& v) {
        const size_t off = member.at("offset").get<size_t>(), width = member.at("value").size();
        if (v.size() != width) fail("member '" + member.at("name").get<std::string>() + "' takes " + std::to_string(width) + " values");
        std::memcpy(&bytes[off], v.data(), 4 * width);
    };
    for (const json& m : block.at("members")) put(m, m.at("value").get<std::vector<float>>());
    for (const auto& entry : overrides) {
        const std::string& name = entry.first;  // a named reference: C++17 lambdas cannot capture structured bindings
        const std::vector<float>& v = entry.second;
        auto it = std::find_if(block.at("members").begin(), block.at("members").end(),
                               [&](const json& m) { return m.at("name") == name; });
        if (it == block.at("members").end()) fail("the uniform block has no member '" + name + "'");
        put(*it, v);
    }
    GLuint buf;
    glGenBuffers(1, &buf);
    glBindBuffer(GL_UNIFORM_BUFFER, buf);
    glBufferData(GL_UNIFORM_BUFFER, GLsizeiptr(bytes.size()), bytes.data(), GL_STATIC_DRAW);
    return buf;
}

// ---- 4. One resource: a texture of the target its GLSL type names, every level read from its EXR (RGBA float, the
// EXR's bottom row is GL row 0; a 2D array stacks its layers from the bottom up), with the listed sampler state.
GLenum glEnum(const std::string& s) {
    static const std::pair<const char*, GLenum> names[] = {
        {"nearest", GL_NEAREST}, {"linear", GL_LINEAR}, {"nearest_mipmap_nearest", GL_NEAREST_MIPMAP_NEAREST},
        {"linear_mipmap_nearest", GL_LINEAR_MIPMAP_NEAREST}, {"nearest_mipmap_linear", GL_NEAREST_MIPMAP_LINEAR},
        {"linear_mipmap_linear", GL_LINEAR_MIPMAP_LINEAR}, {"repeat", GL_REPEAT}, {"mirrored_repeat", GL_MIRRORED_REPEAT},
        {"clamp_to_edge", GL_CLAMP_TO_EDGE}};
    for (const auto& [name, e] : names)
        if (s == name) return e;
    fail("unknown sampler state '" + s + "'");
}

std::vector<float> readRgbaBottomUp(const std::string& path, int width, int height) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) fail("cannot read '" + path + "': " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width != width || spec.height != height || spec.nchannels != 4)
        fail("'" + path + "' is not the " + std::to_string(width) + "x" + std::to_string(height) + " RGBA image the manifest lists");
    std::vector<float> top(size_t(width) * height * 4), rgba(top.size());
    if (!in->read_image(0, 0, 0, 4, OIIO::TypeDesc::FLOAT, top.data())) fail("cannot read '" + path + "': " + in->geterror());
    for (int y = 0; y < height; ++y)
        std::copy_n(&top[size_t(height - 1 - y) * width * 4], size_t(width) * 4, &rgba[size_t(y) * width * 4]);
    return rgba;
}

struct Texture {
    GLuint name = 0;
    GLenum target = 0;
    int unit = 0;
};

Texture resourceTexture(const json& r, const fs::path& dir) {
    if (r.at("format") != "RGBA32F") fail("resource '" + r.at("name").get<std::string>() + "': unknown format");
    const std::string type = r.at("glsl_type");
    Texture t;
    t.unit = r.at("binding");
    t.target = type == "sampler1DArray" ? GL_TEXTURE_1D_ARRAY : type == "sampler2DArray" ? GL_TEXTURE_2D_ARRAY : GL_TEXTURE_2D;
    glGenTextures(1, &t.name);
    glBindTexture(t.target, t.name);
    const json& levels = r.at("levels");
    for (size_t l = 0; l < levels.size(); ++l) {
        const int w = levels[l].at("width"), h = levels[l].at("height"), layers = levels[l].value("layers", 1);
        std::vector<float> px = readRgbaBottomUp((dir / levels[l].at("exr").get<std::string>()).string(), w, h * layers);
        if (t.target == GL_TEXTURE_2D_ARRAY)
            glTexImage3D(t.target, GLint(l), GL_RGBA32F, w, h, layers, 0, GL_RGBA, GL_FLOAT, px.data());
        else  // GL_TEXTURE_2D, or GL_TEXTURE_1D_ARRAY whose rows are its layers
            glTexImage2D(t.target, GLint(l), GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, px.data());
    }
    if (r.at("generate_mipmaps").get<bool>()) {
        glGenerateMipmap(t.target);  // a resource that lists level 0 only asks the host for the chain
    } else {
        glTexParameteri(t.target, GL_TEXTURE_BASE_LEVEL, 0);
        glTexParameteri(t.target, GL_TEXTURE_MAX_LEVEL, GLint(levels.size()) - 1);
    }
    glTexParameteri(t.target, GL_TEXTURE_MIN_FILTER, GLint(glEnum(r.at("min_filter"))));
    glTexParameteri(t.target, GL_TEXTURE_MAG_FILTER, GLint(glEnum(r.at("mag_filter"))));
    glTexParameteri(t.target, GL_TEXTURE_WRAP_S, GLint(glEnum(r.at("wrap_s"))));
    if (t.target != GL_TEXTURE_1D_ARRAY) glTexParameteri(t.target, GL_TEXTURE_WRAP_T, GLint(glEnum(r.at("wrap_t"))));
    return t;
}

// ---- 5. The engine's scene: the same as scene.json ----------------------------------------------------------
struct Vec3 {
    float x, y, z;
};
Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
Vec3 normalize(Vec3 a) { return a * (1.f / std::sqrt(dot(a, a))); }

const Vec3 kEye{0, -4, 1}, kLookAt{0, 0, 0}, kUp{0, 0, 1};
const float kFovYDegrees = 36.f;
const Vec3 kPointPosition{2.5f, -3, 3}, kPointIntensity{40, 40, 40};  // W/sr
const Vec3 kSunTravels{1, 0.5f, -0.6f}, kSunIrradiance{2 * 0.8f, 2 * 0.9f, 2 * 1.0f};  // W/m²
const Vec3 kQuadCentre{-1.5f, 1.5f, 3}, kQuadFaces{0, 0, 0};  // a 2 x 1 rectangle facing the origin
const float kQuadSize[2] = {2, 1}, kQuadRadiance = 6;  // W/(m²·sr)

// std140 image of HostFrame.
struct FrameBlock {
    float viewProj[16];
    float eye[4], pointPosition[4], pointIntensity[4], sunToLight[4], sunIrradiance[4];
    float quadCorner[4], quadEdgeU[4], quadEdgeV[4], quadRadiance[4];
};
void put(float* dst, Vec3 v) { dst[0] = v.x, dst[1] = v.y, dst[2] = v.z, dst[3] = 0.f; }

// A pinhole camera: clip = P·V as glm::perspective·glm::lookAt would build it, column-major. Frame pixel (x, y) from
// the top left is GL window pixel (x, H-1-y), and its centre lies on the CPU renderer's ray through that pixel.
void viewProjection(int W, int H, float zNear, float zFar, float* m) {
    const Vec3 f = normalize(kLookAt - kEye), r = normalize(cross(f, kUp)), u = cross(r, f);
    const float sy = 1.f / std::tan(0.5f * kFovYDegrees * 3.14159265f / 180.f), sx = sy * float(H) / float(W);
    const float A = (zFar + zNear) / (zFar - zNear), B = -2.f * zFar * zNear / (zFar - zNear);
    const Vec3 rows[4] = {r * sx, u * sy, f * A, f};
    const float add[4] = {0.f, 0.f, B, 0.f};
    for (int i = 0; i < 4; ++i) {
        m[0 * 4 + i] = rows[i].x, m[1 * 4 + i] = rows[i].y, m[2 * 4 + i] = rows[i].z;
        m[3 * 4 + i] = -dot(rows[i], kEye) + add[i];
    }
}

FrameBlock frameBlock(int W, int H) {
    FrameBlock b{};
    viewProjection(W, H, 0.01f, 100.f, b.viewProj);
    put(b.eye, kEye);
    put(b.pointPosition, kPointPosition);
    put(b.pointIntensity, kPointIntensity);
    put(b.sunToLight, normalize(kSunTravels) * -1.f);
    put(b.sunIrradiance, kSunIrradiance);
    // The rectangle's corner and edges, oriented as Specula's quad light: edge u along cross(up, n), v = n x u.
    const Vec3 n = normalize(kQuadFaces - kQuadCentre), eu = normalize(cross(kUp, n)) * kQuadSize[0];
    const Vec3 ev = cross(n, normalize(eu)) * kQuadSize[1];
    put(b.quadCorner, kQuadCentre - eu * 0.5f - ev * 0.5f);
    put(b.quadEdgeU, eu);
    put(b.quadEdgeV, ev);
    put(b.quadRadiance, Vec3{kQuadRadiance, kQuadRadiance, kQuadRadiance});
    return b;
}

// A unit sphere tessellated like Specula's built-in sphere (core/geometry/shapes.cpp, 128 segments): a uv grid of
// nu x nu/2 cells, u = φ/2π, v = θ/π from +z, the two pole rows collapsed to one vertex per cell at its mid-u, the
// tangent along dp/du with its bitangent sign, triangles counter-clockwise seen from outside.
struct Mesh {
    std::vector<float> vertices;  // position 3, normal 3, tangent 4, uv 2
    std::vector<unsigned> indices;
};
Mesh sphere(int nu) {
    const int nv = nu / 2;
    const double pi = 3.14159265358979323846;
    Mesh m;
    auto vertex = [&](double u, double v) {
        const double sp = std::sin(2 * pi * u), cp = std::cos(2 * pi * u), st = std::sin(pi * v), ct = std::cos(pi * v);
        const double stc = std::max(st, 1e-5);  // dp/du keeps its direction at the poles
        const Vec3 n{float(st * cp), float(st * sp), float(ct)};
        const Vec3 t = normalize(Vec3{float(-stc * sp), float(stc * cp), 0.f});
        const Vec3 dpdv{float(ct * cp), float(ct * sp), float(-st)};
        const float w = dot(cross(n, t), dpdv) < 0.f ? -1.f : 1.f;
        const float attrs[12] = {n.x, n.y, n.z, n.x, n.y, n.z, t.x, t.y, t.z, w, float(u), float(v)};
        m.vertices.insert(m.vertices.end(), attrs, attrs + 12);
        return unsigned(m.vertices.size() / 12 - 1);
    };
    std::vector<std::vector<unsigned>> rows(size_t(nv) + 1);
    for (int j = 0; j <= nv; ++j) {
        const bool pole = j == 0 || j == nv;
        for (int i = 0; i < (pole ? nu : nu + 1); ++i) rows[j].push_back(vertex(pole ? (i + 0.5) / nu : double(i) / nu, double(j) / nv));
    }
    auto tri = [&](unsigned a, unsigned b, unsigned c) { m.indices.insert(m.indices.end(), {a, b, c}); };
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            if (j == 0) {
                tri(rows[0][i], rows[1][i], rows[1][i + 1]);
            } else if (j == nv - 1) {
                tri(rows[j][i], rows[j + 1][i], rows[j][i + 1]);
            } else {
                const unsigned a = rows[j][i], b = rows[j][i + 1], c = rows[j + 1][i + 1], d = rows[j + 1][i];
                tri(a, c, b);
                tri(a, d, c);
            }
        }
    return m;
}

void writeImages(const std::string& exrPath, int W, int H, const std::vector<float>& rgbTopDown) {
    auto write = [&](const std::string& path, OIIO::TypeDesc type, const void* data) {
        auto out = OIIO::ImageOutput::create(path);
        if (!out || !out->open(path, OIIO::ImageSpec(W, H, 3, type)) || !out->write_image(type, data) || !out->close())
            fail("cannot write '" + path + "': " + OIIO::geterror());
    };
    write(exrPath, OIIO::TypeDesc::FLOAT, rgbTopDown.data());
    // A PNG to look at: clamped and sRGB-encoded (no tone mapping; Specula's own PNG goes through an OCIO view).
    std::vector<unsigned char> png(rgbTopDown.size());
    for (size_t i = 0; i < png.size(); ++i) {
        const float c = std::clamp(rgbTopDown[i], 0.f, 1.f);
        const float e = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.f / 2.4f) - 0.055f;
        png[i] = (unsigned char)std::lround(e * 255.f);
    }
    write(fs::path(exrPath).replace_extension(".png").string(), OIIO::TypeDesc::UINT8, png.data());
}

int run(int argc, char** argv) {
    std::string modulePath, manifestPath, outPath = "glsl_host.exr";
    int W = 256, H = 192;
    std::vector<std::pair<std::string, std::vector<float>>> overrides;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "-o" && i + 1 < argc) {
            outPath = argv[++i];
        } else if (a == "--size" && i + 1 < argc) {
            if (std::sscanf(argv[++i], "%dx%d", &W, &H) != 2 || W < 1 || H < 1) fail("--size expects WxH");
        } else if (a == "--set" && i + 1 < argc) {  // NAME=V[,V,V]
            const std::string s = argv[++i];
            const size_t eq = s.find('=');
            if (eq == std::string::npos) fail("--set expects NAME=V[,V,V]");
            std::vector<float> v;
            std::stringstream list(s.substr(eq + 1));
            for (std::string item; std::getline(list, item, ',');) v.push_back(std::stof(item));
            overrides.emplace_back(s.substr(0, eq), v);
        } else if (modulePath.empty()) {
            modulePath = a;
        } else if (manifestPath.empty()) {
            manifestPath = a;
        } else {
            fail("usage: glsl_host_example MODULE.glsl MANIFEST.json [-o OUT.exr] [--size WxH] [--set NAME=V[,V,V]]");
        }
    }
    if (manifestPath.empty()) fail("usage: glsl_host_example MODULE.glsl MANIFEST.json [-o OUT.exr] [--size WxH] [--set NAME=V[,V,V]]");

    // The module and its manifest: format "specula-glsl-manifest", version 1 (docs/graph-format.md).
    const std::string module = readText(modulePath);
    const json manifest = json::parse(readText(manifestPath));
    if (manifest.value("format", "") != "specula-glsl-manifest" || manifest.value("version", 0) != 1)
        fail("'" + manifestPath + "' is not a version-1 Specula GLSL manifest");
    for (const json& w : manifest.value("warnings", json::array()))  // node types the GPU approximates
        std::fprintf(stderr, "glsl_host_example: warning: %s\n", w.get<std::string>().c_str());
    const json& block = manifest.at("uniform_block");
    const json& resources = manifest.at("resources");

    headlessContext();
    std::printf("renderer: %s\n", reinterpret_cast<const char*>(glGetString(GL_RENDERER)));

    // The program: the module first (it starts with its #version line), then the host's names, then the host's code.
    const int frameBinding = block.at("binding").get<int>() + 1;  // uniform-buffer bindings: the module uses one
    const std::string defines = "#define HOST_FRAME_BINDING " + std::to_string(frameBinding) + "\n#define HOST_MATERIAL " +
                                manifest.at("entry_points").at("material").get<std::string>() + "\n";
    const GLuint program =
        link("#version 450 core\n" + defines + kFrameBlock + kVertex, module + defines + kFrameBlock + kFragmentMain);

    // Uniform block and resources, from the manifest only.
    const GLuint params = block.at("size").get<int>() > 0 ? uniformBlock(block, overrides) : 0;
    std::vector<Texture> textures;
    for (const json& r : resources) textures.push_back(resourceTexture(r, fs::path(manifestPath).parent_path()));
    std::printf("manifest: uniform block of %d bytes (%zu members) at binding %d, %zu resources:",
                block.at("size").get<int>(), block.at("members").size(), block.at("binding").get<int>(), resources.size());
    for (const json& r : resources)
        std::printf(" %s(%s, binding %d)", r.at("name").get<std::string>().c_str(), r.at("kind").get<std::string>().c_str(),
                    r.at("binding").get<int>());
    std::printf("\n");

    // Geometry and the frame's constants.
    const Mesh mesh = sphere(128);
    GLuint vao, vbo, ebo, frame;
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(1, &vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(mesh.vertices.size() * 4), mesh.vertices.data(), GL_STATIC_DRAW);
    const GLint sizes[4] = {3, 3, 4, 2}, offsets[4] = {0, 3, 6, 10};
    for (GLuint a = 0; a < 4; ++a) {
        glEnableVertexAttribArray(a);
        glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, 48, reinterpret_cast<const void*>(size_t(offsets[a]) * 4));
    }
    glGenBuffers(1, &ebo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(mesh.indices.size() * 4), mesh.indices.data(), GL_STATIC_DRAW);
    const FrameBlock fb = frameBlock(W, H);
    glGenBuffers(1, &frame);
    glBindBuffer(GL_UNIFORM_BUFFER, frame);
    glBufferData(GL_UNIFORM_BUFFER, sizeof fb, &fb, GL_STATIC_DRAW);

    // A float colour target with depth (a window's back buffer in an engine).
    GLuint fbo, colour, depth;
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glGenTextures(1, &colour);
    glBindTexture(GL_TEXTURE_2D, colour);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, W, H, 0, GL_RGBA, GL_FLOAT, nullptr);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, colour, 0);
    glGenRenderbuffers(1, &depth);
    glBindRenderbuffer(GL_RENDERBUFFER, depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, W, H);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail("incomplete framebuffer");

    // Draw: bind what the manifest lists, the host's frame block, and the sphere.
    const auto t0 = std::chrono::steady_clock::now();
    glViewport(0, 0, W, H);
    glEnable(GL_DEPTH_TEST);
    glClearColor(0.f, 0.f, 0.f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glUseProgram(program);
    if (params) glBindBufferBase(GL_UNIFORM_BUFFER, block.at("binding").get<GLuint>(), params);
    for (const Texture& t : textures) {
        glActiveTexture(GLenum(GL_TEXTURE0 + t.unit));
        glBindTexture(t.target, t.name);
    }
    glBindBufferBase(GL_UNIFORM_BUFFER, GLuint(frameBinding), frame);
    glDrawElements(GL_TRIANGLES, GLsizei(mesh.indices.size()), GL_UNSIGNED_INT, nullptr);
    glFinish();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

    // Read back (GL row 0 is the bottom) and write the EXR and its PNG.
    std::vector<float> rgba(size_t(W) * H * 4), rgb(size_t(W) * H * 3);
    glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, rgba.data());
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 3; ++c) rgb[(size_t(y) * W + x) * 3 + c] = rgba[(size_t(H - 1 - y) * W + x) * 4 + c];
    writeImages(outPath, W, H, rgb);
    std::printf("drew %zu triangles at %dx%d in %.1f ms (first frame, shader compilation included); wrote %s\n",
                mesh.indices.size() / 3, W, H, ms, outPath.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "glsl_host_example: error: %s\n", e.what());
        return 1;
    }
}
