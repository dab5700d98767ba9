// P-NDF manifold cache (issue 12 item 2): content-hash key, checksummed file format, atomic write, in-process sharing.
#include "nodes/bsdf/glint_pndf/pndf_cache.h"

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <unistd.h>

namespace specula::pndf {

namespace {

constexpr char kMagic[8] = {'S', 'P', 'N', 'D', 'F', 'M', 'F', '\0'};
constexpr size_t kHeaderSize = 64;

// Two independent 64-bit hashes over 8-byte words (tail zero-padded): FNV-1a on words, and a splitmix64-mixed
// multiply-rotate chain with its own seed. Independent mixing makes an accidental double collision negligible.
struct Hasher {
    uint64_t a = 0xcbf29ce484222325ull;  // FNV offset basis
    uint64_t b = 0x9e3779b97f4a7c15ull;
    static uint64_t mix(uint64_t z) {  // splitmix64 finaliser
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    void word(uint64_t w) {
        a = (a ^ w) * 0x100000001b3ull;
        b = mix(b ^ (w + 0x632be59bd9b4e019ull)) + (b << 7 | b >> 57);
    }
    void bytes(const void* data, size_t n) {
        const uint8_t* p = static_cast<const uint8_t*>(data);
        size_t i = 0;
        for (; i + 8 <= n; i += 8) {
            uint64_t w;
            std::memcpy(&w, p + i, 8);
            word(w);
        }
        if (i < n) {
            uint64_t w = 0;
            std::memcpy(&w, p + i, n - i);
            word(w ^ (uint64_t(n - i) << 56));
        }
        word(uint64_t(n));  // length, so that zero padding cannot alias
    }
};

uint64_t checksum(const uint8_t* data, size_t n) {
    Hasher h;
    h.bytes(data, n);
    return h.a;
}

struct Stats {
    std::atomic<uint64_t> memoryHits{0}, diskHits{0}, diskRejects{0}, builds{0}, diskWrites{0}, writeFailures{0};
};
Stats& stats() {
    static Stats s;
    return s;
}

std::mutex& memoryMutex() {
    static std::mutex m;
    return m;
}
std::map<std::pair<uint64_t, uint64_t>, std::weak_ptr<const PndfManifold>>& memoryCache() {
    static std::map<std::pair<uint64_t, uint64_t>, std::weak_ptr<const PndfManifold>> m;
    return m;
}

template <class T>
void putAt(std::vector<uint8_t>& buf, size_t off, const T& v) {
    std::memcpy(buf.data() + off, &v, sizeof(T));
}
template <class T>
T getAt(const uint8_t* buf, size_t off) {
    T v;
    std::memcpy(&v, buf + off, sizeof(T));
    return v;
}

// Reads and validates a cache file; nullptr when absent or invalid (invalid counts as a reject).
std::shared_ptr<PndfManifold> readCache(const std::string& path, const PndfCacheKey& key, int width, int height,
                                        double jacobianClamp) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return nullptr;
    const uintmax_t fileSize = std::filesystem::file_size(path, ec);
    auto reject = [] {
        ++stats().diskRejects;
        return nullptr;
    };
    if (ec || fileSize < kHeaderSize) return reject();
    std::ifstream in(path, std::ios::binary);
    if (!in) return reject();
    uint8_t hdr[kHeaderSize];
    if (!in.read(reinterpret_cast<char*>(hdr), kHeaderSize)) return reject();
    if (std::memcmp(hdr, kMagic, 8) != 0 || getAt<uint32_t>(hdr, 8) != kPndfCacheVersion ||
        getAt<uint32_t>(hdr, 12) != kHeaderSize || getAt<uint64_t>(hdr, 16) != key.a ||
        getAt<uint64_t>(hdr, 24) != key.b || getAt<uint32_t>(hdr, 32) != uint32_t(width) ||
        getAt<uint32_t>(hdr, 36) != uint32_t(height) || getAt<double>(hdr, 40) != jacobianClamp)
        return reject();
    // The payload size must match the file exactly and stay below what a map of the *requested* size can need
    // (normals + bounds + clusters < 64 bytes per texel with every level), so a header cannot drive the allocation.
    const uint64_t payload = getAt<uint64_t>(hdr, 48);
    const uint64_t maxPayload = 64 + uint64_t(width) * uint64_t(height) * 64;
    if (payload > maxPayload || payload != fileSize - kHeaderSize) return reject();
    std::vector<uint8_t> buf(static_cast<size_t>(payload));
    if (!in.read(reinterpret_cast<char*>(buf.data()), std::streamsize(payload))) return reject();
    if (checksum(buf.data(), buf.size()) != getAt<uint64_t>(hdr, 56)) return reject();
    std::shared_ptr<PndfManifold> m = PndfManifold::deserialize(buf.data(), buf.size());
    if (!m || m->width() != width || m->height() != height || m->jacobianClamp() != jacobianClamp) return reject();
    return m;
}

void writeCache(const std::string& dir, const std::string& path, const PndfCacheKey& key, const PndfManifold& m) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec && !std::filesystem::is_directory(dir)) {
        ++stats().writeFailures;
        return;
    }
    const std::vector<uint8_t> payload = m.serialize();
    std::vector<uint8_t> hdr(kHeaderSize, 0);
    std::memcpy(hdr.data(), kMagic, 8);
    putAt(hdr, 8, kPndfCacheVersion);
    putAt(hdr, 12, uint32_t(kHeaderSize));
    putAt(hdr, 16, key.a);
    putAt(hdr, 24, key.b);
    putAt(hdr, 32, uint32_t(m.width()));
    putAt(hdr, 36, uint32_t(m.height()));
    putAt(hdr, 40, m.jacobianClamp());
    putAt(hdr, 48, uint64_t(payload.size()));
    putAt(hdr, 56, checksum(payload.data(), payload.size()));
    // Unique temporary name in the same folder, then rename: readers see either no file or a complete one.
    static std::atomic<uint64_t> counter{0};
    const std::string tmp = path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
    bool ok = false;
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (out) {
            out.write(reinterpret_cast<const char*>(hdr.data()), std::streamsize(hdr.size()));
            out.write(reinterpret_cast<const char*>(payload.data()), std::streamsize(payload.size()));
            out.flush();
            ok = bool(out);
        }
    }
    if (ok) {
        std::filesystem::rename(tmp, path, ec);
        ok = !ec;
    }
    if (!ok) {
        std::filesystem::remove(tmp, ec);
        ++stats().writeFailures;
        return;
    }
    ++stats().diskWrites;
}

}  // namespace

