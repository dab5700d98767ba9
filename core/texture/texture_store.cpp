// TextureStore: reads images with OpenImageIO, converts them once to the linear working space, caches a
// MIP-mapped float .tx per (content, colorspace), checksummed by a sidecar (core/util/cache_dir.h), and samples it
// through a shared OIIO TextureSystem.
#include "core/texture/texture_store.h"
#include "core/util/cache_dir.h"
#include "core/util/error.h"
#include "core/util/memory_budget.h"

#include "core/color/color_config.h"
#include "core/io/image_io.h"
#include "core/io/image_read.h"
#include "core/texture/normal_map_gen.h"

#include <OpenImageIO/hash.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/texture.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace specula {

namespace {

// Bump when the cached .tx content changes meaning (conversion, filtering, layout).
constexpr const char* kCacheFormatVersion = "specula-tx-1";

std::string hex64(uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)v);
    return buf;
}

// The shared cache rule (core/util/cache_dir.h), "textures" below it.
std::string textureCacheDir() {
    try {
        return cacheFolder("textures");
    } catch (const IoError& e) {
        throw TextureError(e.what());
    }
}

OIIO::TextureOpt::Wrap toOiio(TextureWrap w) {
    switch (w) {
        case TextureWrap::Repeat: return OIIO::TextureOpt::WrapPeriodic;
        case TextureWrap::Clamp: return OIIO::TextureOpt::WrapClamp;
        case TextureWrap::Mirror: return OIIO::TextureOpt::WrapMirror;
        case TextureWrap::Black: return OIIO::TextureOpt::WrapBlack;
    }
    return OIIO::TextureOpt::WrapPeriodic;
}

struct Entry {
    std::string path;        // as given
    std::string colorspace;  // canonical, or "raw"
    std::string cachePath;   // the MIP-mapped .tx
    int width = 0, height = 0, channels = 0;
    std::vector<float> pixels;  // linear working space, rows top to bottom
    OIIO::TextureSystem::TextureHandle* handle = nullptr;
};

constexpr int kChunkBits = 8;
constexpr int kChunkSize = 1 << kChunkBits;
constexpr int kMaxChunks = 1024;  // up to 262144 textures per store

}  // namespace

struct TextureStore::Impl {
    std::shared_ptr<const ColorConfig> color;
    OIIO::TextureSystem* ts = nullptr;
    int maxSide = 65536;

    std::mutex mutex;                                       // guards everything below except the lock-free table
    std::map<std::pair<std::string, std::string>, int> byKey;  // (absolute path, declared colorspace) -> index
    std::vector<std::unique_ptr<Entry>> owned;
    std::vector<std::unique_ptr<std::atomic<Entry*>[]>> chunkStore;
    // Lock-free lookup for the render threads: chunks[i >> 8][i & 255].
    std::array<std::atomic<std::atomic<Entry*>*>, kMaxChunks> chunks{};
    std::string cacheDir;

    const Entry& entry(TextureHandle h) const {
        if (h.index < 0 || h.index >= kMaxChunks * kChunkSize) throw TextureError("invalid texture handle");
        std::atomic<Entry*>* chunk = chunks[size_t(h.index >> kChunkBits)].load(std::memory_order_acquire);
        Entry* e = chunk ? chunk[h.index & (kChunkSize - 1)].load(std::memory_order_acquire) : nullptr;
        if (!e) throw TextureError("invalid texture handle " + std::to_string(h.index));
        return *e;
    }

    // Caller holds 'mutex'.
    int publish(std::unique_ptr<Entry> e) {
        int index = int(owned.size());
        if (index >= kMaxChunks * kChunkSize) throw TextureError("too many textures");
        size_t c = size_t(index >> kChunkBits);
        if (!chunks[c].load(std::memory_order_relaxed)) {
            chunkStore.emplace_back(new std::atomic<Entry*>[kChunkSize]);
            for (int i = 0; i < kChunkSize; ++i) chunkStore.back()[size_t(i)].store(nullptr, std::memory_order_relaxed);
            chunks[c].store(chunkStore.back().get(), std::memory_order_release);
        }
        Entry* raw = e.get();
        owned.push_back(std::move(e));
        chunks[c].load(std::memory_order_relaxed)[index & (kChunkSize - 1)].store(raw, std::memory_order_release);
        return index;
    }
};

