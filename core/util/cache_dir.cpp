// The cache folders' rule and the cache files' checksum (core/util/cache_dir.h).
#include "core/util/cache_dir.h"

#include "core/util/error.h"

#include <atomic>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace specula {

std::string cacheFolder(const std::string& sub) {
    std::vector<fs::path> bases;
    if (const char* e = std::getenv("SPECULA_CACHE_DIR"); e && *e) bases.emplace_back(e);
    if (const char* e = std::getenv("XDG_CACHE_HOME"); e && *e) bases.emplace_back(fs::path(e) / "specula");
    if (const char* e = std::getenv("HOME"); e && *e) bases.emplace_back(fs::path(e) / ".cache" / "specula");
    std::error_code ec;
    bases.emplace_back(fs::temp_directory_path(ec) / ("specula-cache-" + std::to_string(::getuid())));
    for (const fs::path& b : bases) {
        const fs::path d = b / sub;
        fs::create_directories(d, ec);
        if (fs::is_directory(d, ec) && ::access(d.c_str(), W_OK | X_OK) == 0) return d.string();
    }
    throw IoError("no writable cache folder for '" + sub + "' (tried $SPECULA_CACHE_DIR, $XDG_CACHE_HOME/specula, "
                  "~/.cache/specula and the temp folder)");
}

// ---- checksum ----------------------------------------------------------------------------------------------------

void ContentChecksum::word(uint64_t w) {
    // rotl is a bijection, xor with w too, and the multiplier is odd: see the header.
    state_ = ((state_ << 23 | state_ >> 41) ^ w) * 0xff51afd7ed558ccdull;
}

void ContentChecksum::add(const void* data, size_t bytes) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    bytes_ += bytes;
    while (pendingCount_ > 0 && pendingCount_ < 8 && bytes > 0) {
        pending_[pendingCount_++] = *p++;
        --bytes;
    }
    if (pendingCount_ == 8) {
        uint64_t w;
        std::memcpy(&w, pending_, 8);
        word(w);
        pendingCount_ = 0;
    }
    for (; bytes >= 8; p += 8, bytes -= 8) {
        uint64_t w;
        std::memcpy(&w, p, 8);
        word(w);
    }
    for (; bytes > 0; --bytes) pending_[pendingCount_++] = *p++;
}

