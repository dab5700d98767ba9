// Image output and comparison with OpenImageIO: multi-layer float EXR, OCIO-viewed 8-bit PNG (both written
// atomically via temp file + rename), ImageSet reading by "layer." prefix, RMSE/MAE/PSNR and a diff map.
#include "core/io/image_io.h"
#include "core/io/image_read.h"

#include "core/color/color_config.h"
#include "core/util/error.h"
#include "core/util/memory_budget.h"

#include <glm/gtc/type_ptr.hpp>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <fstream>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace specula {

namespace {

constexpr const char* kChannelOrderAttr = "specula:channels";  // comma-separated channel names as written
// OIIO 2.4 does not store "oiio:*" attributes in EXR headers (and reports "Linear" for every EXR), so the
// working colorspace is also written under this name; readImageSet maps it back to "oiio:ColorSpace".
constexpr const char* kColorSpaceAttr = "specula:colorSpace";

mode_t currentUmask() {
    // Read without changing it (umask() is process-global and racy): Linux >= 4.7 reports it here.
    std::ifstream f("/proc/self/status");
    std::string line;
    while (std::getline(f, line)) {
        if (line.rfind("Umask:", 0) == 0) return mode_t(std::strtol(line.c_str() + 6, nullptr, 8));
    }
    return 022;
}

void removeQuietly(const std::string& p) {
    std::error_code ec;
    fs::remove(p, ec);
}

std::string joinNames(const std::vector<std::string>& v) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
    return s;
}

// Order of channels inside a layer: R,G,B,A / X,Y,Z,W / U,V / others in file order.
int channelRank(const std::string& c) {
    static const char* order[] = {"R", "G", "B", "A", "X", "Y", "Z", "W", "U", "V"};
    for (int i = 0; i < 10; ++i)
        if (c == order[i]) return i;
    return 100;
}

std::vector<uint8_t> quantise8(const std::vector<float>& v) {
    std::vector<uint8_t> out(v.size());
    for (size_t i = 0; i < v.size(); ++i) {
        float x = v[i];
        if (!(x > 0.f)) x = 0.f;  // also NaN -> 0
        if (x > 1.f) x = 1.f;
        out[i] = uint8_t(std::lround(x * 255.f));
    }
    return out;
}

}  // namespace

// Writes an uint8 or float image with OIIO to 'path' atomically (core/io/image_read.h).
void writeImageAtomic(const std::string& path, const OIIO::ImageSpec& spec, const void* data, const char* format,
                      const char* what, OIIO::TypeDesc dataType) {
    std::string tmp = createTempFileNear(path);
    const std::string cannot = std::string("cannot write ") + what + " '" + path + "': ";
    try {
        auto out = OIIO::ImageOutput::create(format);  // by format name: 'path' may lack an extension
        if (!out) throw ImageIoError(cannot + OIIO::geterror());
        if (!out->open(tmp, spec)) throw ImageIoError(cannot + out->geterror());
        if (!out->write_image(dataType == OIIO::TypeDesc::UNKNOWN ? spec.format : dataType, data)) {
            std::string err = out->geterror();
            out->close();
            throw ImageIoError(cannot + err);
        }
        if (!out->close()) throw ImageIoError(cannot + out->geterror());
        // Neither OpenImageIO's PNG writer nor OpenEXR reports every failed write (a full disk, a file-size limit:
        // issue 35): the last row is read back, which needs the whole file (PNG rows are sequential; an EXR's last
        // chunk is at its end), so a truncated file is an error and never takes the name.
        auto in = OIIO::ImageInput::open(tmp);
        std::vector<float> row(size_t(spec.width) * size_t(std::max(spec.nchannels, 1)));
        const bool whole = in && in->spec().width == spec.width && in->spec().height == spec.height &&
                           in->read_scanlines(0, 0, spec.height - 1, spec.height, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT,
                                              row.data());
        if (in) in->close();
        if (!whole) throw ImageIoError(cannot + "the file written is incomplete (is the disk full?)");
    } catch (...) {
        removeQuietly(tmp);
        throw;
    }
    commitTempFile(tmp, path);
}


const AovBuffer* ImageSet::find(const std::string& name) const {
    for (const auto& a : aovs)
        if (a.name == name) return &a;
    return nullptr;
}

// ---- atomic files ---------------------------------------------------------------------------------

std::string createTempFileNear(const std::string& path) {
    fs::path p(path);
    fs::path dir = p.parent_path();
    if (dir.empty()) dir = ".";
    std::string stem = p.stem().string();
    std::string ext = p.extension().string();
    std::string tmpl = (dir / ("." + stem + ".tmp-XXXXXX" + ext)).string();
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back('\0');
    int fd = mkstemps(buf.data(), int(ext.size()));
    if (fd < 0)
        throw ImageIoError("cannot create a file in '" + dir.string() + "' (for '" + path + "'): " +
                           std::strerror(errno));
    // mkstemps creates the file 0600; give it the permissions a normal open() would.
    fchmod(fd, 0666 & ~currentUmask());
    ::close(fd);
    return std::string(buf.data());
}

void commitTempFile(const std::string& tmpPath, const std::string& path) {
    int fd = ::open(tmpPath.c_str(), O_RDONLY);
    if (fd >= 0) {
        ::fsync(fd);
        ::close(fd);
    }
    if (std::rename(tmpPath.c_str(), path.c_str()) != 0) {
        int e = errno;
        removeQuietly(tmpPath);
        throw ImageIoError("cannot rename '" + tmpPath + "' to '" + path + "': " + std::strerror(e));
    }
}