std::string PndfCacheKey::hex() const {
    char buf[33];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(a),
                  static_cast<unsigned long long>(b));
    return buf;
}

PndfCacheKey pndfCacheKey(const std::vector<Vec3>& normals, int width, int height, double jacobianClamp) {
    Hasher h;
    h.word(kPndfCacheVersion);
    h.word(uint64_t(uint32_t(width)) << 32 | uint32_t(height));
    uint64_t epsBits;
    std::memcpy(&epsBits, &jacobianClamp, 8);
    h.word(epsBits);
    h.bytes(normals.data(), normals.size() * sizeof(Vec3));
    return {h.a, h.b};
}

std::string defaultPndfCacheDir() {
    if (const char* d = std::getenv("SPECULA_CACHE_DIR")) return d;  // set but empty: disabled
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/specula";
    if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/specula";
    return "";
}

std::string pndfCachePath(const std::string& cacheDir, const PndfCacheKey& key) {
    return cacheDir + "/pndf-" + key.hex() + ".bin";
}

std::shared_ptr<const PndfManifold> loadOrBuildManifold(const std::vector<Vec3>& normals, int width, int height,
                                                        double jacobianClamp, const std::string& cacheDir) {
    const PndfCacheKey key = pndfCacheKey(normals, width, height, jacobianClamp);
    {
        std::lock_guard<std::mutex> lock(memoryMutex());
        auto it = memoryCache().find({key.a, key.b});
        if (it != memoryCache().end())
            if (std::shared_ptr<const PndfManifold> m = it->second.lock()) {
                ++stats().memoryHits;
                return m;
            }
    }
    // The build and the file I/O run outside the lock; two threads asking for the same new map may both build it
    // (the results are identical), which is cheaper than serialising every material's load.
    std::shared_ptr<const PndfManifold> m;
    const std::string path = cacheDir.empty() ? std::string() : pndfCachePath(cacheDir, key);
    if (!path.empty()) {
        m = readCache(path, key, width, height, jacobianClamp);
        if (m) ++stats().diskHits;
    }
    if (!m) {
        auto built = std::make_shared<PndfManifold>(normals, width, height, jacobianClamp);
        ++stats().builds;
        if (!path.empty()) writeCache(cacheDir, path, key, *built);
        m = std::move(built);
    }
    std::lock_guard<std::mutex> lock(memoryMutex());
    for (auto it = memoryCache().begin(); it != memoryCache().end();)  // drop maps no material holds any more
        it = it->second.expired() ? memoryCache().erase(it) : std::next(it);
    memoryCache()[{key.a, key.b}] = m;
    return m;
}

std::shared_ptr<const PndfManifold> loadOrBuildManifold(const std::vector<Vec3>& normals, int width, int height,
                                                        double jacobianClamp) {
    return loadOrBuildManifold(normals, width, height, jacobianClamp, defaultPndfCacheDir());
}

PndfCacheStats pndfCacheStats() {
    const Stats& s = stats();
    PndfCacheStats r;
    r.memoryHits = s.memoryHits;
    r.diskHits = s.diskHits;
    r.diskRejects = s.diskRejects;
    r.builds = s.builds;
    r.diskWrites = s.diskWrites;
    r.writeFailures = s.writeFailures;
    return r;
}

void resetPndfCacheStats() {
    Stats& s = stats();
    s.memoryHits = s.diskHits = s.diskRejects = s.builds = s.diskWrites = s.writeFailures = 0;
}

}  // namespace specula::pndf
