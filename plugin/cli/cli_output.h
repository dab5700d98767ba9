// Shared checks for CLI subcommands that write files: fail early (exit 3, nothing written) when the
// output's folder is missing, with the same message for every command.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>

namespace specula {

// True if the folder that would hold 'path' exists (or 'path' has none); otherwise prints the error.
inline bool outputFolderExists(const std::string& path) {
    std::filesystem::path dir = std::filesystem::path(path).parent_path();
    if (dir.empty() || std::filesystem::is_directory(dir)) return true;
    std::fprintf(stderr, "specula: error: output folder '%s' does not exist\n", dir.string().c_str());
    return false;
}

}  // namespace specula