void writeFileAtomic(const std::string& path, const std::string& bytes) {
    std::string tmp = createTempFileNear(path);
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        f.write(bytes.data(), std::streamsize(bytes.size()));
        f.flush();
        if (!f) {
            removeQuietly(tmp);
            throw ImageIoError("cannot write '" + path + "' (temp '" + tmp + "')");
        }
    }
    commitTempFile(tmp, path);
}

// ---- EXR ------------------------------------------------------------------------------------------

void writeExr(const std::string& path, const ImageSet& images, const ColorConfig& color) {
    const int w = images.width, h = images.height;
    if (w <= 0 || h <= 0) throw ImageIoError("cannot write '" + path + "': empty image");
    if (images.aovs.empty()) throw ImageIoError("cannot write '" + path + "': no AOVs");
    const size_t npix = size_t(w) * size_t(h);

    std::vector<std::string> names;
    std::set<std::string> seen;
    int alphaChannel = -1;
    for (const auto& aov : images.aovs) {
        if (aov.channels() <= 0) throw ImageIoError("cannot write '" + path + "': AOV '" + aov.name + "' has no channels");
        if (aov.pixels.size() != npix * size_t(aov.channels()))
            throw ImageIoError("cannot write '" + path + "': AOV '" + aov.name + "' has " +
                               std::to_string(aov.pixels.size()) + " floats, expected " +
                               std::to_string(npix * size_t(aov.channels())));
        for (const auto& c : aov.channelNames) {
            std::string n = aov.name == "beauty" ? c : aov.name + "." + c;
            if (!seen.insert(n).second) throw ImageIoError("cannot write '" + path + "': duplicate channel '" + n + "'");
            if (aov.name == "beauty" && c == "A") alphaChannel = int(names.size());
            names.push_back(n);
        }
    }
    const int nch = int(names.size());

    std::vector<float> data(npix * size_t(nch));
    int off = 0;
    for (const auto& aov : images.aovs) {
        const int c = aov.channels();
        for (size_t i = 0; i < npix; ++i)
            std::copy_n(&aov.pixels[i * size_t(c)], c, &data[i * size_t(nch) + size_t(off)]);
        off += c;
    }

    OIIO::ImageSpec spec(w, h, nch, OIIO::TypeDesc::FLOAT);
    spec.channelnames = names;
    spec.alpha_channel = alphaChannel;
    spec.z_channel = -1;
    spec.attribute("compression", "zip");
    for (const auto& [k, v] : images.metadata) spec.attribute(k, v);
    // glm's column-major storage of M is the row-major storage of M's transpose: Imath's row-vector matrix.
    // OpenImageIO's names for the standard ones are "worldtocamera" and "worldtoNDC" (its "worldtoscreen" is another).
    for (const auto& [k, m] : images.matrices)
        spec.attribute(k == "worldToCamera" ? "worldtocamera" : k == "worldToNDC" ? "worldtoNDC" : k, OIIO::TypeMatrix44,
                       glm::value_ptr(m));
    spec.attribute("oiio:ColorSpace", color.workingSpace());
    spec.attribute(kColorSpaceAttr, color.workingSpace());
    bool commaFree = std::none_of(names.begin(), names.end(), [](const std::string& n) {
        return n.find(',') != std::string::npos;
    });
    if (commaFree) {
        std::string order;
        for (size_t i = 0; i < names.size(); ++i) order += (i ? "," : "") + names[i];
        spec.attribute(kChannelOrderAttr, order);
    }
    writeImageAtomic(path, spec, data.data(), "openexr", "EXR");
}

// ---- PNG ------------------------------------------------------------------------------------------

