// Headless EGL context (Mesa surfaceless, else an EGL device), programs, and manifest-driven resource binding.
#define GL_GLEXT_PROTOTYPES 1
#include "plugin/preview/gl_util.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <cstring>

namespace specula::gl {

namespace {
bool gOk = false, gTried = false;
std::string gWhy;
unsigned gVao = 0;

// Whether a shader or program reached 'status'; if not, its info log into *log and the object deleted.
bool succeeded(GLuint obj, GLenum status, void (*getiv)(GLuint, GLenum, GLint*),
               void (*infoLog)(GLuint, GLsizei, GLsizei*, GLchar*), void (*remove)(GLuint), std::string* log) {
    GLint ok = 0;
    getiv(obj, status, &ok);
    if (ok) return true;
    char buf[8192];
    infoLog(obj, sizeof buf, nullptr, buf);
    if (log) *log = buf;
    remove(obj);
    return false;
}

GLuint compileShader(GLenum type, const std::string& src, std::string* log) {
    GLuint s = glCreateShader(type);
    const char* c = src.c_str();
    glShaderSource(s, 1, &c, nullptr);
    glCompileShader(s);
    return succeeded(s, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog, glDeleteShader, log) ? s : 0;
}
}  // namespace

namespace {
// Makes a GL 4.5 core context current on 'dpy' (no surface); "" on success, else what failed.
std::string makeCurrent(EGLDisplay dpy, const char* platform) {
    EGLint major = 0, minor = 0;
    EGLConfig cfg;
    EGLint n = 0;
    const EGLint cfgAttrs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    const EGLint ctxAttrs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5, EGL_CONTEXT_OPENGL_PROFILE_MASK,
                               EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &major, &minor)) return std::string("eglInitialize (") + platform + ") failed";
    if (!eglBindAPI(EGL_OPENGL_API)) return "eglBindAPI failed";
    if (!eglChooseConfig(dpy, cfgAttrs, &cfg, 1, &n) || n < 1) return std::string("eglChooseConfig (") + platform + ") failed";
    EGLContext ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctxAttrs);
    if (ctx == EGL_NO_CONTEXT) return std::string("eglCreateContext (GL 4.5 core, ") + platform + ") failed";
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) return "eglMakeCurrent failed";
    return "";
}
}  // namespace

bool context(std::string* why) {
    if (!gTried) {
        gTried = true;
        auto getPlatformDisplay = (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
        // Mesa (llvmpipe in CI) offers the surfaceless platform; NVIDIA's driver offers EGL devices instead.
        gWhy = getPlatformDisplay
                   ? makeCurrent(getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr), "surfaceless")
                   : "eglGetPlatformDisplayEXT missing";
        auto queryDevices = (PFNEGLQUERYDEVICESEXTPROC)eglGetProcAddress("eglQueryDevicesEXT");
        if (!gWhy.empty() && getPlatformDisplay && queryDevices) {
            EGLDeviceEXT devices[8];
            EGLint count = 0;
            if (queryDevices(8, devices, &count))
                for (EGLint d = 0; d < count && !gWhy.empty(); ++d) {
                    std::string w = makeCurrent(getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[d], nullptr), "device");
                    gWhy = w.empty() ? "" : gWhy + "; " + w;
                }
        }
        if (gWhy.empty()) {
            glGenVertexArrays(1, &gVao);
            glBindVertexArray(gVao);
            gOk = true;
        }
    }
    if (why) *why = gWhy;
    return gOk;
}

std::string renderer() { return gOk ? reinterpret_cast<const char*>(glGetString(GL_RENDERER)) : ""; }

unsigned program(const std::string& vertex, const std::string& fragment, std::string* log) {
    GLuint v = compileShader(GL_VERTEX_SHADER, vertex, log);
    GLuint f = v ? compileShader(GL_FRAGMENT_SHADER, fragment, log) : 0;
    if (!f) {
        if (v) glDeleteShader(v);
        return 0;
    }
    GLuint p = glCreateProgram();
    glAttachShader(p, v);
    glAttachShader(p, f);
    glLinkProgram(p);
    glDeleteShader(v);
    glDeleteShader(f);
    return succeeded(p, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog, glDeleteProgram, log) ? p : 0;
}