uint64_t ContentChecksum::value() const {
    ContentChecksum c = *this;
    if (c.pendingCount_ > 0) {
        uint64_t w = 0;
        std::memcpy(&w, c.pending_, c.pendingCount_);
        c.word(w);
    }
    c.word(c.bytes_);  // the length: zero padding of the last word cannot alias a longer stream
    uint64_t z = c.state_;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

uint64_t contentChecksum(const void* data, size_t bytes) {
    ContentChecksum c;
    c.add(data, bytes);
    return c.value();
}

namespace {

constexpr const char* kSidecarTag = "specula-cache-checksum 1";

// Size and checksum of a file's bytes, read in 1 MiB pieces; false when it cannot be read completely.
bool checksumFile(const std::string& file, uint64_t& size, uint64_t& sum) {
    std::ifstream in(file, std::ios::binary);
    if (!in) return false;
    std::vector<char> buf(size_t(1) << 20);
    ContentChecksum c;
    size = 0;
    while (in) {
        in.read(buf.data(), std::streamsize(buf.size()));
        const std::streamsize got = in.gcount();
        if (got <= 0) break;
        c.add(buf.data(), size_t(got));
        size += uint64_t(got);
    }
    if (in.bad()) return false;
    sum = c.value();
    return true;
}

std::string sidecarLine(uint64_t size, uint64_t sum) {
    char line[96];
    std::snprintf(line, sizeof line, "%s %" PRIu64 " %016" PRIx64 "\n", kSidecarTag, size, sum);
    return line;
}

}  // namespace

std::string cacheChecksumPath(const std::string& file) { return file + ".sum"; }

bool writeCacheChecksum(const std::string& file) {
    uint64_t size = 0, sum = 0;
    if (!checksumFile(file, size, sum)) return false;
    const std::string line = sidecarLine(size, sum);
    return writeFileAtomically(cacheChecksumPath(file), {{line.data(), line.size()}});
}

bool cacheChecksumMatches(const std::string& file) {
    // The sidecar is one short line: a longer file is not ours (and is not read whole).
    std::error_code ec;
    const std::string side = cacheChecksumPath(file);
    const auto sideSize = fs::file_size(side, ec);
    if (ec || sideSize > 128) return false;
    std::ifstream in(side, std::ios::binary);
    std::string recorded((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // The size first: a truncated or padded file is refused without reading it.
    const auto fileSize = fs::file_size(file, ec);
    if (ec) return false;
    const size_t tagEnd = std::strlen(kSidecarTag);
    if (recorded.compare(0, tagEnd, kSidecarTag) != 0) return false;
    const std::string sizeField = " " + std::to_string(uint64_t(fileSize)) + " ";
    if (recorded.compare(tagEnd, sizeField.size(), sizeField) != 0) return false;
    uint64_t size = 0, sum = 0;
    if (!checksumFile(file, size, sum)) return false;
    return recorded == sidecarLine(size, sum);
}

// ---- the cache service ------------------------------------------------------------------------------------------

bool writeFileAtomically(const std::string& path, const std::vector<CachePiece>& pieces) {
    std::error_code ec;
    const fs::path parent = fs::path(path).parent_path();
    if (!parent.empty()) {
        fs::create_directories(parent, ec);
        if (!fs::is_directory(parent, ec)) return false;
    }
    static std::atomic<unsigned> serial{0};
    const std::string tmp = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(serial++);
    bool ok = false;
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (out) {
            for (const CachePiece& p : pieces) out.write(static_cast<const char*>(p.data), std::streamsize(p.bytes));
            out.flush();
            ok = bool(out);
        }
    }
    if (ok) {
        fs::rename(tmp, path, ec);
        ok = !ec;
    }
    if (!ok) fs::remove(tmp, ec);
    return ok;
}

namespace {

constexpr char kEntryMagic[8] = {'S', 'P', 'C', 'A', 'C', 'H', 'E', '1'};
constexpr size_t kEntryHeader = 32;

}  // namespace

void warnCorruptCacheEntry(const std::string& path, const std::string& why) {
    std::fprintf(stderr, "specula: warning: cache file '%s' %s; rebuilding it\n", path.c_str(), why.c_str());
}

CacheLookup readCacheEntry(const std::string& path, const std::string& tag, uint64_t maxPayload,
                           std::vector<uint8_t>& payload) {
    std::error_code ec;
    if (!fs::exists(path, ec)) return CacheLookup::Missing;
    auto corrupt = [&](const std::string& why) {
        warnCorruptCacheEntry(path, why);
        return CacheLookup::Corrupt;
    };
    const uint64_t fileSize = fs::is_regular_file(path, ec) ? uint64_t(fs::file_size(path, ec)) : 0;
    if (ec || fileSize < kEntryHeader) return corrupt("is shorter than its header");
    std::ifstream in(path, std::ios::binary);
    unsigned char header[kEntryHeader];
    if (!in.read(reinterpret_cast<char*>(header), kEntryHeader)) return corrupt("cannot be read");
    uint64_t tagSum = 0, size = 0, sum = 0;
    std::memcpy(&tagSum, header + 8, 8);
    std::memcpy(&size, header + 16, 8);
    std::memcpy(&sum, header + 24, 8);
    if (std::memcmp(header, kEntryMagic, 8) != 0) return corrupt("is not a Specula cache file");
    if (tagSum != contentChecksum(tag.data(), tag.size())) return corrupt("holds another kind or version than '" + tag + "'");
    // The size first, against the file and the caller's bound: a header cannot drive the allocation.
    if (size != fileSize - kEntryHeader || size > maxPayload) return corrupt("has the wrong size");
    payload.resize(size_t(size));
    if (!in.read(reinterpret_cast<char*>(payload.data()), std::streamsize(size))) return corrupt("cannot be read");
    if (contentChecksum(payload.data(), payload.size()) != sum) return corrupt("fails its content checksum");
    return CacheLookup::Hit;
}

bool writeCacheEntry(const std::string& path, const std::string& tag, const std::vector<CachePiece>& pieces) {
    ContentChecksum c;
    uint64_t size = 0;
    for (const CachePiece& p : pieces) {
        c.add(p.data, p.bytes);
        size += p.bytes;
    }
    unsigned char header[kEntryHeader];
    const uint64_t tagSum = contentChecksum(tag.data(), tag.size()), sum = c.value();
    std::memcpy(header, kEntryMagic, 8);
    std::memcpy(header + 8, &tagSum, 8);
    std::memcpy(header + 16, &size, 8);
    std::memcpy(header + 24, &sum, 8);
    std::vector<CachePiece> all{{header, kEntryHeader}};
    all.insert(all.end(), pieces.begin(), pieces.end());
    return writeFileAtomically(path, all);
}

}  // namespace specula