namespace {
// One private TextureSystem for the whole process (no cross-talk with other OIIO users), created on first use and
// never destroyed. OIIO keeps per-thread tile state per texture system in thread-specific storage: destroying a
// system while render worker threads live on (one per TextureStore, as before) corrupted that state at random
// (decr_tiles assertions and crashes in tests that load several scenes). Texture files are content-addressed .tx
// caches, so a file name never changes meaning while the system lives.
OIIO::TextureSystem* processTextureSystem() {
    static OIIO::TextureSystem* ts = [] {
        OIIO::TextureSystem* t = OIIO::TextureSystem::create(false);
        t->attribute("automip", 0);
        t->attribute("autotile", 0);
        t->attribute("gray_to_rgb", 0);
        t->attribute("forcefloat", 1);
        return t;
    }();
    return ts;
}
}  // namespace

TextureStore::TextureStore(std::shared_ptr<const ColorConfig> color, int maxSide) : impl_(std::make_unique<Impl>()) {
    if (!color) throw TextureError("TextureStore needs a ColorConfig");
    impl_->color = std::move(color);
    impl_->maxSide = std::clamp(maxSide, 1, 65536);
    impl_->ts = processTextureSystem();
}

TextureStore::~TextureStore() = default;

namespace {

// A texture is read as floats, converted and MIP-mapped: the texture store's side limit and kMaxTextureBytes of float
// pixels bound what a header can make us allocate (docs/scene-format.md, issue 16).
constexpr uint64_t kMaxTextureBytes = uint64_t(4) << 30;
constexpr uint64_t kMaxTextureFileBytes = uint64_t(4) << 30;

void checkTextureFileSize(const std::string& path) {
    std::error_code ec;
    const uint64_t size = fs::file_size(path, ec);
    if (!ec && size > kMaxTextureFileBytes)
        throw TextureInputError("texture '" + path + "' is " + formatBytes(size) + "; textures are limited to " +
                           formatBytes(kMaxTextureFileBytes));
}

// Read, colour conversion and MIP chain hold about three float copies at once.
void checkTextureMemory(const std::string& path, const OIIO::ImageSpec& spec) {
    const uint64_t bytes = uint64_t(spec.width) * uint64_t(spec.height) * uint64_t(spec.nchannels) * sizeof(float);
    const std::string claim = std::to_string(spec.width) + "x" + std::to_string(spec.height) + " pixels, " +
                              std::to_string(spec.nchannels) + " channels";
    const MemoryBudget budget = memoryBudget();
    if (3 * bytes > budget.availableBytes)
        throw TextureInputError("texture '" + path + "' (" + claim + ") needs about " + formatBytes(3 * bytes) + " to load, but " +
                           formatBytes(budget.availableBytes) + " are left under " + budget.limitedBy);
}

}  // namespace

