// The GPU's display transform: draws a scene-linear texture into the bound framebuffer through the scene's OCIO view
// (OCIO's GPU shader path, LUTs as textures), what the CPU's PNG writer computes, for windows and screenshots.
#pragma once

#include <string>
#include <vector>

namespace specula {
class ColorConfig;
}

namespace specula::preview {

class DisplayPass {
public:
    // 'view' empty: the config's default view; exposure in stops before the view (as writePng). Needs the GL 4.5
    // context current. Throws ColorError for an unknown view, IoError when the shader does not compile.
    DisplayPass(const ColorConfig& color, const std::string& view, float exposureStops);
    ~DisplayPass();
    DisplayPass(const DisplayPass&) = delete;
    DisplayPass& operator=(const DisplayPass&) = delete;

    enum class Mode { Colour, Normal };  // Colour: through the view; Normal: xyz·0.5 + 0.5, raw
    // Draws texture 'sceneLinear' (RGBA32F) texel for pixel into the bound framebuffer's viewport (0, 0, W, H).
    void draw(unsigned sceneLinear, int width, int height, Mode mode) const;

private:
    unsigned program_ = 0, vao_ = 0;
    struct Lut {
        unsigned texture = 0, target = 0;
        int unit = 0;
    };
    std::vector<Lut> luts_;
};

}  // namespace specula::preview
