// The files a command reads, by identity (core/util/input_files.h).
#include "core/util/input_files.h"

#include "core/util/error.h"

#include <filesystem>
#include <map>
#include <mutex>
#include <fcntl.h>
#include <sys/stat.h>
#include <tuple>
#include <utility>

namespace specula {

namespace {

// One incarnation of a file: device and inode, plus the birth time where the file system reports it. An inode
// number is reused as soon as its file is deleted (on ext4, by the very next file created in the folder), so a
// scene that an editor replaced by rename leaves its old number free for this command's own temporary output;
// the birth time tells the two apart. Without one (btime 0), a noted identity counts only while its noted name
// still resolves to it (see notedAs).
struct FileId {
    unsigned long long dev = 0, ino = 0;
    long long btimeSec = 0;
    unsigned btimeNsec = 0;
    bool operator<(const FileId& o) const {
        return std::tie(dev, ino, btimeSec, btimeNsec) < std::tie(o.dev, o.ino, o.btimeSec, o.btimeNsec);
    }
    bool operator==(const FileId& o) const {
        return dev == o.dev && ino == o.ino && btimeSec == o.btimeSec && btimeNsec == o.btimeNsec;
    }
    bool hasBirthTime() const { return btimeSec != 0 || btimeNsec != 0; }
};

struct Registry {
    std::mutex m;
    int scopes = 0;
    std::map<FileId, std::string> files;  // identity -> the name it was read by
};
Registry& registry() {
    static Registry r;
    return r;
}

// statx() follows links: a link to an input is that input.
bool fileId(const std::string& path, FileId& id) {
    struct statx st {};
    if (path.empty() || ::statx(AT_FDCWD, path.c_str(), 0, STATX_INO | STATX_BTIME, &st) != 0) return false;
    id = FileId{};
    id.dev = (static_cast<unsigned long long>(st.stx_dev_major) << 32) | st.stx_dev_minor;
    id.ino = st.stx_ino;
    if (st.stx_mask & STATX_BTIME) {
        id.btimeSec = st.stx_btime.tv_sec;
        id.btimeNsec = st.stx_btime.tv_nsec;
    }
    return true;
}

// Whether 'out' is a file the open scope noted and that still exists as read: with a birth time the identity says
// so; without one, the noted name must still resolve to it, or the inode number may belong to a newer file.
// Caller holds r.m.
const std::string* notedAs(const Registry& r, const FileId& out) {
    auto it = r.files.find(out);
    if (it == r.files.end()) return nullptr;
    if (out.hasBirthTime()) return &it->second;
    FileId now;
    return fileId(it->second, now) && now == out ? &it->second : nullptr;
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
    if (const std::string* input = notedAs(r, out))
        throw Error(ErrorCode::Usage, "", option + " '" + output + "' is the input file '" + *input +
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
