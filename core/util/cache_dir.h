// Where Specula keeps what it derives from its inputs (MIP-mapped textures, images unpacked from glTF files): one
// rule for those caches, so that SPECULA_CACHE_DIR moves them together. And one rule for trusting what is found
// there: a cache file is used only when its checksum agrees (issue 35: a corrupted texture cache was used unchecked
// and gave a wrong image, where the LTC and P-NDF caches, which checksum their payloads, refit).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

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

}  // namespace specula