TextureHandle TextureStore::load(const std::string& path, const std::string& colorspace) {
    auto& I = *impl_;
    std::error_code ec;
    // 'generate:<kind>:<size>:<seed>' (normal_map_gen.h): a procedural normal map instead of a file, raw data.
    const bool generated = isGeneratedNormalMapName(path);
    if (!generated && !fs::is_regular_file(path, ec)) throw TextureError("texture file not found: '" + path + "'");
    std::string absPath = generated ? path : fs::weakly_canonical(fs::absolute(path, ec), ec).string();
    if (absPath.empty()) absPath = path;

    const bool autoSpace = colorspace.empty() || colorspace == "auto";
    std::string declared;
    if (!autoSpace) {
        try {
            declared = I.color->canonicalColorspace(colorspace);
        } catch (const ColorError& e) {
            throw TextureColorspaceError("texture '" + path + "': " + e.what());
        }
    }
    const auto key = std::make_pair(absPath, autoSpace ? std::string("auto") : declared);
    {
        std::lock_guard<std::mutex> lock(I.mutex);
        auto it = I.byKey.find(key);
        if (it != I.byKey.end()) return TextureHandle{it->second};
        if (I.cacheDir.empty()) I.cacheDir = textureCacheDir();
    }

    // ---- read the file (content hash + pixels); heavy work happens without the lock ----
    std::string bytes;
    OIIO::ImageSpec spec;
    std::vector<float> pixels;
    if (generated) {
        // The name is the content (the generator is deterministic), the pixels come from memory.
        NormalMap map;
        try {
            map = generateNormalMapFromName(path, I.maxSide);
        } catch (const std::exception& err) {
            throw TextureError(err.what());
        }
        bytes = path;
        spec = OIIO::ImageSpec(map.size, map.size, 3, OIIO::TypeDesc::FLOAT);
        spec.attribute("oiio:ColorSpace", "Raw");
        pixels = encodeNormalMapRgb(map);
        if (autoSpace) declared = "raw";
    } else {
        checkTextureFileSize(path);
        {
            std::ifstream f(path, std::ios::binary);
            std::ostringstream ss;
            ss << f.rdbuf();
            if (!f.good() && !f.eof()) throw TextureError("cannot read texture '" + path + "'");
            bytes = ss.str();
        }
        // The one guarded open (core/io/image_read.h): straight alpha (colour is converted unpremultiplied), and
        // kMaxTextureTexels per side, 64 channels and kMaxTextureBytes of float pixels bound what a header can make us
        // allocate (docs/scene-format.md, issue 16).
        ImageLimits limits;
        limits.maxSide = I.maxSide;
        limits.maxPixels = int64_t(I.maxSide) * I.maxSide;
        limits.maxChannels = 64;
        limits.maxFloatBytes = kMaxTextureBytes;
        limits.what = "textures";
        GuardedImage guarded = openImageGuarded(path, limits);
        if (guarded.refused) throw TextureInputError("texture '" + path + "': " + guarded.problem);
        if (!guarded.input) throw TextureError("cannot read texture '" + path + "': " + guarded.problem);
        OIIO::ImageInput* in = guarded.input.get();
        spec = in->spec();
        checkTextureMemory(path, spec);
        pixels.resize(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
        if (!readPixelsAsFloat(*in, 0, pixels.data()))
            throw TextureError("cannot read texture '" + path + "': " + in->geterror());
    }
    auto e = std::make_unique<Entry>();
    e->path = path;
    e->width = spec.width;
    e->height = spec.height;
    e->channels = spec.nchannels;

    if (autoSpace && !generated) {
        // The file's own tag if the config knows it; else 8/16-bit integer = sRGB, float = working space.
        std::string tag = spec.get_string_attribute("oiio:ColorSpace");
        if (!tag.empty() && I.color->hasColorspace(tag))
            declared = I.color->canonicalColorspace(tag);
        else if (spec.format.is_floating_point())
            declared = I.color->workingSpace();
        else
            declared = I.color->canonicalColorspace("sRGB - Texture");
    }
    e->colorspace = declared;

    const size_t npix = size_t(e->width) * size_t(e->height);
    const size_t nc = size_t(e->channels);
    e->pixels = std::move(pixels);

    // ---- colour: declared space -> working linear (RGB only; alpha and extra channels untouched) ----
    try {
        if (!I.color->isData(declared)) {
            std::vector<float> rgb(npix * 3);
            for (size_t i = 0; i < npix; ++i)
                for (size_t k = 0; k < 3; ++k) rgb[i * 3 + k] = e->pixels[i * nc + (nc >= 3 ? k : 0)];
            I.color->toWorking(rgb.data(), npix, declared);
            for (size_t i = 0; i < npix; ++i) {
                if (nc >= 3) {
                    for (size_t k = 0; k < 3; ++k) e->pixels[i * nc + k] = rgb[i * 3 + k];
                } else {  // grey (+alpha): neutral stays neutral; keep the mean
                    e->pixels[i * nc] = (rgb[i * 3] + rgb[i * 3 + 1] + rgb[i * 3 + 2]) / 3.f;
                }
            }
        }
    } catch (const ColorError& err) {
        throw TextureError("texture '" + path + "': " + err.what());
    }

    // ---- MIP-mapped float texture in the cache, keyed by content + colorspace + config + version ----
    std::string keyText = std::string(kCacheFormatVersion) + "|" + declared + "|" + I.color->cacheId();
    uint64_t h1 = OIIO::fasthash::fasthash64(bytes.data(), bytes.size(), 0x5bec01a5ULL);
    uint64_t h2 = OIIO::fasthash::fasthash64(bytes.data(), bytes.size(), 0x0c0ffee1ULL);
    h1 = OIIO::fasthash::fasthash64(keyText.data(), keyText.size(), h1);
    h2 = OIIO::fasthash::fasthash64(keyText.data(), keyText.size(), h2 ^ bytes.size());
    e->cachePath = (fs::path(I.cacheDir) / (hex64(h1) + hex64(h2) + ".tx")).string();

    auto makeTx = [&]() {
        OIIO::ImageSpec linSpec(e->width, e->height, e->channels, OIIO::TypeDesc::FLOAT);
        linSpec.channelnames = spec.channelnames;
        linSpec.alpha_channel = -1;  // plain channels: no (un)premultiplication anywhere downstream
        linSpec.attribute("oiio:ColorSpace", I.color->isData(declared) ? std::string("Raw") : I.color->workingSpace());
        OIIO::ImageBuf lin(linSpec, e->pixels.data());
        OIIO::ImageSpec cfg;
        cfg.tile_width = 64;
        cfg.tile_height = 64;
        cfg.tile_depth = 1;
        cfg.format = OIIO::TypeDesc::FLOAT;
        cfg.attribute("maketx:filtername", "box");
        cfg.attribute("maketx:fileformatname", "tiff");
        cfg.attribute("maketx:constant_color_detect", 0);
        cfg.attribute("maketx:monochrome_detect", 0);
        cfg.attribute("maketx:opaque_detect", 0);
        cfg.attribute("maketx:fixnan", "none");
        cfg.attribute("compression", "zip");
        cfg.attribute("specula:source", absPath);
        cfg.attribute("specula:colorspace", declared);
        std::string tmp;
        try {
            tmp = createTempFileNear(e->cachePath);
        } catch (const ImageIoError& err) {
            throw TextureError("texture '" + path + "': cannot write the MIP cache: " + err.what());
        }
        std::ostringstream log;
        if (!OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, lin, tmp, cfg, &log)) {
            std::error_code rec;
            fs::remove(tmp, rec);
            throw TextureError("texture '" + path + "': cannot build the MIP map: " + OIIO::geterror() + " " +
                               log.str());
        }
        try {
            commitTempFile(tmp, e->cachePath);
        } catch (const ImageIoError& err) {
            throw TextureError("texture '" + path + "': " + err.what());
        }
        // Best effort: without a sidecar the file is rebuilt next time rather than trusted.
        (void)writeCacheChecksum(e->cachePath);
        // OIIO may hold tiles or an open handle of an earlier file under this name (a corrupt one being replaced).
        I.ts->invalidate(OIIO::ustring(e->cachePath), true);
    };

    auto openHandle = [&]() -> bool {
        e->handle = I.ts->get_texture_handle(OIIO::ustring(e->cachePath));
        if (!e->handle) return false;
        int exists = 0;
        int res[3] = {0, 0, 0};
        bool ok = I.ts->get_texture_info(e->handle, nullptr, 0, OIIO::ustring("exists"), OIIO::TypeInt, &exists) &&
                  exists &&
                  I.ts->get_texture_info(e->handle, nullptr, 0, OIIO::ustring("resolution"),
                                         OIIO::TypeDesc(OIIO::TypeDesc::INT, 2), res) &&
                  res[0] == e->width && res[1] == e->height;
        if (!ok) (void)I.ts->geterror();
        return ok;
    };

    // A cache file is used only when its checksum sidecar agrees with every byte of it (core/util/cache_dir.h):
    // OpenImageIO reads a corrupted or truncated .tx, or a valid one of other content, without complaint and
    // samples wrong texels (issue 35). Anything else is rebuilt from the pixels in memory, like the LTC and P-NDF
    // caches refit on a bad checksum.
    if (!fs::is_regular_file(e->cachePath, ec)) {
        makeTx();
    } else if (!cacheChecksumMatches(e->cachePath)) {
        warnCorruptCacheEntry(e->cachePath, "fails its checksum sidecar");
        makeTx();
    }
    if (!openHandle()) {
        // A file replaced between the check and the open: rebuild it once more.
        makeTx();
        if (!openHandle())
            throw TextureError("texture '" + path + "': cannot open the MIP cache '" + e->cachePath +
                               "': " + I.ts->geterror());
    }

    std::lock_guard<std::mutex> lock(I.mutex);
    auto it = I.byKey.find(key);
    if (it != I.byKey.end()) return TextureHandle{it->second};  // another thread won the race
    int index = I.publish(std::move(e));
    I.byKey.emplace(key, index);
    return TextureHandle{index};
}