void writePng(const std::string& path, const ImageSet& images, const ColorConfig& color, const std::string& view,
              float exposureStops) {
    const AovBuffer* beauty = images.find("beauty");
    if (!beauty && !images.aovs.empty()) beauty = &images.aovs.front();
    if (!beauty) throw ImageIoError("cannot write '" + path + "': no beauty AOV");
    const int w = images.width, h = images.height;
    const size_t npix = size_t(w) * size_t(h);
    const int c = beauty->channels();
    if (w <= 0 || h <= 0 || c <= 0 || beauty->pixels.size() != npix * size_t(c))
        throw ImageIoError("cannot write '" + path + "': beauty AOV size does not match the image");

    auto idx = [&](const char* n) {
        for (int i = 0; i < c; ++i)
            if (beauty->channelNames[size_t(i)] == n) return i;
        return -1;
    };
    int ir = idx("R"), ig = idx("G"), ib = idx("B"), ia = idx("A");
    if (ir < 0 || ig < 0 || ib < 0) {  // not named RGB: first three channels, or grey
        ir = 0;
        ig = std::min(1, c - 1);
        ib = std::min(2, c - 1);
        if (c == 2 || c == 4) ia = c - 1;
        if (c == 2) ig = ib = 0;
    }
    const bool hasAlpha = ia >= 0;

    std::vector<float> rgb(npix * 3);
    std::vector<float> alpha(hasAlpha ? npix : 0);
    for (size_t i = 0; i < npix; ++i) {
        const float* p = &beauty->pixels[i * size_t(c)];
        float a = hasAlpha ? p[ia] : 1.f;
        // The beauty is premultiplied; PNG stores unassociated colour.
        float inv = (hasAlpha && a > 0.f) ? 1.f / a : 1.f;
        rgb[i * 3 + 0] = p[ir] * inv;
        rgb[i * 3 + 1] = p[ig] * inv;
        rgb[i * 3 + 2] = p[ib] * inv;
        if (hasAlpha) alpha[i] = a;
    }
    try {
        color.toDisplay(rgb.data(), npix, view, exposureStops);
    } catch (const ColorError& e) {
        throw ImageIoError("cannot write '" + path + "': " + e.what());
    }

    const int outc = hasAlpha ? 4 : 3;
    std::vector<float> packed(npix * size_t(outc));
    for (size_t i = 0; i < npix; ++i) {
        for (int k = 0; k < 3; ++k) packed[i * size_t(outc) + size_t(k)] = rgb[i * 3 + size_t(k)];
        if (hasAlpha) packed[i * 4 + 3] = alpha[i];
    }
    std::vector<uint8_t> bytes = quantise8(packed);

    OIIO::ImageSpec spec(w, h, outc, OIIO::TypeDesc::UINT8);
    if (hasAlpha) {
        spec.alpha_channel = 3;
        spec.attribute("oiio:UnassociatedAlpha", 1);
    }
    spec.attribute("oiio:ColorSpace", "sRGB");
    spec.attribute("Software", std::string("Specula ") +
#ifdef SPECULA_VERSION
                                   SPECULA_VERSION
#else
                                   ""
#endif
    );
    for (const auto& [k, v] : images.metadata) spec.attribute(k, v);
    writeImageAtomic(path, spec, bytes.data(), "png", "PNG");
}

// ---- reading --------------------------------------------------------------------------------------

std::string imageHeaderProblem(const std::string& path, int64_t maxSide, int64_t maxPixels) {
    std::ifstream f(path, std::ios::binary);
    unsigned char head[8];
    if (!f.read(reinterpret_cast<char*>(head), 8)) return "";  // unreadable or short: the decoder says so
    if (!(head[0] == 0x76 && head[1] == 0x2f && head[2] == 0x31 && head[3] == 0x01)) return "";  // not OpenEXR
    std::error_code ec;
    const uint64_t fileBytes = fs::file_size(path, ec);
    if (ec) return "";
    const bool multipart = (head[5] & 0x10) != 0;  // version field bit 12 (OpenEXR file layout: "multi-part")
    // Names and type names are at most 255 bytes (long-name files); anything else is malformed, which the decoder
    // reports itself.
    auto readString = [&](std::string& s) {
        s.clear();
        char c;
        while (f.get(c)) {
            if (c == '\0') return true;
            if (s.size() >= 255) return false;
            s.push_back(c);
        }
        return false;
    };
    std::string name, type;
    for (int attributes = 0; attributes < (1 << 16); ++attributes) {  // bounded walk
        if (!readString(name)) return "";
        if (name.empty()) {  // end of a header; a multi-part file's list of headers ends with an empty one
            if (!multipart || f.peek() == 0 || f.peek() == std::char_traits<char>::eof()) return "";
            continue;
        }
        unsigned char b[4];
        if (!readString(type) || !f.read(reinterpret_cast<char*>(b), 4)) return "";
        const int64_t size = int32_t(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24);
        const std::streamoff pos = f.tellg();
        if (pos < 0) return "";
        const uint64_t left = fileBytes > uint64_t(pos) ? fileBytes - uint64_t(pos) : 0;
        if (size < 0 || uint64_t(size) > left)
            return "its OpenEXR header's attribute '" + name + "' (" + type + ") declares " + std::to_string(size) +
                   " bytes, but only " + std::to_string(left) + " bytes follow in the file";
        // OpenEXR reads a value of a fixed-size type at its type's size, whatever size the attribute declares, and
        // the next attribute from there: a declared size that differs would put the decoder out of step with this
        // walk (fuzz_merge: a float attribute declaring 0 bytes), so it is refused.
        static const std::map<std::string, int64_t> fixedSizes = {
            {"box2i", 16}, {"box2f", 16}, {"int", 4}, {"float", 4}, {"double", 8}, {"v2i", 8}, {"v2f", 8}, {"v2d", 16},
            {"v3i", 12}, {"v3f", 12}, {"v3d", 24}, {"m33f", 36}, {"m33d", 72}, {"m44f", 64}, {"m44d", 128},
            {"compression", 1}, {"lineOrder", 1}, {"envmap", 1}, {"deepImageState", 1}, {"chromaticities", 32},
            {"keycode", 28}, {"timecode", 8}, {"rational", 8}, {"tiledesc", 9}};
        if (const auto fixed = fixedSizes.find(type); fixed != fixedSizes.end() && fixed->second != size)
            return "its OpenEXR header's attribute '" + name + "' (" + type + ") declares " + std::to_string(size) +
                   " bytes; a " + type + " takes " + std::to_string(fixed->second);
        if (type == "chlist") {
            // OpenEXR reads a channel list entry by entry (a name, then 16 bytes) up to an empty name, whatever size
            // the attribute declares, and reads the next attribute from where the list ended: a list that does not
            // end exactly at its declared size would put the decoder's reading out of step with this walk (a fuzzed
            // 772-byte piece then had it allocate 2 GB for a string). Such a list is refused (issue 35).
            int64_t used = 0;
            std::string channel;
            for (;;) {
                if (!readString(channel)) return "its OpenEXR header's channel list is malformed (a name longer than 255 bytes or cut off)";
                used += int64_t(channel.size()) + 1;
                if (channel.empty()) break;
                if (!f.seekg(16, std::ios::cur) || used + 16 > size) break;
                used += 16;
            }
            if (used != size)
                return "its OpenEXR header's channel list '" + name + "' declares " + std::to_string(size) +
                       " bytes but its entries take " + (used > size ? "more" : std::to_string(used));
            continue;
        }
        if (type == "preview") {
            // A preview image is allocated at the width x height its first 8 bytes declare, before its pixels are read.
            unsigned char wh[8];
            if (size < 8 || !f.read(reinterpret_cast<char*>(wh), 8)) return "its OpenEXR header's preview is cut off";
            const uint64_t pw = uint32_t(wh[0]) | uint32_t(wh[1]) << 8 | uint32_t(wh[2]) << 16 | uint32_t(wh[3]) << 24;
            const uint64_t ph = uint32_t(wh[4]) | uint32_t(wh[5]) << 8 | uint32_t(wh[6]) << 16 | uint32_t(wh[7]) << 24;
            if (pw * ph * 4 + 8 != uint64_t(size))
                return "its OpenEXR header's preview declares " + std::to_string(pw) + "x" + std::to_string(ph) +
                       " pixels in an attribute of " + std::to_string(size) + " bytes";
            f.seekg(std::streamoff(size - 8), std::ios::cur);
            continue;
        }
        if (name == "dataWindow" && type == "box2i" && size == 16) {
            // OpenEXR sizes its line buffers by the data window when it opens the file (a 215-byte file declaring
            // 16794113x1 half RGB pixels asks for 16 lines of 100 MB each, by our count, for ZIP), so the caller's
            // size limits are applied here, before it.
            unsigned char w[16];
            if (!f.read(reinterpret_cast<char*>(w), 16)) return "";
            auto at = [&](int i) {
                return int64_t(int32_t(uint32_t(w[i]) | uint32_t(w[i + 1]) << 8 | uint32_t(w[i + 2]) << 16 |
                                       uint32_t(w[i + 3]) << 24));
            };
            const int64_t width = at(8) - at(0) + 1, height = at(12) - at(4) + 1;  // each within ±2^32: no overflow
            if (width > 0 && height > 0 && (width > maxSide || height > maxSide || width > maxPixels / height))
                return "its OpenEXR header declares " + std::to_string(width) + "x" + std::to_string(height) +
                       " pixels (dataWindow), beyond the limit of " +
                       (maxSide < maxPixels ? std::to_string(maxSide) + " pixels a side"
                                            : std::to_string(maxPixels) + " pixels");
            continue;
        }
        f.seekg(std::streamoff(size), std::ios::cur);
    }
    return "";
}

