// Headless EGL/GL helpers and glslangValidator driver for the GLSL drift-guard tests.
#define GL_GLEXT_PROTOTYPES 1
#include "glsl_harness.h"

#include "core/codegen/glsl_signature.h"
#include "plugin/preview/gl_util.h"

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

bool glContext(std::string* why) { return gl::context(why); }

std::string glRenderer() { return gl::renderer(); }

unsigned glProgram(const std::string& fragment, std::string* log) {
    static const std::string vs = R"(#version 450 core
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
})";
    return gl::program(vs, fragment, log);
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

}  // namespace specula::glsltest
