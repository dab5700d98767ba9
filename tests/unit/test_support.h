// Helpers shared by the unit tests: temporary directories, running the CLI, reading files.
#pragma once

#include <string>

namespace specula::test {

// A fresh empty directory under the system temp dir, removed at process exit.
std::string tempDir(const std::string& tag);
// Runs the specula CLI with 'args' (shell-quoted by the caller); returns the exit code and
// captures stdout+stderr into 'output'.
int runCli(const std::string& args, std::string* output = nullptr);
std::string readFile(const std::string& path);
void writeFile(const std::string& path, const std::string& text);
std::string sourcePath(const std::string& relative);  // path inside the source tree

}  // namespace specula::test
