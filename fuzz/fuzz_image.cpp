// libFuzzer target: image files through the texture store (header limits, decode, colour conversion, MIP cache) and
// through readImageSet (the EXR reader of compare and the validation tools). The first byte picks the format by
// extension (PNG, EXR, PPM, HDR, TGA, TIFF, JPEG) and the colour space; the rest is the file. Only TextureError and
// ImageIoError may leave; anything else or a crash is a finding.
#include "core/color/color_config.h"
#include "core/io/image_io.h"
#include "core/texture/texture_store.h"
#include "fuzz/fuzz_common.h"

#include <cstdlib>

using namespace specula;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    static const char* kExt[] = {"png", "exr", "ppm", "hdr", "tga", "tif", "jpg"};
    // The MIP caches of the inputs go to the scratch folder (emptied every 256 inputs), not to the shared cache.
    static const bool cacheSet = ::setenv("SPECULA_CACHE_DIR", (fuzz::scratchDir() + "/cache").c_str(), 1) == 0;
    (void)cacheSet;
    static int calls = 0;
    if (++calls % 256 == 0) fuzz::clearScratch();  // MIP caches of earlier inputs
    static const std::shared_ptr<const ColorConfig> color = ColorConfig::load("builtin");
    // One per input: a store keeps every texture it loaded. Sides capped at fuzz::kFuzzTextureSide (256, a host's
    // SceneLimits cap, as in the scene and graph targets): mutants that decode to hundreds of MiB made ASan spend
    // most of the time poisoning and faulting in those buffers; the decoders run the same code on a 256² image, and
    // the refusal above the cap is a path worth fuzzing too.
    TextureStore store(color, fuzz::kFuzzTextureSide);
    // A fresh name per input: the process-wide texture system keeps what it opened by name.
    const std::string path =
        fuzz::writeScratch("image" + std::to_string(calls) + "." + kExt[data[0] % 7], data + 1, size - 1);
    try {
        TextureHandle h = store.load(path, (data[0] & 0x80) ? "sRGB - Texture" : "raw");
        (void)store.pixels(h);
    } catch (const TextureError&) {
    }
    try {
        // Pixels capped like the texture store's sides (256², not the 2^26 of compare): a valid EXR of a constant
        // colour decodes to a gigabyte from a few hundred bytes, which is legitimate but took most of a campaign.
        ImageSet set = readImageSet(path, int64_t(fuzz::kFuzzTextureSide) * fuzz::kFuzzTextureSide);
        (void)set;
    } catch (const ImageIoError&) {
    }
    return 0;
}
