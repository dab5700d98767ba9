// Output helpers of the public API.
#include "core/api/specula.h"

#include <filesystem>

namespace specula {

std::string writeRenderOutputs(const std::string& exrPath, const Scene& scene, const ImageSet& images) {
    std::string png = std::filesystem::path(exrPath).replace_extension(".png").string();
    writeExr(exrPath, images, *scene.colorConfig);
    writePng(png, images, *scene.colorConfig, scene.color.view, scene.color.exposure);
    return png;
}

}  // namespace specula