namespace {
GLenum glFilter(const std::string& f) {
    if (f == "nearest") return GL_NEAREST;
    if (f == "linear") return GL_LINEAR;
    if (f == "nearest_mipmap_nearest") return GL_NEAREST_MIPMAP_NEAREST;
    if (f == "linear_mipmap_nearest") return GL_LINEAR_MIPMAP_NEAREST;
    if (f == "nearest_mipmap_linear") return GL_NEAREST_MIPMAP_LINEAR;
    return GL_LINEAR_MIPMAP_LINEAR;
}
GLenum glWrap(const std::string& w) {
    if (w == "clamp_to_edge") return GL_CLAMP_TO_EDGE;
    if (w == "mirrored_repeat") return GL_MIRRORED_REPEAT;
    return GL_REPEAT;
}
}  // namespace

Texture resourceTexture(const graph::ResourceImage& img, const std::string& glslType) {
    Texture t;
    t.target = glslType == "sampler1DArray" ? GL_TEXTURE_1D_ARRAY : glslType == "sampler2DArray" ? GL_TEXTURE_2D_ARRAY : GL_TEXTURE_2D;
    glGenTextures(1, &t.name);
    glBindTexture(t.target, t.name);
    for (size_t l = 0; l < img.levels.size(); ++l) {
        const graph::ResourceImage::Level& lv = img.levels[l];
        if (t.target == GL_TEXTURE_2D_ARRAY)
            glTexImage3D(t.target, GLint(l), GL_RGBA32F, lv.width, lv.height, lv.layers, 0, GL_RGBA, GL_FLOAT, lv.rgba.data());
        else
            glTexImage2D(t.target, GLint(l), GL_RGBA32F, lv.width, lv.height, 0, GL_RGBA, GL_FLOAT, lv.rgba.data());
    }
    if (img.generateMipmaps) {
        glGenerateMipmap(t.target);
    } else {
        glTexParameteri(t.target, GL_TEXTURE_BASE_LEVEL, 0);
        glTexParameteri(t.target, GL_TEXTURE_MAX_LEVEL, GLint(img.levels.size()) - 1);
    }
    glTexParameteri(t.target, GL_TEXTURE_MIN_FILTER, GLint(glFilter(img.minFilter)));
    glTexParameteri(t.target, GL_TEXTURE_MAG_FILTER, GLint(glFilter(img.magFilter)));
    glTexParameteri(t.target, GL_TEXTURE_WRAP_S, GLint(glWrap(img.wrapS)));
    if (t.target != GL_TEXTURE_1D_ARRAY) glTexParameteri(t.target, GL_TEXTURE_WRAP_T, GLint(glWrap(img.wrapT)));
    return t;
}

void ManifestBindings::add(const nlohmann::json& manifest, const std::vector<graph::ResourceImage>& images) {
    const nlohmann::json& ub = manifest["uniform_block"];
    std::vector<char> bytes(std::max<size_t>(ub["size"].get<size_t>(), 16), 0);
    for (const nlohmann::json& mem : ub["members"]) {
        const std::vector<float> v = mem["value"].get<std::vector<float>>();
        std::memcpy(&bytes[mem["offset"].get<size_t>()], v.data(), 4 * v.size());
    }
    GLuint buf;
    glGenBuffers(1, &buf);
    glBindBuffer(GL_UNIFORM_BUFFER, buf);
    glBufferData(GL_UNIFORM_BUFFER, GLsizeiptr(bytes.size()), bytes.data(), GL_STATIC_DRAW);
    buffers_.push_back(buf);
    bufferBindings_.push_back(ub["binding"].get<unsigned>());
    const nlohmann::json& res = manifest["resources"];
    for (size_t r = 0; r < res.size(); ++r) {
        textures_.push_back(resourceTexture(images[r], res[r]["glsl_type"].get<std::string>()));
        textureBindings_.push_back(res[r]["binding"].get<int>());
    }
}

void ManifestBindings::bind() const {
    for (size_t m = 0; m < buffers_.size(); ++m) glBindBufferBase(GL_UNIFORM_BUFFER, bufferBindings_[m], buffers_[m]);
    for (size_t t = 0; t < textures_.size(); ++t) {
        glActiveTexture(GLenum(GL_TEXTURE0 + textureBindings_[t]));
        glBindTexture(textures_[t].target, textures_[t].name);
    }
}

ManifestBindings::~ManifestBindings() {
    for (unsigned b : buffers_) glDeleteBuffers(1, &b);
    for (const Texture& t : textures_) glDeleteTextures(1, &t.name);
}

}  // namespace specula::gl
