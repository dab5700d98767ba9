// P-NDF manifold cache (issue 12 item 2): a PndfManifold is built once per normal-map content and shared, in
// process through a weak_ptr map and across runs through a checksummed file per content hash in a cache folder.
//
// The key is two independent 64-bit hashes of (format version, width, height, ε_J, the normal data); the file is
// <cacheDir>/pndf-<keyA><keyB>.bin, an entry of the cache service (core/util/cache_dir.h: header with the format tag
// "pndf-manifold <kPndfCacheVersion>", payload size and content checksum, written atomically) whose payload is
//   u64 keyA, u64 keyB, u32 width, u32 height, f64 ε_J   (the request it answers, 32 bytes)
//   then PndfManifold::serialize() (native byte order).
// A file is used only when the service accepts it (size bounded by the requested map before anything is allocated,
// checksum), its request matches and deserialize accepts it; anything else (truncated, corrupt, wrong version,
// foreign key) is rejected with a warning and replaced by a fresh build. A cache folder that cannot be created or
// written is skipped: the cache never fails a render.
#pragma once

#include "nodes/bsdf/glint_pndf/pndf_manifold.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace specula::pndf {

// Bumped whenever the build (fit, bounds, replacement) or the byte layout changes, so stale files never match.
constexpr uint32_t kPndfCacheVersion = 2;  // 2: the cache service's file layout

struct PndfCacheKey {
    uint64_t a = 0, b = 0;
    std::string hex() const;  // 32 lowercase hex digits
    bool operator==(const PndfCacheKey& o) const { return a == o.a && b == o.b; }
};
PndfCacheKey pndfCacheKey(const std::vector<Vec3>& normals, int width, int height, double jacobianClamp);

// The default cache folder: $SPECULA_CACHE_DIR if set (an empty value disables the disk cache), else
// $XDG_CACHE_HOME/specula, else $HOME/.cache/specula, else "" (disabled).
std::string defaultPndfCacheDir();
// <cacheDir>/pndf-<key hex>.bin
std::string pndfCachePath(const std::string& cacheDir, const PndfCacheKey& key);

// The manifold for this map: from the in-process cache if another material holds it, else from the disk cache in
// cacheDir (empty: no disk cache), else built (and then written to cacheDir when possible). Throws what the
// PndfManifold constructor throws for invalid input; cache I/O problems never throw.
std::shared_ptr<const PndfManifold> loadOrBuildManifold(const std::vector<Vec3>& normals, int width, int height,
                                                        double jacobianClamp, const std::string& cacheDir);
// Same with defaultPndfCacheDir().
std::shared_ptr<const PndfManifold> loadOrBuildManifold(const std::vector<Vec3>& normals, int width, int height,
                                                        double jacobianClamp = kDefaultJacobianClamp);

// Process-wide counters (tests and logs): where each loadOrBuildManifold answer came from.
struct PndfCacheStats {
    uint64_t memoryHits = 0;    // shared from the in-process map
    uint64_t diskHits = 0;      // read from a valid cache file
    uint64_t diskRejects = 0;   // a cache file existed but was invalid (then rebuilt)
    uint64_t builds = 0;        // built from the normals
    uint64_t diskWrites = 0;    // cache files written
    uint64_t writeFailures = 0; // cache folder or file not writable (skipped)
};
PndfCacheStats pndfCacheStats();
void resetPndfCacheStats();

}  // namespace specula::pndf
