// libspecula side of the OpenImageIO module (core/io_module/io_module.h): forwarding stubs for image I/O, textures
// and normal maps; the first call dlopens libspecula_io.so from libspecula's own folder.
#include "core/io_module/io_module.h"

#include "core/util/error.h"
#include "core/util/input_files.h"

#include <algorithm>
#include <dlfcn.h>

#include <atomic>
#include <filesystem>
#include <mutex>

namespace specula {

void writeImage8(const std::string& path, int width, int height, int channels, const float* pixels,
                 const std::string& description);

namespace io_module {
namespace {

std::atomic<const Table*> gTable{nullptr};

const Table* loadTable() {
    Dl_info self{};
    std::string dir;
    if (dladdr(reinterpret_cast<void*>(&loadTable), &self) && self.dli_fname)
        dir = std::filesystem::path(self.dli_fname).parent_path().string();
    std::string path = (dir.empty() ? std::string() : dir + "/") + SPECULA_IO_MODULE;
    void* h = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!h) throw IoError(std::string("cannot load the image I/O module: ") + dlerror());
    auto fn = reinterpret_cast<const Table* (*)()>(dlsym(h, "specula_io_module_table"));
    if (!fn) throw IoError("image I/O module '" + path + "' has no table");
    const Table* t = fn();
    if (!t || t->abiVersion != kAbiVersion) throw IoError("image I/O module '" + path + "' has the wrong version");
    return t;  // never unloaded: OpenImageIO keeps per-process state
}

}  // namespace

const Table& table() {
    if (const Table* t = gTable.load(std::memory_order_acquire)) return *t;
    static std::mutex m;
    std::lock_guard<std::mutex> lock(m);
    if (!gTable.load()) gTable.store(loadTable(), std::memory_order_release);
    return *gTable.load();
}

bool loaded() { return gTable.load() != nullptr; }

}  // namespace io_module

using io_module::table;

// ---- core/io/image_io.h ---------------------------------------------------------------------------
const AovBuffer* ImageSet::find(const std::string& name) const { return table().imageSetFind(*this, name); }
void writeExr(const std::string& path, const ImageSet& images, const ColorConfig& color) {
    refuseOverwritingInputs(path, {}, "output");
    table().writeExr(path, images, color);
}
void writePng(const std::string& path, const ImageSet& images, const ColorConfig& color, const std::string& view,
              float exposureStops) {
    refuseOverwritingInputs(path, {}, "output");
    table().writePng(path, images, color, view, exposureStops);
}
ImageSet readImageSet(const std::string& path, int64_t maxPixels) {
    noteInputFile(path);
    return table().readImageSet(path, maxPixels);
}
CompareResult compareImages(const std::string& a, const std::string& b, const std::string& aov, const std::string& diff) {
    noteInputFile(a);
    noteInputFile(b);
    if (!diff.empty()) refuseOverwritingInputs(diff, {a, b}, "--diff");
    return table().compareImages(a, b, aov, diff);
}
// Every writer refuses a target that this command read (core/util/input_files.h); a temporary is checked on commit.
void writeFileAtomic(const std::string& path, const std::string& bytes) {
    refuseOverwritingInputs(path, {}, "output");
    table().writeFileAtomic(path, bytes);
}
std::string createTempFileNear(const std::string& path) { return table().createTempFileNear(path); }
void commitTempFile(const std::string& tmp, const std::string& path) {
    refuseOverwritingInputs(path, {}, "output");
    table().commitTempFile(tmp, path);
}
void writeImage8(const std::string& path, int width, int height, int channels, const float* pixels,
                 const std::string& description) {
    refuseOverwritingInputs(path, {}, "output");
    table().writeImage8(path, width, height, channels, pixels, description);
}
bool drawText(float* rgb, int width, int height, int x, int y, const std::string& text, int pixelSize,
              const Vec3& color, int alignX, bool vertical) {
    return table().drawText(rgb, width, height, x, y, text, pixelSize, color, alignX, vertical);
}

// ---- core/texture/texture_store.h: the module's TextureStore is created on the first load() ----------
struct TextureStore::Impl {
    std::shared_ptr<const ColorConfig> color;
    int maxSide = 65536;
    TextureStore* real = nullptr;
    std::mutex m;
};

TextureStore::TextureStore(std::shared_ptr<const ColorConfig> color, int maxSide) : impl_(std::make_unique<Impl>()) {
    impl_->color = std::move(color);
    impl_->maxSide = maxSide;
}
TextureStore::~TextureStore() {
    if (impl_ && impl_->real) table().textureDestroy(impl_->real);
}
TextureHandle TextureStore::load(const std::string& path, const std::string& colorspace) {
    {
        std::lock_guard<std::mutex> lock(impl_->m);
        if (!impl_->real) impl_->real = table().textureCreate(impl_->color, impl_->maxSide);
    }
    noteInputFile(path);
    return table().textureLoad(impl_->real, path, colorspace);
}
int TextureStore::maxSide() const { return std::clamp(impl_->maxSide, 1, 65536); }  // as the real store clamps it
int TextureStore::width(TextureHandle h) const { return table().textureWidth(impl_->real, h); }
int TextureStore::height(TextureHandle h) const { return table().textureHeight(impl_->real, h); }
int TextureStore::channels(TextureHandle h) const { return table().textureChannels(impl_->real, h); }
void TextureStore::sample(TextureHandle h, Vec2 uv, Vec2 duvdx, Vec2 duvdy, float* out, int nchannels,
                          TextureWrap wrap) const {
    table().textureSample(impl_->real, h, uv, duvdx, duvdy, out, nchannels, wrap);
}
Color3 TextureStore::sampleRgb(TextureHandle h, Vec2 uv, Vec2 duvdx, Vec2 duvdy, TextureWrap wrap) const {
    return table().textureSampleRgb(impl_->real, h, uv, duvdx, duvdy, wrap);
}
const std::vector<float>& TextureStore::pixels(TextureHandle h) const { return table().texturePixels(impl_->real, h); }

// ---- core/texture/normal_map_gen.h ---------------------------------------------------------------------
const char* normalMapKindName(NormalMapKind k) { return table().normalMapKindName(k); }
NormalMapKind parseNormalMapKind(const std::string& name) { return table().parseNormalMapKind(name); }
const std::vector<NormalMapKind>& allNormalMapKinds() { return table().allNormalMapKinds(); }
NormalMap generateNormalMap(NormalMapKind kind, int size, uint64_t seed) {
    return table().generateNormalMap(kind, size, seed);
}
NormalMap generateBrushedNormalMap(int size, uint64_t seed, double angleDegrees, double* usedAngleDegrees) {
    return table().generateBrushedNormalMap(size, seed, angleDegrees, usedAngleDegrees);
}
void writeNormalMap(const NormalMap& map, const std::string& path) {
    refuseOverwritingInputs(path, {}, "output");
    table().writeNormalMap(map, path);
}
uint64_t normalMapHash(const NormalMap& map) { return table().normalMapHash(map); }
SlopeStats slopeStats(const NormalMap& map) { return table().slopeStats(map); }
double SlopeStats::sigmaX() const { return table().slopeStat(*this, 0); }
double SlopeStats::sigmaY() const { return table().slopeStat(*this, 1); }
double SlopeStats::rho() const { return table().slopeStat(*this, 2); }
double SlopeStats::sigmaMajor() const { return table().slopeStat(*this, 3); }
double SlopeStats::sigmaMinor() const { return table().slopeStat(*this, 4); }

}  // namespace specula
