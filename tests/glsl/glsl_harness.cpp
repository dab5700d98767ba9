// Headless EGL/GL helpers and glslangValidator driver for the GLSL drift-guard tests.
#define GL_GLEXT_PROTOTYPES 1
#include "glsl_harness.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <array>
#include <cstdio>
#include <cstdlib>
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
                     const std::vector<std::string>& outVars, const std::string& sampler) {
    using namespace graph;
    std::vector<std::string> args;
    if (spec.has(kGlslShading)) args.push_back("s");
    if (spec.has(kGlslDirections)) {
        args.push_back("wo");
        args.push_back("wi");
    }
    if (spec.has(kGlslTexture)) args.push_back(sampler);
    for (size_t k = 0; k < spec.inputs.size(); ++k) {
        const PortSpec& p = spec.inputs[k];
        if (p.type == TypeDesc::String && p.enumValues.empty()) continue;
        args.push_back(inputExpr(int(k)));
    }
    for (auto& o : outVars) args.push_back(o);
    std::string s = spec.glslFunction + "(";
    for (size_t i = 0; i < args.size(); ++i) s += (i ? ", " : "") + args[i];
    return s + ")";
}

}  // namespace specula::glsltest