std::string decodedSizeProblem(const std::string& path, const OIIO::ImageSpec& spec, uint64_t claimedBefore) {
    const uint64_t w = uint64_t(std::max(spec.width, 0)), h = uint64_t(std::max(spec.height, 0));
    const uint64_t c = uint64_t(std::max(spec.nchannels, 0)), d = uint64_t(std::max(spec.depth, 1));
    std::error_code ec;
    const uint64_t fileBytes = fs::file_size(path, ec);
    // Each factor is below 2^31 and the callers bound depth and channels first: no overflow.
    const uint64_t partBytes = w * h * d * c * uint64_t(std::max<size_t>(spec.format.size(), 1));
    const uint64_t decodedBytes = claimedBefore + partBytes;
    constexpr uint64_t kMaxCompression = 2048, kAlwaysDecodable = uint64_t(256) << 20;
    if (ec || decodedBytes <= kAlwaysDecodable || decodedBytes / kMaxCompression <= fileBytes) return "";
    return "its header claims " + std::to_string(w) + "x" + std::to_string(h) + " pixels, " + std::to_string(c) +
           " channels (" + formatBytes(partBytes) + " decoded" +
           (claimedBefore ? ", " + formatBytes(decodedBytes) + " with the parts before it" : std::string()) +
           ") from a file of " + formatBytes(fileBytes) +
           ", more than any image compression gives (" + std::to_string(kMaxCompression) +
           ":1): the file is truncated or damaged";
}

std::string imageSpecProblem(const std::string& path, const OIIO::ImageSpec& spec, const ImageLimits& limits,
                             uint64_t claimedBefore) {
    const uint64_t w = uint64_t(std::max(spec.width, 0)), h = uint64_t(std::max(spec.height, 0));
    const uint64_t c = uint64_t(std::max(spec.nchannels, 0));
    const std::string claim = std::to_string(w) + "x" + std::to_string(h) + " pixels, " + std::to_string(c) + " channels";
    if (spec.depth > 1) return "it is a volume image (depth " + std::to_string(spec.depth) + "); volume images are not supported";
    if (w == 0 || h == 0 || c == 0) return "its header claims an empty image (" + claim + ")";
    // Each factor is below 2^31: no overflow.
    const uint64_t floatBytes = w * h * c * sizeof(float);
    if (w > uint64_t(limits.maxSide) || h > uint64_t(limits.maxSide) || w * h > uint64_t(limits.maxPixels) ||
        c > uint64_t(limits.maxChannels) || floatBytes > limits.maxFloatBytes) {
        std::string bounds;
        if (limits.maxSide < std::numeric_limits<int64_t>::max())
            bounds += std::to_string(limits.maxSide) + " pixels a side, ";
        if (limits.maxPixels / std::max<int64_t>(limits.maxSide, 1) < limits.maxSide)  // a bound beyond side x side
            bounds += std::to_string(limits.maxPixels) + " pixels, ";
        bounds += std::to_string(limits.maxChannels) + " channels";
        if (limits.maxFloatBytes < std::numeric_limits<uint64_t>::max())
            bounds += " and " + formatBytes(limits.maxFloatBytes) + " of float pixels";
        return "its header claims " + claim + " (" + formatBytes(floatBytes) + " as floats); " + limits.what +
               " are limited to " + bounds;
    }
    return decodedSizeProblem(path, spec, claimedBefore);
}