int TextureStore::maxSide() const { return impl_->maxSide; }
int TextureStore::width(TextureHandle h) const { return impl_->entry(h).width; }
int TextureStore::height(TextureHandle h) const { return impl_->entry(h).height; }
int TextureStore::channels(TextureHandle h) const { return impl_->entry(h).channels; }
const std::vector<float>& TextureStore::pixels(TextureHandle h) const { return impl_->entry(h).pixels; }

void TextureStore::sample(TextureHandle h, Vec2 uv, Vec2 duvdx, Vec2 duvdy, float* out, int nchannels,
                          TextureWrap wrap) const {
    const Entry& e = impl_->entry(h);
    if (nchannels <= 0) return;
    constexpr int kMaxFetch = 16;
    const int c = e.channels;
    const int fetch = std::min(std::min(c, std::max(nchannels, 1)), kMaxFetch);
    float tmp[kMaxFetch];

    OIIO::TextureOpt opt;
    opt.swrap = opt.twrap = toOiio(wrap);
    opt.mipmode = OIIO::TextureOpt::MipModeAniso;  // trilinear between levels, anisotropic along the major axis
    opt.interpmode = OIIO::TextureOpt::InterpBilinear;
    opt.fill = 0.f;
    // OIIO's t = 0 is the top row; Specula's v = 0 is the bottom row.
    const float s = uv.x, t = 1.f - uv.y;
    OIIO::TextureSystem* ts = impl_->ts;
    OIIO::TextureSystem::Perthread* pt = ts->get_perthread_info();
    if (!ts->texture(e.handle, pt, opt, s, t, duvdx.x, -duvdx.y, duvdy.x, -duvdy.y, fetch, tmp)) {
        (void)ts->geterror();
        for (int i = 0; i < fetch; ++i) tmp[i] = 0.f;
    }

    // Missing channels (i >= the texture's channel count): alpha (index 3) = 1, others = the last
    // available channel, so grey textures replicate to RGB.
    for (int i = 0; i < nchannels; ++i) out[i] = i < fetch ? tmp[i] : (i == 3 ? 1.f : tmp[fetch - 1]);
}

Color3 TextureStore::sampleRgb(TextureHandle h, Vec2 uv, Vec2 duvdx, Vec2 duvdy, TextureWrap wrap) const {
    float v[3];
    sample(h, uv, duvdx, duvdy, v, 3, wrap);
    return Color3(v[0], v[1], v[2]);
}

}  // namespace specula
