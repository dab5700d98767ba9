// The bad-input catalogue (issue 16 item 5): tests/unit/data/hostile_catalogue.json lists scenes, graphs, meshes,
// images, command lines, output paths and signals that must each end in one clear error: the documented exit code,
// the message naming the JSON pointer or file, no output file, and no existing file changed. One test per case.
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using nlohmann::json;
namespace test = specula::test;

namespace {

// The main file (its "small" base scene and the cases of issue 16) and one file per surface hardened later
// (hostile_catalogue_<surface>.json, issue 35), whose cases are appended in file-name order; names must be unique.
const json& catalogue() {
    static const json doc = [] {
        const fs::path data = fs::path(SPECULA_SOURCE_DIR) / "tests/unit/data";
        std::ifstream in(data / "hostile_catalogue.json");
        json main = json::parse(in);
        std::vector<fs::path> extra;
        for (const auto& e : fs::directory_iterator(data))
            if (e.path().filename().string().rfind("hostile_catalogue_", 0) == 0 && e.path().extension() == ".json")
                extra.push_back(e.path());
        std::sort(extra.begin(), extra.end());
        for (const fs::path& p : extra) {
            std::ifstream f(p);
            const json more = json::parse(f);
            for (const json& c : more.at("cases")) main["cases"].push_back(c);
        }
        return main;
    }();
    return doc;
}

// The bytes of a file entry: a string as it is, {"hex": ...}, or {"base": "small", "set": {...}, "remove": [...]}.
// A case may list "before" commands (run in the folder first, each must exit 0), e.g. renders of farm pieces.
std::string contentOf(const json& f) {
    if (f.is_string()) return f.get<std::string>();
    if (f.contains("hex")) {
        std::string hex = f["hex"], bytes;
        for (size_t i = 0; i + 1 < hex.size(); i += 2) bytes += char(std::stoi(hex.substr(i, 2), nullptr, 16));
        return bytes;
    }
    json scene = catalogue()[f["base"].get<std::string>()];
    if (f.contains("set"))
        for (auto it = f["set"].begin(); it != f["set"].end(); ++it) scene[json::json_pointer(it.key())] = it.value();
    if (f.contains("remove"))
        for (const auto& p : f["remove"]) {
            json::json_pointer ptr(p.get<std::string>());
            scene[ptr.parent_pointer()].erase(ptr.back());
        }
    return scene.dump(1);
}

struct Outcome {
    int exit = -1;
    std::string output;
};

// Runs the CLI in 'dir' (sh -c 'cd dir && exec specula ARGS'); with a signal, sends it after 'afterMs'.
Outcome run(const std::string& dir, const std::string& args, int signal, int afterMs) {
    int fds[2];
    if (pipe(fds) != 0) return {};
    pid_t pid = fork();
    if (pid == 0) {
        dup2(fds[1], 1);
        dup2(fds[1], 2);
        close(fds[0]);
        close(fds[1]);
        const std::string cmd = "cd '" + dir + "' && exec \"" SPECULA_CLI "\" " + args;
        execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
        _exit(127);
    }
    close(fds[1]);
    if (signal) {
        std::this_thread::sleep_for(std::chrono::milliseconds(afterMs));
        kill(pid, signal);
    }
    Outcome o;
    char buf[4096];
    for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) > 0;) o.output.append(buf, size_t(n));
    close(fds[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    o.exit = WIFEXITED(status) ? WEXITSTATUS(status) : WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
    return o;
}

class HostileInput : public ::testing::TestWithParam<size_t> {};

TEST_P(HostileInput, OneClearErrorAndNothingWritten) {
    const json& c = catalogue()["cases"][GetParam()];
    const std::string dir = test::tempDir("hostile");
    std::map<std::string, std::string> before;
    for (auto it = c["files"].begin(); it != c["files"].end(); ++it) {
        fs::path p = fs::path(dir) / it.key();
        fs::create_directories(p.parent_path());
        test::writeFile(p.string(), contentOf(it.value()));
        before[it.key()] = test::readFile(p.string());
    }
    // Commands that set the case up (render the pieces a merge case refuses); each must succeed.
    for (const auto& prep : c.value("before", json::array())) {
        const Outcome p = run(dir, prep.get<std::string>(), 0, 0);
        ASSERT_EQ(p.exit, 0) << prep << ":\n" << p.output;
    }
    for (const auto& u : c.value("unchanged", json::array()))
        if (fs::exists(fs::path(dir) / u.get<std::string>())) before[u.get<std::string>()] = test::readFile((fs::path(dir) / u.get<std::string>()).string());
    int sig = 0;
    if (c.contains("signal")) sig = c["signal"] == "INT" ? SIGINT : SIGTERM;
    const Outcome o = run(dir, c["command"], sig, c.value("signal_after_ms", 0));
    EXPECT_EQ(o.exit, c["exit"].get<int>()) << o.output;
    for (const auto& m : c["message"]) EXPECT_NE(o.output.find(m.get<std::string>()), std::string::npos) << "'" << m << "' not in:\n" << o.output;
    // One message: an error is one line (a usage error may add CLI11's hint line).
    if (o.exit == 1 || o.exit == 3) EXPECT_LE(std::count(o.output.begin(), o.output.end(), '\n'), 2) << o.output;
    for (const auto& a : c.value("absent", json::array())) EXPECT_FALSE(fs::exists(fs::path(dir) / a.get<std::string>())) << a;
    for (const auto& a : c.value("present", json::array())) EXPECT_TRUE(fs::exists(fs::path(dir) / a.get<std::string>())) << a;
    for (const auto& u : c.value("unchanged", json::array()))
        EXPECT_EQ(test::readFile((fs::path(dir) / u.get<std::string>()).string()), before[u.get<std::string>()]) << u;
    // No temporary file is left behind.
    for (auto& e : fs::recursive_directory_iterator(dir))
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

INSTANTIATE_TEST_SUITE_P(Catalogue, HostileInput, ::testing::Range<size_t>(0, catalogue()["cases"].size()),
                         [](const ::testing::TestParamInfo<size_t>& info) {
                             return catalogue()["cases"][info.param]["name"].get<std::string>();
                         });

TEST(HostileCatalogue, HoldsAtLeastEightyCases) { EXPECT_GE(catalogue()["cases"].size(), 80u); }

// Issue 35: at least 50 cases beyond the 132 of issue 16, and no two cases of one name (gtest would merge them).
TEST(HostileCatalogue, HoldsTheCasesOfIssue35WithUniqueNames) {
    EXPECT_GE(catalogue()["cases"].size(), 182u);
    std::set<std::string> names;
    for (const json& c : catalogue()["cases"]) EXPECT_TRUE(names.insert(c["name"].get<std::string>()).second) << c["name"];
}

}  // namespace
