// Module side of the OpenImageIO module (core/io_module/io_module.h): the table of the real functions, built into
// libspecula_io.so together with image_io.cpp, texture_store.cpp and normal_map_gen.cpp. Linked with
// -Bsymbolic-functions, so every name below binds to the module's own definition, not to libspecula's stub.
#include "core/io_module/io_module.h"
#include "core/io/image_read.h"

#include "core/util/error.h"

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>

namespace specula {

// An 8-bit image of w*h*channels floats in [0,1] (format from the extension), e.g. `specula plot`.
void writeImage8(const std::string& path, int width, int height, int channels, const float* pixels,
                 const std::string& description) {
    // Through a temporary, like every image libspecula writes: a full disk (OpenImageIO's PNG writer does not report
    // every short write) must leave no truncated file under the name; the size is checked after closing.
    auto probe = OIIO::ImageOutput::create(path);
    if (!probe) throw IoError("cannot write '" + path + "': unsupported format");
    const std::string format = probe->format_name();
    probe.reset();
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
    if (!description.empty()) spec.attribute("ImageDescription", description);
    writeImageAtomic(path, spec, pixels, format.c_str(), "image", OIIO::TypeDesc::FLOAT);  // floats in, 8 bits out
}

namespace {
const std::string& fontPath() {
    static const std::string path = [] {
        std::error_code ec;
        const char* env = std::getenv("SPECULA_FONT");
        for (const std::string& p : {std::string(env ? env : ""), std::string("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf")})
            if (!p.empty() && std::filesystem::is_regular_file(p, ec)) return p;
        return std::string();
    }();
    return path;
}
}  // namespace

bool drawText(float* rgb, int width, int height, int x, int y, const std::string& text, int pixelSize,
              const Vec3& color, int alignX, bool vertical) {
    if (fontPath().empty()) return false;
    // The text is drawn white on black into its own buffer and composited with it as coverage, so that it can be
    // turned for a vertical axis and keeps the figure's colours under its anti-aliased edges.
    // text_size is relative to the baseline's start (its ybegin is negative: the ascent).
    const OIIO::ROI extent = OIIO::ImageBufAlgo::text_size(text, pixelSize, fontPath());
    if (!extent.defined() || extent.width() <= 0 || extent.height() <= 0) return false;
    OIIO::ImageBuf label(OIIO::ImageSpec(extent.width(), extent.height(), 1, OIIO::TypeDesc::FLOAT));
    OIIO::ImageBufAlgo::zero(label);
    const float white[1] = {1.f};
    if (!OIIO::ImageBufAlgo::render_text(label, -extent.xbegin, -extent.ybegin, text, pixelSize, fontPath(), white))
        return false;
    const OIIO::ROI roi = label.roi();
    const int w = roi.width(), h = roi.height();  // i along the text, j down from its top edge
    const int shift = alignX < 0 ? 0 : alignX == 0 ? w / 2 : w;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            float cover = 0.f;
            label.getpixel(roi.xbegin + i, roi.ybegin + j, &cover, 1);
            cover = std::min(cover, 1.f);
            if (!(cover > 0.f)) continue;
            // Vertical text reads upwards: its start at the bottom, its top edge facing left.
            const int px = vertical ? x + j : x - shift + i;
            const int py = vertical ? y + shift - i : y + j;
            if (px < 0 || py < 0 || px >= width || py >= height) continue;
            float* d = rgb + (size_t(py) * size_t(width) + size_t(px)) * 3;
            for (int c = 0; c < 3; ++c) d[c] = d[c] * (1.f - cover) + color[c] * cover;
        }
    return true;
}

}  // namespace specula

using namespace specula;

extern "C" __attribute__((visibility("default"))) const io_module::Table* specula_io_module_table() {
    static const io_module::Table t = [] {
        io_module::Table x;
        x.imageSetFind = [](const ImageSet& s, const std::string& n) { return s.find(n); };
        x.writeExr = &writeExr;
        x.writePng = &writePng;
        x.readImageSet = &readImageSet;
        x.compareImages = &compareImages;
        x.writeFileAtomic = &writeFileAtomic;
        x.createTempFileNear = &createTempFileNear;
        x.commitTempFile = &commitTempFile;
        x.writeImage8 = &writeImage8;
        x.drawText = &drawText;
        x.textureCreate = [](std::shared_ptr<const ColorConfig> c, int maxSide) { return new TextureStore(std::move(c), maxSide); };
        x.textureDestroy = [](TextureStore* s) { delete s; };
        x.textureLoad = [](TextureStore* s, const std::string& p, const std::string& cs) { return s->load(p, cs); };
        x.textureWidth = [](const TextureStore* s, TextureHandle h) { return s->width(h); };
        x.textureHeight = [](const TextureStore* s, TextureHandle h) { return s->height(h); };
        x.textureChannels = [](const TextureStore* s, TextureHandle h) { return s->channels(h); };
        x.textureSample = [](const TextureStore* s, TextureHandle h, Vec2 uv, Vec2 dx, Vec2 dy, float* out, int n,
                             TextureWrap w) { s->sample(h, uv, dx, dy, out, n, w); };
        x.textureSampleRgb = [](const TextureStore* s, TextureHandle h, Vec2 uv, Vec2 dx, Vec2 dy, TextureWrap w) {
            return s->sampleRgb(h, uv, dx, dy, w);
        };
        x.texturePixels = [](const TextureStore* s, TextureHandle h) -> const std::vector<float>& { return s->pixels(h); };
        x.normalMapKindName = &normalMapKindName;
        x.parseNormalMapKind = &parseNormalMapKind;
        x.allNormalMapKinds = &allNormalMapKinds;
        x.generateNormalMap = &generateNormalMap;
        x.generateBrushedNormalMap = &generateBrushedNormalMap;
        x.writeNormalMap = &writeNormalMap;
        x.normalMapHash = &normalMapHash;
        x.slopeStats = &slopeStats;
        x.slopeStat = [](const SlopeStats& s, int which) {
            switch (which) {
                case 0: return s.sigmaX();
                case 1: return s.sigmaY();
                case 2: return s.rho();
                case 3: return s.sigmaMajor();
                default: return s.sigmaMinor();
            }
        };
        return x;
    }();
    return &t;
}