GuardedImage openImageGuarded(const std::string& path, const ImageLimits& limits) {
    GuardedImage g;
    g.problem = imageHeaderProblem(path, limits.maxSide, limits.maxPixels);
    if (!g.problem.empty()) {
        g.refused = true;
        return g;
    }
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);  // the file's values, unaltered (colour converts unpremultiplied)
    g.input = OIIO::ImageInput::open(path, &config);
    if (!g.input) {
        g.problem = OIIO::geterror();
        return g;
    }
    // Before the pixels: a 300-byte file may claim 100000x100000.
    g.problem = imageSpecProblem(path, g.input->spec(), limits);
    if (!g.problem.empty()) {
        g.refused = true;
        g.input.reset();
    }
    return g;
}

bool readPixelsAsFloat(OIIO::ImageInput& in, int subimage, float* out) {
    if (!in.seek_subimage(subimage, 0)) return false;
    const OIIO::ImageSpec spec = in.spec();
    // TypeUnknown, not the file's format by name: OpenImageIO 2.4.7 reads straight into the caller's buffer only then.
    if (spec.format == OIIO::TypeDesc::FLOAT && spec.channelformats.empty())
        return in.read_image(subimage, 0, 0, spec.nchannels, OIIO::TypeUnknown, out);
    if (!spec.channelformats.empty())  // mixed channel formats (rare): OpenImageIO's converting read
        return in.read_image(subimage, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, out);
    const size_t values = size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels);
    // Not value-initialised (see readImageSet): a truncated file fails the read before anything is converted.
    const std::unique_ptr<unsigned char[]> native(new unsigned char[values * spec.format.size()]);
    if (!in.read_image(subimage, 0, 0, spec.nchannels, OIIO::TypeUnknown, native.get())) return false;
    const size_t step = size_t(1) << 30;  // convert_pixel_values counts in an int
    for (size_t i = 0; i < values; i += step)
        if (!OIIO::convert_pixel_values(spec.format, native.get() + i * spec.format.size(), OIIO::TypeDesc::FLOAT,
                                        out + i, int(std::min(step, values - i))))
            return false;
    return true;
}

