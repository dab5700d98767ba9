// Where Specula keeps what it derives from its inputs (MIP-mapped textures, images unpacked from glTF files, fitted
// tables): one rule for those caches, so that SPECULA_CACHE_DIR moves them together. And one service for writing and
// trusting what is found there: atomic writes, and a cache file is used only when its content checksum agrees
// (issue 35: a corrupted texture cache was used unchecked and gave a wrong image).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace specula {

// <base>/<sub>, created, for the first usable base of $SPECULA_CACHE_DIR, $XDG_CACHE_HOME/specula,
// ~/.cache/specula and <temp>/specula-cache-<uid>. Throws IoError naming them when none is writable.
std::string cacheFolder(const std::string& sub);

// A 64-bit checksum of a byte stream, fed in pieces of any size (the result depends only on the bytes and their
// count, not on how they were split). Per 8-byte word the state is rotated, xored with the word and multiplied by an
// odd constant: every step is a bijection of the state for a fixed word and of the word for a fixed state, so a
// change confined to one word always changes the result; the length and a final avalanche (splitmix64) end it.
// It guards against corruption (bit flips, truncation, foreign files), not against an adversary.
class ContentChecksum {
public:
    void add(const void* data, size_t bytes);
    uint64_t value() const;

private:
    void word(uint64_t w);
    uint64_t state_ = 0x9e3779b97f4a7c15ull;
    uint64_t bytes_ = 0;
    unsigned char pending_[8] = {};
    size_t pendingCount_ = 0;
};
uint64_t contentChecksum(const void* data, size_t bytes);

// Checksum sidecars for cache files that another library writes and reads (OpenImageIO's .tx), so that the checksum
// cannot live in the file itself: <file>.sum holds one line "specula-cache-checksum 1 <size> <16 hex digits>".
// writeCacheChecksum computes it for the file as it is now and publishes the sidecar atomically (temporary file and
// rename); false when it cannot (the cache is then rebuilt next time, never trusted). cacheChecksumMatches is true
// only when the sidecar exists and names the file's current size and content checksum; it reads the whole file.
bool writeCacheChecksum(const std::string& file);
bool cacheChecksumMatches(const std::string& file);
std::string cacheChecksumPath(const std::string& file);

// ---- the cache service: every cache Specula writes itself (LTC prefilter, P-NDF manifolds, the glint dictionary) ----

// Bytes to write, in order.
struct CachePiece {
    const void* data;
    size_t bytes;
};

// Publishes 'pieces' as the file 'path': written to a unique temporary beside it and renamed over it once complete,
// so a reader sees the old file or the new one, never a partial one (concurrent writers of the same content just
// replace each other). Creates the folder. False when any step fails (the temporary is removed).
bool writeFileAtomically(const std::string& path, const std::vector<CachePiece>& pieces);

// A cache entry is one file: a 32-byte header, then the payload.
//   bytes  0..7   magic "SPCACHE1"                 8..15  contentChecksum of the caller's format tag
//         16..23  u64 payload size                24..31  ContentChecksum of the payload
// The tag names what the payload is and its layout version ("pndf-manifold 1"): a file of another kind or an older
// layout never matches. Native byte order (every supported host is little-endian).
enum class CacheLookup { Hit, Missing, Corrupt };
// Reads the entry at 'path' written under 'tag' into 'payload'. Hit only when the file is exactly header + payload,
// the payload is at most maxPayload bytes (both checked before anything is allocated), and the tag and the
// checksum agree. Corrupt when the file exists but fails a check: a warning naming it goes to stderr, and the caller
// rebuilds the entry and writes it again. Missing when there is no file.
CacheLookup readCacheEntry(const std::string& path, const std::string& tag, uint64_t maxPayload,
                           std::vector<uint8_t>& payload);
// Writes the entry (header + pieces) with writeFileAtomically; false when it cannot (the cache never fails a render).
bool writeCacheEntry(const std::string& path, const std::string& tag, const std::vector<CachePiece>& pieces);
// The warning readCacheEntry gives, for callers whose own checks of a Hit's payload fail.
void warnCorruptCacheEntry(const std::string& path, const std::string& why);

// A cache folder ("" disables it: reads miss, writes do nothing) whose entries are named by their content keys.
class CacheStore {
public:
    explicit CacheStore(std::string folder) : folder_(std::move(folder)) {}
    bool enabled() const { return !folder_.empty(); }
    const std::string& folder() const { return folder_; }
    std::string path(const std::string& name) const { return folder_ + "/" + name; }
    CacheLookup read(const std::string& name, const std::string& tag, uint64_t maxPayload,
                     std::vector<uint8_t>& payload) const {
        return enabled() ? readCacheEntry(path(name), tag, maxPayload, payload) : CacheLookup::Missing;
    }
    bool write(const std::string& name, const std::string& tag, const std::vector<CachePiece>& pieces) const {
        return enabled() && writeCacheEntry(path(name), tag, pieces);
    }

private:
    std::string folder_;
};

}  // namespace specula
