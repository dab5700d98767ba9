// P-NDF manifold cache (issue 12 item 2): content-hash key and in-process sharing; the files through the cache service
// (core/util/cache_dir.h: atomic write, content checksum).
#include "nodes/bsdf/glint_pndf/pndf_cache.h"

#include "core/util/cache_dir.h"

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <map>
#include <mutex>

namespace specula::pndf {

namespace {

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

// The cache service's format tag of a manifold file (core/util/cache_dir.h).
std::string cacheTag() { return "pndf-manifold " + std::to_string(kPndfCacheVersion); }

// What the payload starts with: the request it answers (u64 keyA, u64 keyB, u32 width, u32 height, f64 ε_J).
constexpr size_t kRequestBytes = 32;
std::vector<uint8_t> requestBytes(const PndfCacheKey& key, int width, int height, double jacobianClamp) {
    std::vector<uint8_t> r(kRequestBytes);
    const uint32_t w = uint32_t(width), h = uint32_t(height);
    std::memcpy(r.data(), &key.a, 8);
    std::memcpy(r.data() + 8, &key.b, 8);
    std::memcpy(r.data() + 16, &w, 4);
    std::memcpy(r.data() + 20, &h, 4);
    std::memcpy(r.data() + 24, &jacobianClamp, 8);
    return r;
}

// Reads and validates a cache file; nullptr when absent or invalid (invalid counts as a reject).
std::shared_ptr<PndfManifold> readCache(const std::string& path, const PndfCacheKey& key, int width, int height,
                                        double jacobianClamp) {
    // The payload stays below what a map of the *requested* size can need (normals + bounds + clusters < 64 bytes
    // per texel with every level), so a header cannot drive the allocation.
    const uint64_t maxPayload = kRequestBytes + 64 + uint64_t(width) * uint64_t(height) * 64;
    std::vector<uint8_t> buf;
    const CacheLookup found = readCacheEntry(path, cacheTag(), maxPayload, buf);
    if (found == CacheLookup::Missing) return nullptr;
    auto reject = [&](const char* why) {
        if (why) warnCorruptCacheEntry(path, why);
        ++stats().diskRejects;
        return nullptr;
    };
    if (found == CacheLookup::Corrupt) return reject(nullptr);  // readCacheEntry has warned
    if (buf.size() < kRequestBytes ||
        std::memcmp(buf.data(), requestBytes(key, width, height, jacobianClamp).data(), kRequestBytes) != 0)
        return reject("answers another normal map");
    std::shared_ptr<PndfManifold> m = PndfManifold::deserialize(buf.data() + kRequestBytes, buf.size() - kRequestBytes);
    if (!m || m->width() != width || m->height() != height || m->jacobianClamp() != jacobianClamp)
        return reject("holds no valid manifold of its size");
    return m;
}

void writeCache(const std::string& path, const PndfCacheKey& key, const PndfManifold& m) {
    const std::vector<uint8_t> request = requestBytes(key, m.width(), m.height(), m.jacobianClamp());
    const std::vector<uint8_t> payload = m.serialize();
    if (writeCacheEntry(path, cacheTag(), {{request.data(), request.size()}, {payload.data(), payload.size()}}))
        ++stats().diskWrites;
    else
        ++stats().writeFailures;
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
        if (!path.empty()) writeCache(path, key, *built);
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
