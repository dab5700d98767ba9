// Reading images through OpenImageIO safely and without waste: header checks before a decoder allocates, and pixels
// read as floats without the scratch buffer of OpenImageIO's converting read. Internal to the io module.
#pragma once

#include <OpenImageIO/imageio.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>

namespace specula {

// Writes 'data' (of 'dataType', default spec.format) as 'format' ("openexr", "png", ...) to a temporary beside
// 'path' and renames it over 'path' once complete. Its last row is read back first: neither OpenImageIO's PNG writer
// nor OpenEXR reports every failed write (a full disk, a file-size limit), and a truncated file must never take the
// name. Throws ImageIoError "cannot write <what> '<path>': ...". Internal to the io module.
void writeImageAtomic(const std::string& path, const OIIO::ImageSpec& spec, const void* data, const char* format,
                      const char* what, OIIO::TypeDesc dataType = OIIO::TypeDesc::UNKNOWN);

// Why a file would make a decoder allocate beyond what it holds, or "" when it would not. Only OpenEXR needs it: its
// header reader allocates every attribute at the size the attribute declares before reading it (a 200-byte file
// declaring a 2 GiB attribute allocates 2 GiB; under ASan that poisoning was most of fuzz_image's time). The walk
// reads each header's attribute names, types and sizes (multi-part files included) and requires every size to fit in
// the bytes left in the file. OpenEXR also sizes its line buffers by the data window when it opens a file, so every
// header's dataWindow must fit the caller's limits: at most maxSide pixels a side and maxPixels pixels.
std::string imageHeaderProblem(const std::string& path, int64_t maxSide, int64_t maxPixels);

// Why a header's claimed size cannot be what the file decodes to, or "" when it can. A file cannot decode to much
// more than its size allows: deflate (PNG, EXR zip) stops near 1032:1, and RLE, JPEG and the other EXR codecs below
// that. A header that claims more (a 111-byte TGA claiming 8294x28461 RGBA: 3.5 GiB of floats, found by fuzz_image) is
// refused before its pixels are allocated; images under 256 MiB decoded pass whatever their size, so highly
// compressible images of ordinary size still load. claimedBefore: what the file's earlier parts claim (multi-part
// files), so that the allowance holds for the whole file, not for each part.
std::string decodedSizeProblem(const std::string& path, const OIIO::ImageSpec& spec, uint64_t claimedBefore = 0);

// Reads subimage `subimage` (MIP level 0, every channel) of `in` into `out` as width × height × channels contiguous
// floats, converted from the file's own format as OpenImageIO's converting read would. Why not read_image(FLOAT)
// directly: OpenImageIO 2.4 converts through a scratch buffer of about 64 MiB whatever the image's size
// (ImageInput::read_scanlines' chunk), and under ASan poisoning that buffer took most of the image fuzzer's time
// (docs/reliability.md). Returns false with the reader's error pending, as read_image does.
bool readPixelsAsFloat(OIIO::ImageInput& in, int subimage, float* out);

// ---- the one guarded image open: every image Specula reads (ImageSet files, textures) goes through it ----

// What a header may claim before anything is allocated for its pixels.
struct ImageLimits {
    int64_t maxSide = std::numeric_limits<int64_t>::max();   // pixels along either axis
    int64_t maxPixels = std::numeric_limits<int64_t>::max(); // width x height
    int maxChannels = 1024;
    uint64_t maxFloatBytes = std::numeric_limits<uint64_t>::max();  // width x height x channels floats
    const char* what = "images";  // the plural the refusal names ("textures are limited to ...")
};

// Why one (sub)image header is refused under 'limits', or "" when it is not: an empty or volume image, a size or
// channel count beyond the limits, or more pixels than the file's size can decode to (decodedSizeProblem, with
// claimedBefore as there). The text starts with "its header claims ..." where a size is at fault.
std::string imageSpecProblem(const std::string& path, const OIIO::ImageSpec& spec, const ImageLimits& limits,
                             uint64_t claimedBefore = 0);

struct GuardedImage {
    std::unique_ptr<OIIO::ImageInput> input;  // the open reader at subimage 0; null when refused or unreadable
    bool refused = false;  // the file broke a limit (a bad input); else OpenImageIO could not open it
    std::string problem;   // why, without the file's name (the caller names it in its own error)
};
// Opens 'path' for reading: the OpenEXR attribute walk (imageHeaderProblem, bounded by limits.maxSide and
// limits.maxPixels), OpenImageIO's open with straight alpha ("oiio:UnassociatedAlpha": the file's values, unaltered),
// then imageSpecProblem on the first subimage's header.
GuardedImage openImageGuarded(const std::string& path, const ImageLimits& limits);

}  // namespace specula
