// Shared checks for CLI subcommands that write files: fail early (exit 3, nothing written) when the
// output's folder is missing, with the same message for every command.
#pragma once

#include "core/util/error.h"

#include <cstdio>
#include <filesystem>
#include <string>

namespace specula {

// The one message for a missing output folder (exit 3).
inline std::string missingOutputFolderMessage(const std::string& path) {
    return "output folder '" + std::filesystem::path(path).parent_path().string() + "' does not exist";
}

// True if the folder that would hold 'path' exists (or 'path' has none); otherwise prints the error.
inline bool outputFolderExists(const std::string& path) {
    std::error_code ec;
    std::filesystem::path dir = std::filesystem::path(path).parent_path();
    if (path.empty() || dir.empty() || std::filesystem::is_directory(dir, ec)) return true;
    std::fprintf(stderr, "specula: error: %s\n", missingOutputFolderMessage(path).c_str());
    return false;
}

// The same check for commands that report through exceptions: IoError (exit 3) before any work is done.
inline void requireOutputFolder(const std::string& path) {
    std::error_code ec;
    std::filesystem::path dir = std::filesystem::path(path).parent_path();
    if (!path.empty() && !dir.empty() && !std::filesystem::is_directory(dir, ec)) throw IoError(missingOutputFolderMessage(path));
}

}  // namespace specula
