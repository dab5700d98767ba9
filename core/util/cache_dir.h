// Where Specula keeps what it derives from its inputs (MIP-mapped textures, images unpacked from glTF files): one
// rule for those caches, so that SPECULA_CACHE_DIR moves them together.
#pragma once

#include <string>

namespace specula {

// <base>/<sub>, created, for the first usable base of $SPECULA_CACHE_DIR, $XDG_CACHE_HOME/specula,
// ~/.cache/specula and <temp>/specula-cache-<uid>. Throws IoError naming them when none is writable.
std::string cacheFolder(const std::string& sub);

}  // namespace specula
