// Image output and comparison: multi-layer scene-linear EXR with colorspace metadata, OCIO-viewed PNG,
// all written atomically (temp file + rename); RMSE/MAE/PSNR comparison with a false-colour diff map.
#pragma once

#include "core/math/math.h"
#include "core/util/error.h"

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace specula {

class ColorConfig;

// A file that cannot be read or written: an IoError, so every front end reports it with exit code 3 (docs/cli.md).
struct ImageIoError : IoError {
    using IoError::IoError;
};

// One AOV: 'channels' floats per pixel, rows top to bottom, linear values.
// Layer "beauty" is written as the EXR's R,G,B(,A) channels; others as "<name>.R" etc.
// channelNames: e.g. {"R","G","B"} for colours, {"X","Y","Z"} for normals, {"U","V"}, {"Z"} for depth.
struct AovBuffer {
    std::string name;
    std::vector<std::string> channelNames;
    std::vector<float> pixels;  // width*height*channelNames.size()

    int channels() const { return int(channelNames.size()); }
};

struct ImageSet {
    int width = 0, height = 0;
    std::vector<AovBuffer> aovs;                 // the first must be "beauty"
    std::map<std::string, std::string> metadata;  // extra string attributes (e.g. "specula:spp")
    // 4x4 matrix attributes by their OpenEXR names, OpenEXR's standard "worldToCamera" and "worldToNDC" among them
    // (column-vector convention here; the file holds Imath's row-vector matrices).
    std::map<std::string, Mat4> matrices;
    const AovBuffer* find(const std::string& name) const;
};

// Writes all AOVs as layers of one EXR (half or float: float), with the working colorspace as
// "oiio:ColorSpace" metadata. The file appears only when complete: written to a temp file in the
// same directory, then renamed over 'path'. Throws ImageIoError.
void writeExr(const std::string& path, const ImageSet& images, const ColorConfig& color);

// Converts the beauty AOV from the working space through the OCIO display/view, writes an 8-bit PNG
// (sRGB-tagged), atomically. 'view' empty = the config's default view.
void writePng(const std::string& path, const ImageSet& images, const ColorConfig& color, const std::string& view,
              float exposureStops = 0.f);

// Reads an EXR written by writeExr (or any image OIIO reads) back into an ImageSet,
// grouping channels into AOVs by their "layer." prefix (unprefixed RGB(A) -> "beauty"). A header declaring more than
// maxPixels pixels (the renderer's own maximum by default; a caller may lower it, as fuzz_image does) is refused.
constexpr int64_t kMaxImageSetPixels = int64_t(1) << 26;
ImageSet readImageSet(const std::string& path, int64_t maxPixels = kMaxImageSetPixels);

struct CompareResult {
    double rmse = 0, mae = 0, psnr = 0;  // over all pixels and channels of the compared AOV
    double peak = 1;                     // PSNR's peak: the reference's (b's) largest value, 1 if it has none > 0
    double meanA = 0, meanB = 0;
    int width = 0, height = 0, channels = 0;
    // The channels compared: those both images' AOVs have (an RGBA image against an RGB one compares R, G, B), and
    // those only one has, left out (with the file that has them), e.g. "A (only in 'a.exr')".
    std::vector<std::string> compared, ignored;
};

// Compares AOV 'aov' of two images with OpenImageIO's ImageBufAlgo (compare/computePixelStats).
// PSNR = 20 log10(peak / RMSE) with the reference's (b's) peak value. If diffPng is non-empty, writes a false-colour |A-B| map with a colour bar.
// Channels are matched by name: only the common ones are compared (CompareResult::ignored lists the others).
// Throws ImageIoError on missing files, a missing AOV, a size mismatch or no common channel (message names both).
CompareResult compareImages(const std::string& pathA, const std::string& pathB, const std::string& aov = "beauty",
                            const std::string& diffPng = "");

// Writes 'bytes' to path atomically (temp file in the same directory + rename).
void writeFileAtomic(const std::string& path, const std::string& bytes);

// Writes an 8-bit image of width*height*channels floats in [0,1], rows top to bottom, format from the
// extension (e.g. `specula plot`), with an optional ImageDescription. Throws IoError.
void writeImage8(const std::string& path, int width, int height, int channels, const float* pixels,
                 const std::string& description = "");

// Text for figures (`specula plot`'s titles, axes and colour bars): draws UTF-8 'text' into an RGB float image of
// width*height pixels (rows top to bottom) with OpenImageIO's FreeType renderer and the DejaVu Sans font (Debian's
// fonts-dejavu-core; SPECULA_FONT names another .ttf). (x, y) is the text's top edge at its left end, centre or right
// end for alignX -1, 0 or 1; 'vertical' turns the text a quarter to the left (reading upwards), with (x, y) then
// its left edge at its bottom, centre or top end. Returns false when no font is found.
bool drawText(float* rgb, int width, int height, int x, int y, const std::string& text, int pixelSize,
              const Vec3& color, int alignX = -1, bool vertical = false);

// Building blocks of the atomic writes above, for other writers (e.g. the texture cache):
// creates a unique empty file ".<stem>.tmp-XXXXXX<ext>" next to 'path' and returns its path
// (throws ImageIoError if the directory does not exist or is not writable) ...
std::string createTempFileNear(const std::string& path);
// ... then makes it durable and renames it over 'path'; on failure removes 'tmpPath' and throws ImageIoError.
void commitTempFile(const std::string& tmpPath, const std::string& path);

}  // namespace specula
