// Colour management through OpenColorIO: loads the config Specula ships (OCIO 2.1 has no built-in
// configs), converts textures into the working space and renders scene-linear images through a view.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace specula {

struct ColorError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class ColorConfig {
public:
    // Loads the shipped config (data/ocio/config.ocio; located via $SPECULA_DATA_DIR, then the
    // compile-time SPECULA_DATA_DIR, then relative to the executable). "builtin" = that config;
    // otherwise a path to an .ocio file. Throws ColorError.
    static std::shared_ptr<const ColorConfig> load(const std::string& configPathOrBuiltin = "builtin");

    ~ColorConfig();
    const std::string& workingSpace() const;  // the scene_linear role's colorspace name
    std::string defaultDisplay() const;
    std::string defaultView() const;
    std::vector<std::string> colorspaces() const;
    std::vector<std::string> views(const std::string& display = "") const;
    bool hasColorspace(const std::string& name) const;  // also accepts aliases/roles
    // Every name a scene may give as a colorspace: names, aliases, roles and "raw" (docs/scene-format.md lists them).
    std::vector<std::string> acceptedColorspaceNames() const;
    bool hasView(const std::string& view) const;        // on the default display

    const std::string& configPath() const;  // the .ocio file that was loaded
    const std::string& cacheId() const;     // OCIO's cache id of the config (changes when its content does)
    // Canonical colorspace name for a name/alias/role, or "raw" for data spaces. Throws ColorError.
    std::string canonicalColorspace(const std::string& name) const;
    bool isData(const std::string& name) const;  // true for "raw" and isdata colorspaces. Throws ColorError.

    // In-place conversion of packed RGB (3 floats/pixel) from 'colorspace' to the working space.
    // "raw"/data colorspaces are a no-op. Throws ColorError on unknown names.
    void toWorking(float* rgb, size_t pixelCount, const std::string& colorspace) const;
    // In-place conversion of packed RGB from the working space to 'colorspace' (inverse of toWorking).
    void fromWorking(float* rgb, size_t pixelCount, const std::string& colorspace) const;
    // In-place working-space -> display/view conversion of packed RGB, with exposure in stops applied first.
    void toDisplay(float* rgb, size_t pixelCount, const std::string& view, float exposureStops = 0.f) const;

    // The same working-space -> display/view transform as GLSL 4.0 for a GPU (OCIO's GPU shader path), with the LUTs
    // it samples; what toDisplay computes, up to the LUTs' texture interpolation. Throws ColorError.
    struct GpuDisplayShader {
        std::string glsl;          // declares its samplers (no bindings) and 'vec4 functionName(vec4 inPixel)'
        std::string functionName;  // as asked
        struct Lut {
            std::string samplerName;
            int width = 0, height = 0, depth = 0;  // depth > 0: a 3D LUT (edge³); height > 1: a 1D LUT folded into 2D
            int channels = 1;                       // 1 (red) or 3 (RGB); 3D LUTs are RGB
            bool linear = true;                     // linear, else nearest interpolation
            std::vector<float> values;              // width·height·max(depth,1)·channels, x fastest
        };
        std::vector<Lut> luts;
    };
    GpuDisplayShader gpuDisplayShader(const std::string& view, float exposureStops, const std::string& functionName,
                                      const std::string& resourcePrefix) const;

    struct Impl;

private:
    explicit ColorConfig(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace specula