ImageSet readImageSet(const std::string& path, int64_t maxPixels) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw ImageIoError("image file not found: '" + path + "'");
    // The header decides the allocation, so it is bounded first: no image this program writes or compares is larger
    // than the renderer's 2^26 pixels, and none has more than 1024 channels.
    ImageLimits limits;
    limits.maxSide = limits.maxPixels = maxPixels;
    limits.maxChannels = 1024;
    GuardedImage guarded = openImageGuarded(path, limits);
    if (!guarded.input) throw ImageIoError("cannot read image '" + path + "': " + guarded.problem);
    const std::unique_ptr<OIIO::ImageInput>& in = guarded.input;

    ImageSet set;
    struct Chan {
        std::string layer, name;
        const float* src;
        int stride;
    };
    // Not value-initialised: a header may claim up to 2^26 pixels of a file that then turns out truncated, and only the
    // pages the decoder writes should cost anything.
    std::vector<std::unique_ptr<float[]>> buffers;
    std::vector<Chan> chans;
    std::vector<std::string> fileOrder;  // full channel names, as written (if recorded)

    // Pass 1: every part's header, bounded before any pixel is allocated. The claims add up over the parts: a multi-part
    // file of parts that each claim 128 MiB passed a per-part check, however many parts it declared, and fuzz_image's
    // resident memory grew past a gigabyte on such files.
    std::vector<int> parts;  // the subimages of the first part's size, read in pass 2
    uint64_t claimedBytes = 0, floatBytes = 0, largestNative = 0;
    for (int sub = 0; in->seek_subimage(sub, 0); ++sub) {
        const OIIO::ImageSpec& spec = in->spec();
        if (sub == 0) {
            set.width = spec.width;
            set.height = spec.height;
            for (const auto& p : spec.extra_attribs) {
                if (p.type() == OIIO::TypeMatrix44) {
                    Mat4 m;
                    std::memcpy(glm::value_ptr(m), p.data(), sizeof m);
                    set.matrices[p.name().string()] = m;
                    continue;
                }
                if (p.type() != OIIO::TypeString) continue;
                std::string key = p.name().string();
                if (key == kChannelOrderAttr) {
                    std::string v = p.get_string();
                    std::stringstream ss(v);
                    std::string item;
                    while (std::getline(ss, item, ',')) fileOrder.push_back(item);
                    continue;
                }
                set.metadata[key] = p.get_string();
            }
            auto cs = set.metadata.find(kColorSpaceAttr);
            if (cs != set.metadata.end()) set.metadata["oiio:ColorSpace"] = cs->second;
        } else if (spec.width != set.width || spec.height != set.height) {
            continue;  // parts of another size cannot live in one ImageSet
        }
        if (const std::string problem = imageSpecProblem(path, spec, limits, claimedBytes); !problem.empty())
            throw ImageIoError("cannot read '" + path + "': " + problem);
        const uint64_t values = uint64_t(spec.width) * uint64_t(spec.height) * uint64_t(spec.nchannels);
        claimedBytes += values * uint64_t(std::max<size_t>(spec.format.size(), 1));
        floatBytes += values * sizeof(float);
        largestNative = std::max(largestNative, values * uint64_t(spec.format.size()));
        parts.push_back(sub);
    }
    // Every part's floats stay until the channels are gathered, and one part's native pixels are held while it converts.
    const MemoryBudget budget = memoryBudget();
    if (floatBytes + largestNative > budget.availableBytes)
        throw ImageIoError("cannot read '" + path + "': its " + std::to_string(parts.size()) + " part(s) need about " +
                           formatBytes(floatBytes + largestNative) + " to read, but " +
                           formatBytes(budget.availableBytes) + " are left under " + budget.limitedBy);

    // Pass 2: the pixels.
    for (const int sub : parts) {
        if (!in->seek_subimage(sub, 0)) throw ImageIoError("cannot read image '" + path + "': " + in->geterror());
        const OIIO::ImageSpec spec = in->spec();
        std::string partName = sub > 0 ? std::string(spec.get_string_attribute("name")) : std::string();
        buffers.emplace_back(new float[size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels)]);
        if (!readPixelsAsFloat(*in, sub, buffers.back().get()))
            throw ImageIoError("cannot read image '" + path + "': " + in->geterror());
        for (int ch = 0; ch < spec.nchannels; ++ch) {
            std::string full = ch < int(spec.channelnames.size()) ? spec.channelnames[size_t(ch)]
                                                                   : "channel" + std::to_string(ch);
            Chan c{"", "", buffers.back().get() + ch, spec.nchannels};
            auto dot = full.rfind('.');
            if (dot != std::string::npos && dot > 0 && dot + 1 < full.size()) {
                c.layer = full.substr(0, dot);
                c.name = full.substr(dot + 1);
                if (!partName.empty()) c.layer = partName + "." + c.layer;
            } else if (!partName.empty()) {
                c.layer = partName;
                c.name = full;
            } else if (full == "R" || full == "G" || full == "B" || full == "A" || full == "Y") {
                c.layer = "beauty";
                c.name = full;
            } else if (full == "Z") {
                c.layer = "depth";
                c.name = "Z";
            } else {
                c.layer = full;
                c.name = full;
            }
            chans.push_back(c);
        }
    }
    in->close();
    if (set.width <= 0 || set.height <= 0 || chans.empty())
        throw ImageIoError("cannot read image '" + path + "': no pixels");

    // Channel order: as recorded by writeExr if it matches, else beauty first, layers by first
    // appearance, channels inside a layer R,G,B,A / X,Y,Z / U,V / others.
    auto fullName = [](const Chan& c) { return c.layer == "beauty" ? c.name : c.layer + "." + c.name; };
    bool useRecorded = fileOrder.size() == chans.size();
    if (useRecorded) {
        std::vector<Chan> ordered;
        for (const auto& n : fileOrder) {
            auto it = std::find_if(chans.begin(), chans.end(), [&](const Chan& c) { return fullName(c) == n; });
            if (it == chans.end()) {
                useRecorded = false;
                break;
            }
            ordered.push_back(*it);
        }
        if (useRecorded) chans = ordered;
    }
    if (!useRecorded) {
        std::vector<std::string> layers;
        for (const auto& c : chans)
            if (std::find(layers.begin(), layers.end(), c.layer) == layers.end()) layers.push_back(c.layer);
        auto beautyIt = std::find(layers.begin(), layers.end(), "beauty");
        if (beautyIt != layers.end()) std::rotate(layers.begin(), beautyIt, beautyIt + 1);
        std::vector<Chan> ordered;
        for (const auto& l : layers) {
            std::vector<Chan> group;
            for (const auto& c : chans)
                if (c.layer == l) group.push_back(c);
            std::stable_sort(group.begin(), group.end(),
                             [](const Chan& a, const Chan& b) { return channelRank(a.name) < channelRank(b.name); });
            ordered.insert(ordered.end(), group.begin(), group.end());
        }
        chans = ordered;
    }

    const size_t npix = size_t(set.width) * size_t(set.height);
    for (size_t i = 0; i < chans.size();) {
        size_t j = i;
        while (j < chans.size() && chans[j].layer == chans[i].layer) ++j;
        AovBuffer aov;
        aov.name = chans[i].layer;
        const size_t n = j - i;
        for (size_t k = i; k < j; ++k) aov.channelNames.push_back(chans[k].name);
        aov.pixels.resize(npix * n);
        for (size_t p = 0; p < npix; ++p)
            for (size_t k = 0; k < n; ++k) aov.pixels[p * n + k] = chans[i + k].src[p * size_t(chans[i + k].stride)];
        set.aovs.push_back(std::move(aov));
        i = j;
    }
    return set;
}

