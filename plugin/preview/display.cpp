// DisplayPass: OCIO's GLSL for the working-space -> display/view transform (ColorConfig::gpuDisplayShader), its LUTs
// uploaded as textures on the units after 0, a full-screen triangle that fetches one texel per pixel.
#define GL_GLEXT_PROTOTYPES 1
#include "plugin/preview/display.h"

#include "core/color/color_config.h"
#include "core/util/error.h"
#include "plugin/preview/gl_util.h"

#include <GL/gl.h>
#include <GL/glext.h>

namespace specula::preview {

namespace {
const char* kVertex = R"(#version 450 core
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.0, 1.0);
}
)";
// After OCIO's function: texel for pixel (the texture is the framebuffer's size), the view or the raw normal.
const char* kFragmentMain = R"(
layout(binding = 0) uniform sampler2D spc_display_source;
layout(location = 0) uniform int spc_display_mode;  // 0 colour through the view, 1 normal
layout(location = 0) out vec4 o_colour;
void main() {
    vec4 c = texelFetch(spc_display_source, ivec2(gl_FragCoord.xy), 0);
    if (spc_display_mode == 1)
        o_colour = vec4(clamp(c.xyz * 0.5 + 0.5, 0.0, 1.0), 1.0);
    else
        o_colour = vec4(clamp(spc_ocio_display(vec4(c.rgb, 1.0)).rgb, 0.0, 1.0), 1.0);
}
)";
}  // namespace

DisplayPass::DisplayPass(const ColorConfig& color, const std::string& view, float exposureStops) {
    const ColorConfig::GpuDisplayShader sh = color.gpuDisplayShader(view, exposureStops, "spc_ocio_display", "spc_ocio_");
    std::string log;
    program_ = gl::program(kVertex, std::string("#version 450 core\n") + sh.glsl + kFragmentMain, &log);
    if (!program_) throw IoError("the display shader (OCIO view '" + view + "') does not compile: " + log);
    int unit = 1;
    for (const ColorConfig::GpuDisplayShader::Lut& l : sh.luts) {
        Lut g;
        g.unit = unit++;
        g.target = l.depth > 0 ? GL_TEXTURE_3D : l.height > 1 ? GL_TEXTURE_2D : GL_TEXTURE_1D;
        const GLenum internal = l.channels == 1 ? GL_R32F : GL_RGB32F, format = l.channels == 1 ? GL_RED : GL_RGB;
        glGenTextures(1, &g.texture);
        glBindTexture(g.target, g.texture);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        if (g.target == GL_TEXTURE_3D)
            glTexImage3D(g.target, 0, GLint(internal), l.width, l.height, l.depth, 0, format, GL_FLOAT, l.values.data());
        else if (g.target == GL_TEXTURE_2D)
            glTexImage2D(g.target, 0, GLint(internal), l.width, l.height, 0, format, GL_FLOAT, l.values.data());
        else
            glTexImage1D(g.target, 0, GLint(internal), l.width, 0, format, GL_FLOAT, l.values.data());
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        const GLint filter = l.linear ? GL_LINEAR : GL_NEAREST;
        glTexParameteri(g.target, GL_TEXTURE_MIN_FILTER, filter);
        glTexParameteri(g.target, GL_TEXTURE_MAG_FILTER, filter);
        glTexParameteri(g.target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(g.target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glTexParameteri(g.target, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
        // OCIO declares its samplers without bindings: set each to its unit by name.
        const GLint location = glGetUniformLocation(program_, l.samplerName.c_str());
        if (location >= 0) glProgramUniform1i(program_, location, g.unit);
        luts_.push_back(g);
    }
    glGenVertexArrays(1, &vao_);
}

DisplayPass::~DisplayPass() {
    for (const Lut& l : luts_) glDeleteTextures(1, &l.texture);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(program_);
}

void DisplayPass::draw(unsigned sceneLinear, int width, int height, Mode mode) const {
    glViewport(0, 0, width, height);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_FRAMEBUFFER_SRGB);  // the view encodes for the display itself
    glUseProgram(program_);
    glUniform1i(0, mode == Mode::Normal ? 1 : 0);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, sceneLinear);
    for (const Lut& l : luts_) {
        glActiveTexture(GLenum(GL_TEXTURE0 + l.unit));
        glBindTexture(l.target, l.texture);
    }
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glActiveTexture(GL_TEXTURE0);
}

}  // namespace specula::preview
