// The files a command reads, by identity (core/util/input_files.h).
#include "core/util/input_files.h"

#include "core/util/error.h"

#include <filesystem>
#include <map>
#include <mutex>
#include <sys/stat.h>
#include <utility>

namespace specula {

namespace {

using FileId = std::pair<unsigned long long, unsigned long long>;  // (st_dev, st_ino)

struct Registry {
    std::mutex m;
    int scopes = 0;
    std::map<FileId, std::string> files;  // identity -> the name it was read by
};
Registry& registry() {
    static Registry r;
    return r;
}

// stat() follows links: a link to an input is that input.
bool fileId(const std::string& path, FileId& id) {
    struct stat st {};
    if (path.empty() || ::stat(path.c_str(), &st) != 0) return false;
    id = {static_cast<unsigned long long>(st.st_dev), static_cast<unsigned long long>(st.st_ino)};
    return true;
}

}  // namespace

InputFileScope::InputFileScope() {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.m);
    ++r.scopes;
}

InputFileScope::~InputFileScope() {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.m);
    if (--r.scopes == 0) r.files.clear();
}

void noteInputFile(const std::string& path) {
    Registry& r = registry();
    {
        std::lock_guard<std::mutex> lock(r.m);
        if (r.scopes == 0) return;
    }
    FileId id;
    if (!fileId(path, id)) return;
    std::lock_guard<std::mutex> lock(r.m);
    if (r.scopes > 0) r.files.emplace(id, path);
}

void refuseOverwritingInputs(const std::string& output, const std::vector<std::string>& inputs, const std::string& option) {
    FileId out;
    if (!fileId(output, out)) return;  // nothing there yet: it cannot be an input
    for (const std::string& in : inputs) {
        if (sameFile(output, in))
            throw Error(ErrorCode::Usage, "", option + " '" + output + "' is the input file '" + in + "'");
    }
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.m);
    auto it = r.files.find(out);
    if (it != r.files.end())
        throw Error(ErrorCode::Usage, "", option + " '" + output + "' is the input file '" + it->second +
                                              "' of this command; write it elsewhere");
}

bool sameFile(const std::string& a, const std::string& b) {
    FileId ia, ib;
    const bool haveA = fileId(a, ia), haveB = fileId(b, ib);
    if (haveA && haveB) return ia == ib;
    if (haveA != haveB || a.empty() || b.empty()) return false;
    // Neither exists yet (an input about to be written, a path a host has not created): one name, one file.
    std::error_code ec1, ec2;
    const std::filesystem::path ca = std::filesystem::weakly_canonical(a, ec1), cb = std::filesystem::weakly_canonical(b, ec2);
    return !ec1 && !ec2 && ca == cb;
}

std::vector<std::string> notedInputFiles() {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.m);
    std::vector<std::string> out;
    for (const auto& [id, name] : r.files) out.push_back(name);
    return out;
}

}  // namespace specula
