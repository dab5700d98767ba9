#include "test_support.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <vector>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace specula::test {

namespace {
std::vector<std::string>& dirsToRemove() {
    static std::vector<std::string> dirs;
    static bool registered = false;
    if (!registered) {
        registered = true;
        std::atexit([] {
            for (auto& d : dirsToRemove()) {
                std::error_code ec;
                fs::remove_all(d, ec);
            }
        });
    }
    return dirs;
}
}  // namespace

std::string tempDir(const std::string& tag) {
    static std::mutex m;
    std::lock_guard<std::mutex> lock(m);
    std::string pattern = (fs::temp_directory_path() / ("specula-" + tag + "-XXXXXX")).string();
    std::vector<char> buf(pattern.begin(), pattern.end());
    buf.push_back('\0');
    if (!mkdtemp(buf.data())) throw std::runtime_error("mkdtemp failed");
    dirsToRemove().push_back(buf.data());
    return buf.data();
}

int runCli(const std::string& args, std::string* output) {
    std::string cmd = std::string("\"") + SPECULA_CLI + "\" " + args + " 2>&1";
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe) return -1;
    std::string out;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
    int status = pclose(pipe);
    if (output) *output = out;
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
    return -1;
}

std::string readFile(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

void writeFile(const std::string& path, const std::string& text) {
    fs::create_directories(fs::path(path).parent_path());
    std::ofstream f(path, std::ios::binary);
    f << text;
}

std::string sourcePath(const std::string& relative) { return std::string(SPECULA_SOURCE_DIR) + "/" + relative; }

}  // namespace specula::test
