// The cache folders' rule (core/util/cache_dir.h).
#include "core/util/cache_dir.h"

#include "core/util/error.h"

#include <cstdlib>
#include <filesystem>
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

}  // namespace specula
