// Headless EGL/GL helpers and glslangValidator driver for the GLSL drift-guard tests.
#define GL_GLEXT_PROTOTYPES 1
#include "glsl_harness.h"

#include "core/codegen/glsl_signature.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <unistd.h>

namespace specula::glsltest {

bool glslangCompile(const std::string& source, std::string* log) {
    char path[] = "/tmp/specula-glsl-XXXXXX";
    int fd = mkstemp(path);
    if (fd < 0) return false;
    close(fd);
    { std::ofstream(path) << source; }
    std::string cmd = std::string("\"") + SPECULA_GLSLANG + "\" -S frag \"" + path + "\" 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    std::array<char, 4096> buf;
    size_t n;
    while (p && (n = fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
    int rc = p ? pclose(p) : -1;
    unlink(path);
    if (log) *log = out;
    return rc == 0;
}

namespace {
bool gOk = false, gTried = false;
std::string gWhy;
unsigned gVao = 0;

GLuint compileShader(GLenum type, const std::string& src, std::string* log) {
    GLuint s = glCreateShader(type);
    const char* c = src.c_str();
    glShaderSource(s, 1, &c, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char buf[8192];
        glGetShaderInfoLog(s, sizeof buf, nullptr, buf);
        if (log) *log = buf;
        glDeleteShader(s);
        return 0;
    }
    return s;
}
}  // namespace

bool glContext(std::string* why) {
    if (!gTried) {
        gTried = true;
        auto getPlatformDisplay = (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
        EGLDisplay dpy = getPlatformDisplay ? getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr)
                                            : EGL_NO_DISPLAY;
        EGLint major = 0, minor = 0;
        EGLConfig cfg;
        EGLint n = 0;
        const EGLint cfgAttrs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        const EGLint ctxAttrs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5, EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                   EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
        if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &major, &minor))
            gWhy = "eglInitialize (surfaceless) failed";
        else if (!eglBindAPI(EGL_OPENGL_API))
            gWhy = "eglBindAPI failed";
        else if (!eglChooseConfig(dpy, cfgAttrs, &cfg, 1, &n) || n < 1)
            gWhy = "eglChooseConfig failed";
        else {
            EGLContext ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctxAttrs);
            if (ctx == EGL_NO_CONTEXT)
                gWhy = "eglCreateContext (GL 4.5 core) failed";
            else if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx))
                gWhy = "eglMakeCurrent failed";
            else {
                glGenVertexArrays(1, &gVao);
                glBindVertexArray(gVao);
                gOk = true;
            }
        }
    }
    if (why) *why = gWhy;
    return gOk;
}

std::string glRenderer() { return gOk ? reinterpret_cast<const char*>(glGetString(GL_RENDERER)) : ""; }

unsigned glProgram(const std::string& fragment, std::string* log) {
    static const std::string vs = R"(#version 450 core
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
})";
    GLuint v = compileShader(GL_VERTEX_SHADER, vs, log);
    GLuint f = v ? compileShader(GL_FRAGMENT_SHADER, fragment, log) : 0;
    if (!f) return 0;
    GLuint p = glCreateProgram();
    glAttachShader(p, v);
    glAttachShader(p, f);
    glLinkProgram(p);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char buf[8192];
        glGetProgramInfoLog(p, sizeof buf, nullptr, buf);
        if (log) *log = buf;
        glDeleteProgram(p);
        return 0;
    }
    return p;
}

unsigned glDataTexture(int w, int h, const std::vector<float>& rgba) {
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, rgba.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return t;
}

std::vector<float> glRun(unsigned program, int w, int h, const std::function<void()>& bind) {
    GLuint tex, fbo;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
    std::vector<float> px(size_t(w) * h * 4, -12345.f);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE) {
        glViewport(0, 0, w, h);
        glUseProgram(program);
        if (bind) bind();
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, px.data());
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(1, &tex);
    return px;
}

std::string nodeCall(const graph::NodeSpec& spec, const std::function<std::string(int)>& inputExpr,
                     const std::vector<std::string>& outVars, const std::vector<std::string>& resourceVars) {
    using codegen::GlslArgRole;
    return codegen::glslNodeCall(spec, [&](const GlslArgRole& r) -> std::string {
        switch (r.kind) {
            case GlslArgRole::Query: return "q";
            case GlslArgRole::Shading: return "s";
            case GlslArgRole::Input: return inputExpr(r.index);
            case GlslArgRole::Output: return outVars.at(size_t(r.index));
            case GlslArgRole::Resource: return resourceVars.at(size_t(r.index));
        }
        return "";
    });
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

GlTexture glResourceTexture(const graph::ResourceImage& img, const std::string& glslType) {
    GlTexture t;
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
        textures_.push_back(glResourceTexture(images[r], res[r]["glsl_type"].get<std::string>()));
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
    for (const GlTexture& t : textures_) glDeleteTextures(1, &t.name);
}

}  // namespace specula::glsltest