// ---- comparison -----------------------------------------------------------------------------------

namespace {

std::vector<std::string> aovNames(const ImageSet& s) {
    std::vector<std::string> v;
    for (const auto& a : s.aovs) v.push_back(a.name);
    return v;
}

double meanOf(const OIIO::ImageBuf& buf) {
    auto stats = OIIO::ImageBufAlgo::computePixelStats(buf);
    if (stats.avg.empty()) return std::numeric_limits<double>::quiet_NaN();
    double s = 0;
    for (float a : stats.avg) s += a;
    return s / double(stats.avg.size());
}

// Renders 'text' in white on a dark strip of width w; false if OIIO cannot render text (no font).
bool renderTextStrip(const std::string& text, int w, OIIO::ImageBuf& strip) {
    const int fontSize = 13, h = 18;
    for (const char* font : {"", "DejaVuSans", "DejaVuSansMono", "LiberationSans-Regular", "FreeSans"}) {
        OIIO::ImageBuf buf(OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::FLOAT));
        const float bg[3] = {0.08f, 0.08f, 0.08f};
        OIIO::ImageBufAlgo::fill(buf, bg);
        const float white[3] = {1.f, 1.f, 1.f};
        if (OIIO::ImageBufAlgo::render_text(buf, 3, h - 5, text, fontSize, font, white)) {
            strip = std::move(buf);
            return true;
        }
        (void)buf.geterror();  // clear the error
    }
    (void)OIIO::geterror();
    return false;
}

void writeDiffPng(const std::string& diffPng, const AovBuffer& a, const AovBuffer& b, int w, int h) {
    const size_t npix = size_t(w) * size_t(h);
    const int c = a.channels();
    std::vector<float> d(npix);
    for (size_t i = 0; i < npix; ++i) {
        double s = 0;
        for (int k = 0; k < c; ++k) s += std::fabs(double(a.pixels[i * size_t(c) + size_t(k)]) -
                                                   double(b.pixels[i * size_t(c) + size_t(k)]));
        float v = float(s / c);
        d[i] = std::isfinite(v) ? v : 0.f;
    }
    std::vector<float> sorted = d;
    float maxV = sorted.empty() ? 0.f : *std::max_element(sorted.begin(), sorted.end());
    size_t k99 = sorted.empty() ? 0 : std::min(sorted.size() - 1, size_t(std::ceil(0.99 * double(sorted.size()))) - 1);
    float p99 = 0.f;
    if (!sorted.empty()) {
        std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(k99), sorted.end());
        p99 = sorted[k99];
    }
    float scale = p99 > 0.f ? p99 : (maxV > 0.f ? maxV : 1.f);

    const int gap = 2;
    const int barH = std::clamp(h / 12, 6, 24);
    const int totalH = h + gap + barH;
    OIIO::ImageBuf norm(OIIO::ImageSpec(w, totalH, 1, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float v = std::min(d[size_t(y) * size_t(w) + size_t(x)] / scale, 1.f);
            norm.setpixel(x, y, &v, 1);
        }
    for (int y = h; y < totalH; ++y)
        for (int x = 0; x < w; ++x) {
            float v = w > 1 ? float(x) / float(w - 1) : 1.f;
            norm.setpixel(x, y, &v, 1);
        }
    OIIO::ImageBuf mapped = OIIO::ImageBufAlgo::color_map(norm, 0, "viridis");
    if (mapped.has_error()) throw ImageIoError("cannot write diff map '" + diffPng + "': " + mapped.geterror());
    const float black[3] = {0.f, 0.f, 0.f};
    OIIO::ImageBufAlgo::fill(mapped, black, OIIO::ROI(0, w, h, h + gap, 0, 1, 0, 3));

    // Optional caption: the value the top of the bar stands for, and the max difference.
    char caption[160];
    std::snprintf(caption, sizeof caption, "bar 0..%.3g (%s)  max %.3g", double(scale),
                  p99 > 0.f ? "p99" : "max", double(maxV));
    OIIO::ImageBuf strip;
    OIIO::ImageBuf out = mapped;
    if (w >= 48 && renderTextStrip(caption, w, strip)) {
        int sh = strip.spec().height;
        OIIO::ImageBuf both(OIIO::ImageSpec(w, totalH + sh, 3, OIIO::TypeDesc::FLOAT));
        OIIO::ImageBufAlgo::paste(both, 0, 0, 0, 0, mapped);
        OIIO::ImageBufAlgo::paste(both, 0, totalH, 0, 0, strip);
        out = std::move(both);
    }

    const OIIO::ImageSpec& os = out.spec();
    std::vector<float> px(size_t(os.width) * size_t(os.height) * 3);
    out.get_pixels(OIIO::ROI(0, os.width, 0, os.height, 0, 1, 0, 3), OIIO::TypeDesc::FLOAT, px.data());
    std::vector<uint8_t> bytes = quantise8(px);
    OIIO::ImageSpec spec(os.width, os.height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    spec.attribute("specula:diffScale", scale);
    spec.attribute("specula:diffMax", maxV);
    writeImageAtomic(diffPng, spec, bytes.data(), "png", "diff PNG");
}

}  // namespace

