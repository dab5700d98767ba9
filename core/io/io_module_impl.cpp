// Module side of the OpenImageIO module (core/io/io_module.h): the table of the real functions, built into
// libspecula_io.so together with image_io.cpp, texture_store.cpp and normal_map_gen.cpp. Linked with
// -Bsymbolic-functions, so every name below binds to the module's own definition, not to libspecula's stub.
#include "core/io/io_module.h"

#include "core/util/error.h"

#include <OpenImageIO/imageio.h>

namespace specula {

// An 8-bit image of w*h*channels floats in [0,1] (format from the extension), e.g. `specula plot`.
void writeImage8(const std::string& path, int width, int height, int channels, const float* pixels,
                 const std::string& description) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw IoError("cannot write '" + path + "': unsupported format");
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
    if (!description.empty()) spec.attribute("ImageDescription", description);
    if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels) || !out->close())
        throw IoError("cannot write '" + path + "': " + out->geterror());
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
        x.textureCreate = [](std::shared_ptr<const ColorConfig> c) { return new TextureStore(std::move(c)); };
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