CompareResult compareImages(const std::string& pathA, const std::string& pathB, const std::string& aov,
                            const std::string& diffPng) {
    std::error_code ec;
    for (const auto& p : {pathA, pathB})
        if (!fs::exists(p, ec)) throw ImageIoError("compare: image file not found: '" + p + "'");
    ImageSet A = readImageSet(pathA);
    ImageSet B = readImageSet(pathB);
    const AovBuffer* a = A.find(aov);
    const AovBuffer* b = B.find(aov);
    if (!a) throw ImageIoError("compare: AOV '" + aov + "' not in '" + pathA + "'; available: " + joinNames(aovNames(A)));
    if (!b) throw ImageIoError("compare: AOV '" + aov + "' not in '" + pathB + "'; available: " + joinNames(aovNames(B)));
    if (A.width != B.width || A.height != B.height) {
        std::ostringstream ss;
        ss << "compare: size mismatch for AOV '" << aov << "': '" << pathA << "' is " << A.width << "x" << A.height
           << ", '" << pathB << "' is " << B.width << "x" << B.height;
        throw ImageIoError(ss.str());
    }
    // Channels by name: an RGBA image against an RGB one compares R, G and B and says that A was left out.
    std::vector<std::string> compared, ignored;
    std::vector<std::pair<int, int>> pairs;
    for (int i = 0; i < a->channels(); ++i) {
        auto it = std::find(b->channelNames.begin(), b->channelNames.end(), a->channelNames[size_t(i)]);
        if (it == b->channelNames.end()) {
            ignored.push_back(a->channelNames[size_t(i)] + " (only in '" + pathA + "')");
            continue;
        }
        compared.push_back(a->channelNames[size_t(i)]);
        pairs.emplace_back(i, int(it - b->channelNames.begin()));
    }
    for (const std::string& n : b->channelNames)
        if (std::find(a->channelNames.begin(), a->channelNames.end(), n) == a->channelNames.end())
            ignored.push_back(n + " (only in '" + pathB + "')");
    if (pairs.empty())
        throw ImageIoError("compare: AOV '" + aov + "' has no channel in common: '" + pathA + "' has " +
                           joinNames(a->channelNames) + ", '" + pathB + "' has " + joinNames(b->channelNames));
    AovBuffer commonA, commonB;
    if (!ignored.empty() || a->channelNames != b->channelNames) {
        const size_t npix = size_t(A.width) * size_t(A.height);
        for (auto [buf, src, pick] : {std::tuple{&commonA, a, 0}, std::tuple{&commonB, b, 1}}) {
            buf->name = aov;
            buf->channelNames = compared;
            buf->pixels.resize(npix * pairs.size());
            for (size_t px = 0; px < npix; ++px)
                for (size_t k = 0; k < pairs.size(); ++k)
                    buf->pixels[px * pairs.size() + k] =
                        src->pixels[px * size_t(src->channels()) + size_t(pick ? pairs[k].second : pairs[k].first)];
        }
        a = &commonA;
        b = &commonB;
    }

    const int w = A.width, h = A.height, c = a->channels();
    // NaN or Inf make every metric undefined (OpenImageIO's RMSE became nan, printed as "PSNR inf" and the invalid JSON
    // token nan): refuse, naming the file, the count and the first pixel.
    for (auto [buf, path] : {std::pair{a, &pathA}, std::pair{b, &pathB}}) {
        size_t bad = 0, first = 0;
        for (size_t i = 0; i < buf->pixels.size(); ++i)
            if (!std::isfinite(buf->pixels[i]) && bad++ == 0) first = i / size_t(c);
        if (bad)
            throw Error(ErrorCode::BadInput, "", "compare: '" + *path + "' has " + std::to_string(bad) + " NaN or infinite values in AOV '" +
                                     aov + "' (the first at pixel " + std::to_string(first % size_t(w)) + "," +
                                     std::to_string(first / size_t(w)) + "): RMSE, MAE and PSNR are undefined");
    }
    OIIO::ImageSpec spec(w, h, c, OIIO::TypeDesc::FLOAT);
    OIIO::ImageBuf bufA(spec, const_cast<float*>(a->pixels.data()));
    OIIO::ImageBuf bufB(spec, const_cast<float*>(b->pixels.data()));
    // Thresholds at +max: OIIO 2.4 flags 'error' whenever a pixel exceeds the fail threshold.
    const float never = std::numeric_limits<float>::max();
    OIIO::ImageBufAlgo::CompareResults cr = OIIO::ImageBufAlgo::compare(bufA, bufB, never, never);
    if (cr.error) throw ImageIoError("compare: OpenImageIO failed: " + bufA.geterror() + bufB.geterror());

    CompareResult r;
    r.width = w;
    r.height = h;
    r.channels = c;
    r.compared = compared;
    r.ignored = ignored;
    r.rmse = cr.rms_error;
    r.mae = cr.meanerror;
    // PSNR against the reference's own peak (its largest value in the compared AOV), not 1.0: scene-linear HDR data
    // has no unit peak (issue 16). A reference without a positive value falls back to 1.
    double peak = 0.0;
    for (float v : b->pixels) peak = std::max(peak, double(v));
    r.peak = peak > 0.0 ? peak : 1.0;
    r.psnr = r.rmse > 0 ? 20.0 * std::log10(r.peak / r.rmse) : std::numeric_limits<double>::infinity();
    r.meanA = meanOf(bufA);
    r.meanB = meanOf(bufB);
    if (!diffPng.empty()) writeDiffPng(diffPng, *a, *b, w, h);
    return r;
}

}  // namespace specula
