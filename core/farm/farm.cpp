// Farm plans, Slurm scripts and the bit-exact merge of pieces (core/farm/farm.h).
#include "core/farm/farm.h"

#include "core/color/color_config.h"
#include "core/io/image_io.h"
#include "core/scene/animation.h"
#include "core/scene/json_reader.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "core/util/error.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace fs = std::filesystem;

namespace specula::farm {

namespace {

// ---- checked text --------------------------------------------------------------------------------------------------

// A value from a file or the command line as an error message shows it: quoted, control characters as \xNN, at most
// 80 characters, so that every error stays one line whatever the input holds.
std::string shown(const std::string& value) {
    std::string out = "'";
    size_t n = 0;
    for (unsigned char c : value) {
        if (++n > 80) {
            out += "...";
            break;
        }
        if (c < 0x20 || c == 0x7f) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", c);
            out += hex;
        } else {
            out += char(c);
        }
    }
    return out + "'";
}

bool hasControlCharacter(const std::string& s) {
    return std::any_of(s.begin(), s.end(), [](char c) { return (unsigned char)c < 0x20 || c == 0x7f; });
}

// The whole of 'text' as an integer in [lo, hi]: no sign other than '-', no space, no fraction, no exponent.
bool parseWhole(const std::string& text, long long lo, long long hi, long long& value) {
    if (text.empty() || text.size() > 24) return false;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, value);
    return ec == std::errc() && ptr == end && value >= lo && value <= hi;
}

bool parseWholeList(const std::string& text, char sep, size_t count, long long lo, long long hi, std::vector<long long>& out) {
    out.clear();
    size_t start = 0;
    while (out.size() <= count) {
        const size_t end = text.find(sep, start);
        long long v = 0;
        if (!parseWhole(text.substr(start, end == std::string::npos ? std::string::npos : end - start), lo, hi, v)) return false;
        out.push_back(v);
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return out.size() == count;
}

// ---- piece metadata ------------------------------------------------------------------------------------------------

constexpr long long kMaxSide = 16384;     // the renderer's largest image side
constexpr long long kMaxSpp = 1 << 20;    // render --spp's range
constexpr long long kMaxSplits = 1 << 20;
constexpr long long kIntMin = -2147483647LL - 1, kIntMax = 2147483647LL;
// A piece's EXR holds at most 2^26 pixels of a few dozen float channels; a file beyond this is not a piece, and is
// refused before any of it is read.
constexpr uintmax_t kMaxPieceBytes = uintmax_t(64) << 30;

struct Piece {
    std::string path;
    ImageSet images;
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    int splitIndex = -1, splitCount = 0;  // -1: a whole render of its tile
};

std::string meta(const Piece& p, const std::string& key) {
    auto it = p.images.metadata.find("specula:" + key);
    if (it == p.images.metadata.end())
        throw InputError("merge", "'" + p.path + "' is not a Specula render piece (it has no specula:" + key +
                                 " attribute; pieces come from `specula render` of this version)");
    return it->second;
}

// A piece's integer attribute, parsed whole and inside [lo, hi]; otherwise one InputError naming the file, the
// attribute and the range.
long long metaInteger(const Piece& p, const std::string& key, long long lo, long long hi) {
    const std::string text = meta(p, key);
    long long v = 0;
    if (!parseWhole(text, lo, hi, v))
        throw InputError("merge", "'" + p.path + "' has specula:" + key + " " + shown(text) + ", not an integer in " +
                                     std::to_string(lo) + " … " + std::to_string(hi));
    return v;
}

// Refuses, before anything is read, what cannot be a piece file: a missing path (IoError), a device such as /dev/zero,
// a FIFO or a folder (IoError: reading them would never end or means nothing), a file too large, or one that cannot
// be opened.
void checkPieceFile(const std::string& path) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw IoError("merge: cannot read the piece '" + path + "': no such file");
    if (fs::is_directory(st)) throw IoError("merge: the piece '" + path + "' is a folder, not an EXR file");
    if (!fs::is_regular_file(st))
        throw IoError("merge: the piece '" + path + "' is not a regular file (a device, FIFO or socket); pieces are EXR files");
    const uintmax_t bytes = fs::file_size(path, ec);
    if (ec) throw IoError("merge: cannot read the piece '" + path + "': " + ec.message());
    if (bytes > kMaxPieceBytes)
        throw InputError("merge", "'" + path + "' holds " + std::to_string(bytes) + " bytes, more than a piece can (at most 64 GiB)");
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw IoError("merge: cannot open the piece '" + path + "' for reading");
}

// The 'samples' layer of a sample split: one channel of whole numbers of valid samples, at most the split's block of
// spp/K each (the merge divides by their sum; a negative, fractional, NaN or 1e30 count would make a wrong image).
void checkSampleCounts(const Piece& p, long long block) {
    const AovBuffer* samples = p.images.find("samples");
    if (samples->channels() != 1)
        throw InputError("merge", "'" + p.path + "' has a 'samples' layer of " + std::to_string(samples->channels()) +
                                     " channels; a sample split's counts are one channel");
    for (size_t i = 0; i < samples->pixels.size(); ++i) {
        const float n = samples->pixels[i];
        if (!(std::isfinite(n) && n >= 0.f && n <= float(block) && n == std::floor(n))) {
            const size_t w = size_t(std::max(p.images.width, 1));
            char value[32];
            std::snprintf(value, sizeof value, "%g", double(n));
            throw InputError("merge", "'" + p.path + "' has a sample count of " + value + " at pixel " + std::to_string(i % w) + "," +
                                         std::to_string(i / w) + " of its 'samples' layer; counts are whole numbers in 0 … " +
                                         std::to_string(block) + " (spp / splits)");
        }
    }
}

}  // namespace

// ---- merge ---------------------------------------------------------------------------------------------------------

MergeSummary mergePieces(const std::vector<std::string>& paths, const std::string& outPath, bool overwrite, int64_t maxPiecePixels) {
    if (paths.empty()) throw InputError("merge", "merge needs at least one piece");
    if (fs::path(outPath).extension() != ".exr") throw InputError("merge", "merge writes an EXR: '" + outPath + "' does not end in .exr");
    std::error_code ec;
    // The output's folder first: a missing one is known before any piece is read (docs/cli.md: exit 3).
    const fs::path outDir = fs::path(outPath).parent_path().empty() ? fs::path(".") : fs::path(outPath).parent_path();
    if (!fs::is_directory(outDir, ec))
        throw IoError("merge: the output folder '" + outDir.string() + "' of '" + outPath + "' does not exist");
    if (fs::exists(outPath, ec) && !fs::is_regular_file(outPath, ec))
        throw IoError("merge: the output '" + outPath + "' exists and is not a file");
    for (const std::string& p : paths)
        if (fs::exists(outPath, ec) && fs::equivalent(p, outPath, ec))
            throw InputError("merge", "the output '" + outPath + "' is one of the pieces; choose another file");
    if (!overwrite && fs::exists(outPath, ec))
        throw IoError("'" + outPath + "' exists; merge never overwrites a finished frame (pass --force to replace it)");

    std::vector<Piece> pieces;
    for (const std::string& path : paths) {
        checkPieceFile(path);
        Piece p;
        p.path = path;
        try {
            p.images = readImageSet(path, maxPiecePixels);
        } catch (const ImageIoError& e) {
            throw InputError("merge", "'" + path + "' is not a Specula render piece: " + e.what());
        }
        pieces.push_back(std::move(p));
    }
    const Piece& ref = pieces.front();
    MergeSummary sum;
    sum.sceneHash = meta(ref, "scene_hash");
    std::vector<long long> size;
    if (!parseWholeList(meta(ref, "frame_size"), 'x', 2, 1, kMaxSide, size))
        throw InputError("merge", "'" + ref.path + "' has specula:frame_size " + shown(meta(ref, "frame_size")) +
                                     ", not WxH with each side in 1 … " + std::to_string(kMaxSide));
    sum.width = int(size[0]), sum.height = int(size[1]);
    if (int64_t(sum.width) * sum.height > maxPiecePixels)
        throw InputError("merge", "'" + ref.path + "' has specula:frame_size " + shown(meta(ref, "frame_size")) + ", more than " +
                                     std::to_string(maxPiecePixels) + " pixels");
    sum.frame = int(metaInteger(ref, "frame", kIntMin, kIntMax));
    const long long spp = metaInteger(ref, "spp", 1, kMaxSpp);
    (void)metaInteger(ref, "seed", 0, std::numeric_limits<long long>::max());
    const long long block = metaInteger(ref, "sample_block", 1, spp);
    for (Piece& p : pieces) {
        for (const char* key : {"scene_hash", "frame", "frame_size", "spp", "seed", "sample_block"})
            if (meta(p, key) != meta(ref, key))
                throw InputError("merge", "'" + p.path + "' belongs to another render than '" + ref.path + "' (specula:" + key +
                                         " " + shown(meta(p, key)) + " against " + shown(meta(ref, key)) + ")");
        auto partial = p.images.metadata.find("specula:partial");
        if (partial != p.images.metadata.end() && partial->second == "true")
            throw InputError("merge", "'" + p.path + "' is a partial (interrupted) render; render that piece again");
        std::vector<long long> c;
        if (!parseWholeList(meta(p, "crop"), ',', 4, 0, kMaxSide, c) || c[2] > sum.width || c[3] > sum.height || c[0] >= c[2] ||
            c[1] >= c[3] || p.images.width != c[2] - c[0] || p.images.height != c[3] - c[1])
            throw InputError("merge", "'" + p.path + "' has specula:crop " + shown(meta(p, "crop")) + ", which does not fit its " +
                                     std::to_string(p.images.width) + "x" + std::to_string(p.images.height) + " pixels in the " +
                                     std::to_string(sum.width) + "x" + std::to_string(sum.height) + " frame (x0,y0,x1,y1 with x0 < x1 ≤ " +
                                     std::to_string(sum.width) + ", y0 < y1 ≤ " + std::to_string(sum.height) + ")");
        p.x0 = int(c[0]), p.y0 = int(c[1]), p.x1 = int(c[2]), p.y1 = int(c[3]);
        auto split = p.images.metadata.find("specula:sample_split");
        if (split != p.images.metadata.end()) {
            std::vector<long long> s;
            if (!parseWholeList(split->second, '/', 2, 0, kMaxSplits, s) || s[1] < 2 || s[0] >= s[1])
                throw InputError("merge", "'" + p.path + "' has specula:sample_split " + shown(split->second) +
                                             ", not I/K with 0 ≤ I < K and 2 ≤ K ≤ " + std::to_string(kMaxSplits));
            if (spp % s[1] != 0 || block != spp / s[1])
                throw InputError("merge", "'" + p.path + "' has specula:sample_split " + shown(split->second) + " of specula:spp " +
                                             std::to_string(spp) + " with specula:sample_block " + std::to_string(block) +
                                             "; a split's block is spp / K");
            p.splitIndex = int(s[0]), p.splitCount = int(s[1]);
            if (!p.images.find("samples")) throw InputError("merge", "'" + p.path + "' is a sample split without its 'samples' layer");
            checkSampleCounts(p, block);
        }
        std::vector<std::string> names, refNames;
        for (const AovBuffer& b : p.images.aovs)
            if (b.name != "samples") names.push_back(b.name + ":" + std::to_string(b.channels()));
        for (const AovBuffer& b : ref.images.aovs)
            if (b.name != "samples") refNames.push_back(b.name + ":" + std::to_string(b.channels()));
        if (names != refNames) throw InputError("merge", "'" + p.path + "' has other layers than '" + ref.path + "'");
    }

    // Group by tile; each tile is one whole piece or splits 0..K-1 once each.
    std::map<std::array<int, 4>, std::vector<const Piece*>> tiles;
    for (const Piece& p : pieces) tiles[{p.y0, p.x0, p.y1, p.x1}].push_back(&p);
    auto tileName = [](const std::array<int, 4>& t) {
        return std::to_string(t[1]) + "," + std::to_string(t[0]) + "," + std::to_string(t[3]) + "," + std::to_string(t[2]);
    };
    for (auto& [key, list] : tiles) {
        if (list.size() == 1 && list[0]->splitIndex < 0) continue;
        for (const Piece* p : list)
            if (p->splitIndex < 0)
                throw InputError("merge", "tile " + tileName(key) + " is given more than once ('" + list[0]->path + "' and '" +
                                              list[1]->path + "')");
        const int k = list[0]->splitCount;
        std::vector<const Piece*> bySplit(size_t(std::max(k, 1)), nullptr);
        for (const Piece* p : list) {
            if (p->splitIndex < 0 || p->splitCount != k)
                throw InputError("merge", "tile " + tileName(key) + " has pieces of different kinds ('" + list[0]->path + "' and '" +
                                         p->path + "')");
            if (bySplit[size_t(p->splitIndex)])
                throw InputError("merge", "tile " + tileName(key) + " has sample split " + std::to_string(p->splitIndex) + "/" +
                                         std::to_string(k) + " twice ('" + bySplit[size_t(p->splitIndex)]->path + "' and '" +
                                         p->path + "')");
            bySplit[size_t(p->splitIndex)] = p;
        }
        std::string missing;
        int missingCount = 0;
        for (int i = 0; i < k; ++i)
            if (!bySplit[size_t(i)] && ++missingCount <= 8)
                missing += (missing.empty() ? "" : ", ") + std::to_string(i) + "/" + std::to_string(k);
        if (missingCount > 8) missing += " and " + std::to_string(missingCount - 8) + " more";
        if (!missing.empty()) throw InputError("merge", "tile " + tileName(key) + " lacks sample splits " + missing + "; the set is incomplete");
        list = bySplit;
        sum.sampleSplits = std::max(sum.sampleSplits, k);
    }
    // Coverage: every pixel exactly once.
    std::vector<uint8_t> covered(size_t(sum.width) * size_t(sum.height), 0);
    for (auto& [key, list] : tiles)
        for (int y = key[0]; y < key[2]; ++y)
            for (int x = key[1]; x < key[3]; ++x)
                if (covered[size_t(y) * sum.width + x]++)
                    throw InputError("merge", "tile " + tileName(key) + " ('" + list[0]->path + "') overlaps another tile at pixel " +
                                             std::to_string(x) + "," + std::to_string(y));
    for (int y = 0; y < sum.height; ++y)
        for (int x = 0; x < sum.width; ++x)
            if (!covered[size_t(y) * sum.width + x])
                throw InputError("merge", "no piece covers pixel " + std::to_string(x) + "," + std::to_string(y) + " of the " +
                                         std::to_string(sum.width) + "x" + std::to_string(sum.height) + " frame; the set is incomplete");

    // Assemble.
    ImageSet out;
    out.width = sum.width, out.height = sum.height;
    out.metadata = ref.images.metadata;
    out.metadata.erase("specula:sample_split");
    out.metadata["specula:crop"] = "0,0," + std::to_string(sum.width) + "," + std::to_string(sum.height);
    out.matrices = ref.images.matrices;
    out.matrices.erase("worldToNDC");  // the pieces' NDC is their crop's
    for (const AovBuffer& b : ref.images.aovs) {
        if (b.name == "samples") continue;
        AovBuffer o;
        o.name = b.name;
        o.channelNames = b.channelNames;
        o.pixels.assign(size_t(sum.width) * sum.height * b.channelNames.size(), 0.f);
        out.aovs.push_back(std::move(o));
    }
    for (auto& [key, list] : tiles) {
        const int x0 = key[1], y0 = key[0], w = key[3] - key[1], h = key[2] - key[0];
        const bool summed = list[0]->splitIndex >= 0;
        // Each piece's buffers looked up once per tile, not per pixel.
        std::vector<const float*> counts;
        for (const Piece* p : list) counts.push_back(summed ? p->images.find("samples")->pixels.data() : nullptr);
        for (AovBuffer& o : out.aovs) {
            const int ch = o.channels();
            const bool depth = o.name == "depth";
            std::vector<const float*> src;
            for (const Piece* p : list) src.push_back(p->images.find(o.name)->pixels.data());
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const size_t px = size_t(y) * w + x, dst = size_t(y + y0) * sum.width + (x + x0);
                    if (!summed) {
                        for (int c = 0; c < ch; ++c) o.pixels[dst * ch + c] = src[0][px * ch + c];
                        continue;
                    }
                    // The film's sums (core/render/renderer.cpp foldBlock): floats added in split order, depth in
                    // double; then value = sum * (1 / n) with the total count n.
                    int n = 0;
                    for (const float* cnt : counts) n += int(cnt[px]);
                    if (n == 0) continue;
                    const float inv = 1.f / float(n);
                    for (int c = 0; c < ch; ++c) {
                        const size_t k = px * ch + c;
                        if (depth) {
                            double d = double(src[0][k]);
                            for (size_t i = 1; i < src.size(); ++i) d += double(src[i][k]);
                            o.pixels[dst * ch + c] = float(d * inv);
                        } else {
                            float v = src[0][k];
                            for (size_t i = 1; i < src.size(); ++i) v += src[i][k];
                            o.pixels[dst * ch + c] = v * inv;
                        }
                    }
                }
        }
    }
    sum.pieces = int(pieces.size());
    sum.tiles = int(tiles.size());
    try {
        // writeExr reads the frame's last row back before it takes the name: a full disk or a file-size limit, which
        // OpenEXR does not always report, is an error and leaves no truncated frame (core/io/image_read.h).
        writeExr(outPath, out, *ColorConfig::load("builtin"));
    } catch (const ImageIoError& e) {
        // A missing folder, a full disk, no permission: I/O (docs/cli.md, exit 3), not bad input.
        throw IoError(std::string("merge: ") + e.what());
    }
    return sum;
}

// ---- plans ---------------------------------------------------------------------------------------------------------

namespace {

// A plan holds one task per piece: at most the submit limit, each at most a few hundred bytes of JSON.
constexpr long long kMaxTasks = 1000000;
constexpr uintmax_t kMaxPlanBytes = uintmax_t(512) << 20;

std::string shellQuote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// How a command line reads in messages and dry runs: each word shell-quoted unless it is plain.
std::string displayCommand(const std::vector<std::string>& argv) {
    std::string line;
    for (const std::string& a : argv) {
        const bool plain = !a.empty() && std::all_of(a.begin(), a.end(), [](char c) {
            return std::isalnum((unsigned char)c) || std::strchr("-_./=:,%@+", c);
        });
        line += (line.empty() ? "" : " ") + (plain ? a : shellQuote(a));
    }
    return line;
}

// A file of the farm folder, read whole only if it is a regular file no larger than maxBytes (a plan or job list
// replaced by /dev/zero or a FIFO would otherwise be read forever).
std::string readBounded(const fs::path& path, uintmax_t maxBytes, const std::string& what) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw IoError("cannot read " + what + " '" + path.string() + "': no such file");
    if (!fs::is_regular_file(st)) throw IoError(what + " '" + path.string() + "' is not a regular file (a folder, device or FIFO)");
    const uintmax_t bytes = fs::file_size(path, ec);
    if (ec) throw IoError("cannot read " + what + " '" + path.string() + "': " + ec.message());
    if (bytes > maxBytes)
        throw IoError(what + " '" + path.string() + "' holds " + std::to_string(bytes) + " bytes, more than the " +
                      std::to_string(maxBytes >> 20) + " MiB it can");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw IoError("cannot read " + what + " '" + path.string() + "'");
    std::string text(size_t(bytes), '\0');
    f.read(text.data(), std::streamsize(bytes));
    text.resize(size_t(f.gcount()));
    if (f.bad()) throw IoError("cannot read " + what + " '" + path.string() + "'");
    return text;
}

// Writes a farm file atomically (temp file + rename); a full disk or a missing folder is an IoError (exit 3).
void writeText(const fs::path& path, const std::string& text) {
    const fs::path tmp = path.string() + ".tmp";
    std::error_code ec;
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        if (!f) throw IoError("cannot write '" + tmp.string() + "' (does its folder exist?)");
        f << text;
        f.flush();  // a full disk shows at the flush or close, not at <<
        f.close();
        if (!f) {
            fs::remove(tmp, ec);
            throw IoError("cannot write '" + tmp.string() + "' (is the disk full?)");
        }
    }
    fs::rename(tmp, path, ec);
    if (ec) {
        std::error_code ignored;
        fs::remove(tmp, ignored);
        throw IoError("cannot rename '" + tmp.string() + "' to '" + path.string() + "': " + ec.message());
    }
}

// Runs a program (looked up in PATH) with these arguments, without a shell: nothing in them is ever shell syntax.
// Returns its exit status (-1 if it could not run) and its standard output and error.
int runProgram(const std::vector<std::string>& argv, std::string& out) {
    out.clear();
    int fds[2];
    if (pipe(fds) != 0) return -1;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    posix_spawn_file_actions_addclose(&actions, fds[1]);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_t pid = 0;
    const int spawned = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(fds[1]);
    if (spawned != 0) {
        close(fds[0]);
        out = argv[0] + ": " + std::strerror(spawned);
        return -1;
    }
    char buf[4096];
    for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) != 0;) {
        if (n < 0) {
            if (errno == EINTR) continue;
            break;
        }
        if (out.size() < (size_t(1) << 20)) out.append(buf, size_t(n));  // sbatch/squeue say little; keep a bound
    }
    close(fds[0]);
    int st = 0;
    while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
    }
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string trim(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '\r')) s.pop_back();
    return s;
}

// The last line of a command's output: sbatch ends with the line that says why it failed.
std::string lastLine(const std::string& out) {
    const std::string t = trim(out);
    const size_t nl = t.rfind('\n');
    return nl == std::string::npos ? t : t.substr(nl + 1);
}

// ---- the plan, checked -------------------------------------------------------------------------------------------

struct PlanTask {
    int frame = 0;
    std::array<int, 4> crop{};
    int splitIndex = 0, splitCount = 1;
    std::string piece;  // relative to the farm folder, inside it
};

struct Plan {
    Json document;       // as read, for rewriting "attempts"
    fs::path dir;        // the farm folder as the user named it (absolute)
    fs::path planPath;
    std::string name, scene, specula;
    int frameFirst = 0, frameLast = 0, tilesX = 1, tilesY = 1, spp = 1, sppSplit = 1, retries = 0, threadsPerTask = 1;
    int attempts = 0, width = 1, height = 1;
    std::vector<PlanTask> tasks;
    std::vector<std::string> renderArgs;
};

// Typed reads of plan.json; every error names the plan file and the JSON pointer of the value.
struct PlanReader {
    std::string file;

    [[noreturn]] void fail(const std::string& pointer, const std::string& message) const {
        throw InputError(pointer, "in the farm plan '" + file + "': " + message);
    }
    const Json& at(const Json& parent, const std::string& key, const std::string& pointer) const {
        if (!parent.is_object()) fail(pointer, "expected an object, got " + jsonTypeName(parent));
        auto it = parent.find(key);
        if (it == parent.end()) fail(pointer + "/" + key, "missing (the plan was not written by `specula farm submit`)");
        return *it;
    }
    long long integer(const Json& v, const std::string& pointer, long long lo, long long hi) const {
        long long x = 0;
        if (v.is_number_integer() || v.is_number_unsigned()) {
            if (v.is_number_unsigned() && v.get<unsigned long long>() > (unsigned long long)hi) x = hi + 1;
            else x = v.get<long long>();
            if (x >= lo && x <= hi) return x;
        }
        fail(pointer, "expected an integer in " + std::to_string(lo) + " … " + std::to_string(hi) + ", got " +
                          (v.is_number() || v.is_boolean() ? v.dump() : jsonTypeName(v)));
    }
    long long integerAt(const Json& parent, const std::string& key, const std::string& pointer, long long lo, long long hi) const {
        return integer(at(parent, key, pointer), pointer + "/" + key, lo, hi);
    }
    const Json& array(const Json& v, const std::string& pointer, size_t minSize, size_t maxSize) const {
        if (!v.is_array()) fail(pointer, "expected an array, got " + jsonTypeName(v));
        if (v.size() < minSize || v.size() > maxSize)
            fail(pointer, "expected " + (minSize == maxSize ? std::to_string(minSize) : std::to_string(minSize) + " … " + std::to_string(maxSize)) +
                              " items, got " + std::to_string(v.size()));
        return v;
    }
    std::string string(const Json& v, const std::string& pointer) const {
        if (!v.is_string()) fail(pointer, "expected a string, got " + jsonTypeName(v));
        const std::string s = v.get<std::string>();
        if (s.empty() || s.size() > 4096) fail(pointer, "expected a string of 1 … 4096 characters, got " + std::to_string(s.size()));
        if (hasControlCharacter(s)) fail(pointer, shown(s) + " holds a control character (a newline, tab or NUL)");
        return s;
    }
    std::string absolutePath(const Json& parent, const std::string& key, const std::string& pointer) const {
        const std::string s = string(at(parent, key, pointer), pointer + "/" + key);
        if (s[0] != '/') fail(pointer + "/" + key, shown(s) + " is not an absolute path");
        return s;
    }
};

bool isInside(const fs::path& root, const fs::path& p) {
    auto r = root.begin(), q = p.begin();
    for (; r != root.end(); ++r, ++q)
        if (q == p.end() || *r != *q) return false;
    return true;
}

// A path inside the farm folder that a plan names (a piece): relative, without '.' or '..' components, and not leading
// out of the folder through a symlink (its folder, resolved, is inside the resolved farm folder, and the file itself
// is not a symlink). 'folders' caches resolved parent folders (all pieces share pieces/).
void checkInsideFarm(const PlanReader& r, const std::string& pointer, const std::string& rel, const fs::path& root,
                     const fs::path& canonicalRoot, std::map<fs::path, bool>& folders) {
    const fs::path p(rel);
    if (p.is_absolute()) r.fail(pointer, shown(rel) + " is an absolute path; plan paths are relative to the farm folder");
    for (const fs::path& part : p)
        if (part == ".." || part == "." || part.empty())
            r.fail(pointer, shown(rel) + " has a '" + part.string() + "' component; plan paths stay inside the farm folder");
    const fs::path full = root / p;
    const fs::path parent = full.parent_path();
    auto it = folders.find(parent);
    if (it == folders.end()) {
        std::error_code ec;
        const fs::path resolved = fs::weakly_canonical(parent, ec);
        it = folders.emplace(parent, !ec && isInside(canonicalRoot, resolved)).first;
    }
    if (!it->second) r.fail(pointer, shown(rel) + " is in a folder that leads out of the farm folder (a symlink?)");
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(full, ec)))
        r.fail(pointer, shown(rel) + " is a symlink; pieces and frames are plain files inside the farm folder");
}

// Reads farmDir/plan.json and checks all of it (checkPlan in farm.h).
Plan loadPlan(const std::string& farmDir) {
    Plan plan;
    std::error_code ec;
    plan.dir = fs::absolute(farmDir, ec).lexically_normal();
    if (plan.dir.has_filename() == false && plan.dir.has_parent_path()) plan.dir = plan.dir.parent_path();
    plan.planPath = plan.dir / "plan.json";
    if (!fs::exists(plan.planPath, ec))
        throw IoError("'" + farmDir + "' is not a farm folder (no plan.json; see specula farm submit)");
    const PlanReader r{plan.planPath.string()};
    try {
        plan.document = parseStrictJson(readBounded(plan.planPath, kMaxPlanBytes, "the farm plan"), plan.planPath.string());
    } catch (const Json::exception& e) {
        throw InputError("/", "'" + plan.planPath.string() + "' is not a farm plan: " + e.what());
    }
    const Json& d = plan.document;
    if (!d.is_object()) r.fail("/", "expected an object, got " + jsonTypeName(d));
    r.integerAt(d, "version", "", 1, 1);
    plan.name = r.string(r.at(d, "name", ""), "/name");
    if (plan.name.find('/') != std::string::npos || plan.name == "." || plan.name == "..")
        r.fail("/name", shown(plan.name) + " is not a file name (the frames are frames/<name>_FFFF.exr)");
    plan.scene = r.absolutePath(d, "scene", "");
    plan.specula = r.absolutePath(d, "specula", "");
    const std::string written = r.absolutePath(d, "dir", "");
    const Json& frames = r.array(r.at(d, "frames", ""), "/frames", 2, 2);
    plan.frameFirst = int(r.integer(frames[0], "/frames/0", kIntMin, kIntMax));
    plan.frameLast = int(r.integer(frames[1], "/frames/1", plan.frameFirst, std::min<long long>(kIntMax, plan.frameFirst + 99999LL)));
    const Json& size = r.array(r.at(d, "size", ""), "/size", 2, 2);
    plan.width = int(r.integer(size[0], "/size/0", 1, kMaxSide));
    plan.height = int(r.integer(size[1], "/size/1", 1, kMaxSide));
    const Json& tiles = r.array(r.at(d, "tiles", ""), "/tiles", 2, 2);
    plan.tilesX = int(r.integer(tiles[0], "/tiles/0", 1, plan.width));
    plan.tilesY = int(r.integer(tiles[1], "/tiles/1", 1, plan.height));
    plan.spp = int(r.integerAt(d, "spp", "", 1, kMaxSpp));
    plan.sppSplit = int(r.integerAt(d, "spp_split", "", 1, 4096));
    if (plan.spp % plan.sppSplit != 0)
        r.fail("/spp_split", std::to_string(plan.sppSplit) + " does not divide spp " + std::to_string(plan.spp));
    plan.retries = int(r.integerAt(d, "retries", "", 0, 100));
    plan.threadsPerTask = int(r.integerAt(d, "threads_per_task", "", 1, 1024));
    plan.attempts = int(r.integerAt(d, "attempts", "", 0, plan.retries));
    const Json& args = r.array(r.at(d, "render_args", ""), "/render_args", 0, 256);
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string pointer = "/render_args/" + std::to_string(i);
        if (!args[i].is_string()) r.fail(pointer, "expected a string, got " + jsonTypeName(args[i]));
        const std::string a = args[i].get<std::string>();
        if (a.size() > 4096 || a.find('\0') != std::string::npos) r.fail(pointer, "expected a string of at most 4096 characters without NUL");
        plan.renderArgs.push_back(a);
    }

    std::error_code rootEc;
    const fs::path canonicalRoot = fs::canonical(plan.dir, rootEc);
    if (rootEc) throw IoError("cannot resolve the farm folder '" + plan.dir.string() + "': " + rootEc.message());
    std::map<fs::path, bool> folders;
    // frames/<name>_FFFF.exr: the frames folder must be inside the farm too.
    checkInsideFarm(r, "/name", "frames/" + plan.name + "_0000.exr", plan.dir, canonicalRoot, folders);
    const Json& tasks = r.array(r.at(d, "tasks", ""), "/tasks", 1, size_t(kMaxTasks));
    std::set<std::string> pieces;
    plan.tasks.reserve(tasks.size());
    for (size_t i = 0; i < tasks.size(); ++i) {
        const std::string p = "/tasks/" + std::to_string(i);
        const Json& t = tasks[i];
        PlanTask task;
        task.frame = int(r.integerAt(t, "frame", p, plan.frameFirst, plan.frameLast));
        const Json& crop = r.array(r.at(t, "crop", p), p + "/crop", 4, 4);
        for (int k = 0; k < 4; ++k)
            task.crop[size_t(k)] = int(r.integer(crop[size_t(k)], p + "/crop/" + std::to_string(k), 0, k % 2 ? plan.height : plan.width));
        if (task.crop[0] >= task.crop[2] || task.crop[1] >= task.crop[3])
            r.fail(p + "/crop", "expected x0 < x1 and y0 < y1, got " + t.at("crop").dump());
        const Json& split = r.array(r.at(t, "split", p), p + "/split", 2, 2);
        task.splitCount = int(r.integer(split[1], p + "/split/1", plan.sppSplit, plan.sppSplit));
        task.splitIndex = int(r.integer(split[0], p + "/split/0", 0, task.splitCount - 1));
        task.piece = r.string(r.at(t, "piece", p), p + "/piece");
        if (fs::path(task.piece).extension() != ".exr") r.fail(p + "/piece", shown(task.piece) + " does not end in .exr");
        checkInsideFarm(r, p + "/piece", task.piece, plan.dir, canonicalRoot, folders);
        if (!pieces.insert(fs::path(task.piece).lexically_normal().string()).second)
            r.fail(p + "/piece", shown(task.piece) + " is the piece of an earlier task too");
        plan.tasks.push_back(std::move(task));
    }
    // Every frame of the range has a task: otherwise `farm finish` would call a farm complete without that frame.
    std::vector<bool> framesWithTasks(size_t(plan.frameLast - plan.frameFirst) + 1, false);
    for (const PlanTask& t : plan.tasks) framesWithTasks[size_t(t.frame - plan.frameFirst)] = true;
    for (size_t f = 0; f < framesWithTasks.size(); ++f)
        if (!framesWithTasks[f]) r.fail("/tasks", "frame " + std::to_string(plan.frameFirst + long(f)) + " of /frames has no task");
    // The folder the plan was written for must be this one: the scripts name it, so a plan copied or moved elsewhere
    // would have its tasks write into the old folder. Every path above was checked against the folder the user named.
    if (!fs::equivalent(written, plan.dir, ec))
        r.fail("/dir", "the plan was written for the farm folder " + shown(written) + ", not '" + plan.dir.string() +
                           "' (its scripts name that folder; submit the farm again here)");
    return plan;
}

fs::path pieceFile(const Plan& plan, const PlanTask& task) { return plan.dir / task.piece; }

fs::path frameFile(const Plan& plan, int frame) {
    char name[32];
    std::snprintf(name, sizeof name, "_%04d.exr", frame);
    return plan.dir / "frames" / (plan.name + name);
}

// ---- Slurm ---------------------------------------------------------------------------------------------------------

// A Slurm name list (partition, account): names of [A-Za-z0-9._-], separated by commas when 'list'.
void checkSlurmNames(const std::string& option, const std::string& value, bool list) {
    bool ok = !value.empty() && value.size() <= 256;
    bool lastWasComma = true;
    for (char c : value) {
        const bool comma = c == ',';
        if (comma ? (!list || lastWasComma) : !(std::isalnum((unsigned char)c) || c == '.' || c == '_' || c == '-')) ok = false;
        lastWasComma = comma;
    }
    if (lastWasComma) ok = false;
    if (!ok)
        throw InputError(option, shown(value) + " is not a Slurm " + option.substr(2) + " name: use 1 … 256 letters, digits, '.', '_' and '-'" +
                                     (list ? " (several names separated by commas)" : ""));
}

// The array indices as Slurm's --array list with ranges ("0-7,9,12-13"): 1e6 single indices would pass the limit of
// one argument's length.
std::string arraySpec(const std::vector<int>& tasks) {
    std::string spec;
    for (size_t i = 0; i < tasks.size();) {
        size_t j = i;
        while (j + 1 < tasks.size() && tasks[j + 1] == tasks[j] + 1) ++j;
        spec += (spec.empty() ? "" : ",") + std::to_string(tasks[i]) + (j > i ? "-" + std::to_string(tasks[j]) : "");
        i = j + 1;
    }
    return spec;
}

// The job id sbatch --parsable printed ("123" or "123;cluster"): digits only, or the submission is treated as failed.
std::string parsedJobId(const std::string& out) {
    const std::string line = lastLine(out);
    const std::string id = line.substr(0, line.find(';'));
    if (id.empty() || id.size() > 20 || !std::all_of(id.begin(), id.end(), [](char c) { return std::isdigit((unsigned char)c); }))
        return "";
    return id;
}

std::vector<std::string> sbatchArgv(const fs::path& dir, const std::string& dependency, const std::string& array, const std::string& script) {
    // --chdir: the scripts' log paths are relative to it, so no path sits in an #SBATCH line (sbatch splits those
    // lines at spaces and quotes, and reads '#' as a comment), while this argv reaches sbatch word for word.
    std::vector<std::string> argv = {"sbatch", "--parsable", "--chdir=" + dir.string()};
    if (!dependency.empty()) argv.push_back("--dependency=afterany:" + dependency);
    if (!array.empty()) argv.push_back("--array=" + array);
    argv.push_back((dir / script).string());
    return argv;
}

// Queues the task array for these indices; returns its job id. Throws IoError (nothing queued) when sbatch refuses.
std::string submitArray(const fs::path& dir, const std::vector<int>& tasks, std::vector<std::string>& commands) {
    const std::vector<std::string> argv = sbatchArgv(dir, "", arraySpec(tasks), "render.sbatch");
    commands.push_back(displayCommand(argv));
    std::string out;
    const int rc = runProgram(argv, out);
    const std::string id = rc == 0 ? parsedJobId(out) : "";
    if (id.empty()) throw IoError("sbatch failed: " + shown(lastLine(out)) + (rc == 0 ? " (no job id)" : ""));
    return id;
}

// Queues the finish job after the array job; records both in jobs.txt. When sbatch refuses the finish job, the array
// is queued: the error says how to finish by hand.
std::string submitFinish(const fs::path& dir, const std::string& renderJob, const std::vector<int>& tasks,
                         std::vector<std::string>& commands) {
    const std::vector<std::string> argv = sbatchArgv(dir, renderJob, "", "finish.sbatch");
    commands.push_back(displayCommand(argv));
    std::string out;
    const int rc = runProgram(argv, out);
    const std::string finishJob = rc == 0 ? parsedJobId(out) : "";
    std::ofstream jobs(dir / "jobs.txt", std::ios::app);
    jobs << renderJob << " render " << arraySpec(tasks) << "\n";
    if (finishJob.empty())
        throw IoError("sbatch (finish job) failed: " + shown(lastLine(out)) + "; the render job " + renderJob +
                      " is queued: run `specula farm finish " + shellQuote(dir.string()) + "` when it ends");
    jobs << finishJob << " finish\n";
    return finishJob;
}

}  // namespace

std::string slurmJobName(const std::string& sceneStem) {
    std::string name = "specula-";
    for (char c : sceneStem) {
        if (name.size() >= 64) break;
        name += std::isalnum((unsigned char)c) || c == '.' || c == '_' || c == '-' ? c : '_';
    }
    return name;
}

int checkPlan(const std::string& farmDir) { return int(loadPlan(farmDir).tasks.size()); }

SubmitResult submit(const SubmitOptions& o) {
    SubmitResult r;
    std::error_code ec;
    // Every value that reaches a script, checked before anything is read or written (issue 35).
    if (!o.partition.empty()) checkSlurmNames("--partition", o.partition, true);
    if (!o.account.empty()) checkSlurmNames("--account", o.account, false);
    if (o.executable.empty() || o.executable[0] != '/' || hasControlCharacter(o.executable))
        throw InputError("farm submit", "the specula executable " + shown(o.executable) +
                                            " must be an absolute path without control characters (the tasks run it on every node)");
    for (size_t i = 0; i < o.extraRenderArgs.size(); ++i)
        if (o.extraRenderArgs[i].find('\0') != std::string::npos || o.extraRenderArgs[i].size() > 4096)
            throw InputError("farm submit", "render argument " + std::to_string(i) + " holds a NUL or is longer than 4096 characters");
    if (o.extraRenderArgs.size() > 256) throw InputError("farm submit", "more than 256 render arguments");
    const std::string scene = fs::absolute(o.scene, ec).lexically_normal().string();
    if (hasControlCharacter(scene))
        throw InputError("farm submit", "the scene path " + shown(scene) + " holds a control character (a newline or tab); rename the file");
    SceneOverrides ov;
    ov.spp = o.spp;
    Json doc;
    try {
        doc = Json::parse(readJsonText(scene));  // at most 256 MiB (a scene named /dev/zero is refused, not read forever)
    } catch (const Json::exception&) {
        doc = Json::object();  // the loader below reports it properly
    }
    const AnimationRange range = animationRangeOf(doc);
    const int first = o.frameFirst.value_or(range.present ? range.frameStart : 0);
    const int last = o.frameLast.value_or(range.present ? range.frameEnd : first);
    if (last < first) throw InputError("farm submit", "--frames " + std::to_string(first) + "-" + std::to_string(last) + " is an empty range");
    if ((long long)last - first >= 100000) throw InputError("farm submit", "--frames spans more than 100000 frames");
    ov.frame = first;
    const Scene s = loadScene(scene, ov);  // validates the scene (and the first frame) before anything is written
    if (range.present) ov.frame = last, (void)loadScene(scene, ov);
    const int W = s.render.width, H = s.render.height, spp = s.render.spp;
    if (o.tilesX < 1 || o.tilesY < 1 || o.tilesX > W || o.tilesY > H)
        throw InputError("farm submit", "--tiles " + std::to_string(o.tilesX) + "x" + std::to_string(o.tilesY) + " does not fit a " +
                                 std::to_string(W) + "x" + std::to_string(H) + " image");
    if (o.sppSplit < 1 || spp % o.sppSplit != 0)
        throw InputError("farm submit", "--spp-split " + std::to_string(o.sppSplit) + " does not divide the " + std::to_string(spp) + " samples per pixel");
    if (o.sppSplit > 1 && s.render.sampleBlock > 0 && s.render.sampleBlock != spp / o.sppSplit)
        throw InputError("/render/sample_block", "the scene's sample_block " + std::to_string(s.render.sampleBlock) +
                                                     " differs from --spp-split's block of " + std::to_string(spp / o.sppSplit));
    const std::string name = fs::path(scene).stem().string();
    const fs::path dir = fs::absolute(o.farmDir.empty() ? "farm-" + name : o.farmDir, ec).lexically_normal();
    if (hasControlCharacter(dir.string()))
        throw InputError("--dir", "the farm folder " + shown(dir.string()) +
                                      " holds a control character (a newline or tab); Slurm scripts and logs name it");
    // Slurm expands %-patterns (%j, %A, ...) in the log path, its working-folder prefix included, and a backslash
    // turns the patterns off: a farm folder with either would put the logs elsewhere (the farm test saw "100%j" become
    // "1003").
    if (dir.string().find_first_of("%\\") != std::string::npos)
        throw InputError("--dir", "the farm folder " + shown(dir.string()) +
                                      " holds '%' or '\\', which Slurm reads as file-name patterns in the task logs' path; choose another folder");
    if (fs::exists(dir / "plan.json", ec))
        throw IoError("'" + dir.string() + "' already holds a farm plan; use another --dir (or specula farm status)");
    const long long taskCount = (long long)(last - first + 1) * o.tilesX * o.tilesY * o.sppSplit;
    if (taskCount > kMaxTasks) throw InputError("farm submit", "the farm would have " + std::to_string(taskCount) + " tasks (limit 1000000)");

    Json plan;
    plan["version"] = 1;
    plan["name"] = name;
    plan["scene"] = scene;
    plan["dir"] = dir.string();
    plan["specula"] = o.executable;
    plan["frames"] = {first, last};
    plan["tiles"] = {o.tilesX, o.tilesY};
    plan["spp"] = spp;
    plan["spp_split"] = o.sppSplit;
    plan["retries"] = o.retries;
    plan["threads_per_task"] = o.threadsPerTask;
    plan["attempts"] = 0;
    plan["size"] = {W, H};
    Json tasks = Json::array();
    for (int f = first; f <= last; ++f)
        for (int ty = 0; ty < o.tilesY; ++ty)
            for (int tx = 0; tx < o.tilesX; ++tx)
                for (int sp = 0; sp < o.sppSplit; ++sp) {
                    // Tile edges at floor(i W / N): every pixel in exactly one tile.
                    const int x0 = int((long long)tx * W / o.tilesX), x1 = int((long long)(tx + 1) * W / o.tilesX);
                    const int y0 = int((long long)ty * H / o.tilesY), y1 = int((long long)(ty + 1) * H / o.tilesY);
                    char piece[96];
                    std::snprintf(piece, sizeof piece, "pieces/f%04d_x%02d_y%02d_s%02d.exr", f, tx, ty, sp);
                    Json t;
                    t["frame"] = f;
                    t["crop"] = {x0, y0, x1, y1};
                    t["split"] = {sp, o.sppSplit};
                    t["piece"] = piece;
                    tasks.push_back(t);
                }
    plan["tasks"] = tasks;
    plan["render_args"] = o.extraRenderArgs;
    r.farmDir = dir.string();
    r.tasks = int(tasks.size());
    r.frames = last - first + 1;

    // Scripts: the array task runs `specula farm task DIR INDEX`, which execs the piece's render (or does nothing when
    // the piece exists, so a resubmission renders only what is missing). What the #SBATCH lines hold is checked above
    // (names) or generated here (numbers, the fixed relative log paths); the exec line's words are shell-quoted.
    const std::string exe = shellQuote(o.executable), d = shellQuote(dir.string());
    std::string common = "#!/bin/bash\n#SBATCH --job-name=" + slurmJobName(name) + "\n";
    if (!o.partition.empty()) common += "#SBATCH --partition=" + o.partition + "\n";
    if (!o.account.empty()) common += "#SBATCH --account=" + o.account + "\n";
    const std::string renderScript = common + "#SBATCH --cpus-per-task=" + std::to_string(o.threadsPerTask) +
                                     "\n#SBATCH --requeue\n#SBATCH --output=logs/task_%A_%a.log"
                                     "\n# One piece of the render per array task (docs/farm.md).\nexec " + exe + " farm task " + d +
                                     " \"$SLURM_ARRAY_TASK_ID\"\n";
    const std::string finishScript = common + "#SBATCH --cpus-per-task=1\n#SBATCH --output=logs/finish_%j.log"
                                     "\n# Merge finished frames; resubmit missing pieces while retries are left.\nexec " + exe +
                                     " farm finish " + d + "\n";
    for (const char* sub : {"pieces", "logs", "frames"}) {
        fs::create_directories(dir / sub, ec);
        if (ec) throw IoError("cannot create the farm folder '" + (dir / sub).string() + "': " + ec.message());
    }
    writeText(dir / "render.sbatch", renderScript);
    writeText(dir / "finish.sbatch", finishScript);
    fs::permissions(dir / "render.sbatch", fs::perms::owner_exec, fs::perm_options::add, ec);
    fs::permissions(dir / "finish.sbatch", fs::perms::owner_exec, fs::perm_options::add, ec);
    std::vector<int> all(size_t(r.tasks));
    for (int i = 0; i < r.tasks; ++i) all[size_t(i)] = i;
    if (o.dryRun) {
        r.commands.push_back(displayCommand(sbatchArgv(dir, "", arraySpec(all), "render.sbatch")));
        r.commands.push_back(displayCommand(sbatchArgv(dir, "<render job>", "", "finish.sbatch")));
        plan["dry_run"] = true;
        writeText(dir / "plan.json", plan.dump(1));
        return r;
    }
    // The plan is written before the array is queued: a task may start at once and reads it.
    writeText(dir / "plan.json", plan.dump(1));
    std::string renderJob;
    try {
        renderJob = submitArray(dir, all, r.commands);
    } catch (const IoError&) {
        // Nothing was queued when the array itself was refused: take the plan back, so that the same command can be
        // run again (a plan left behind would make the folder look like a running farm).
        fs::remove(dir / "plan.json", ec);
        throw;
    }
    r.jobIds = {renderJob, submitFinish(dir, renderJob, all, r.commands)};
    return r;
}

std::vector<std::string> taskCommand(const std::string& farmDir, int taskIndex) {
    const Plan plan = loadPlan(farmDir);
    if (taskIndex < 0 || size_t(taskIndex) >= plan.tasks.size())
        throw InputError("farm task", "task " + std::to_string(taskIndex) + " is not in the plan (0-" + std::to_string(plan.tasks.size() - 1) + ")");
    const PlanTask& t = plan.tasks[size_t(taskIndex)];
    const std::string piece = pieceFile(plan, t).string();
    std::error_code ec;
    if (fs::exists(piece, ec)) return {};
    // An argv, never a shell line: render_args reach `specula render` word for word.
    std::vector<std::string> argv = {plan.specula, "render", plan.scene, "--frame", std::to_string(t.frame), "--crop",
                                     std::to_string(t.crop[0]) + "," + std::to_string(t.crop[1]) + "," + std::to_string(t.crop[2]) +
                                         "," + std::to_string(t.crop[3])};
    if (plan.sppSplit > 1) {
        argv.push_back("--sample-split");
        argv.push_back(std::to_string(t.splitIndex) + "/" + std::to_string(t.splitCount));
    }
    argv.push_back("--spp");
    argv.push_back(std::to_string(plan.spp));
    argv.push_back("--threads");  // the CPUs Slurm gave the task (--cpus-per-task)
    argv.push_back(std::to_string(plan.threadsPerTask));
    for (const std::string& a : plan.renderArgs) argv.push_back(a);
    argv.push_back("--progress");
    argv.push_back("json");
    argv.push_back("-o");
    argv.push_back(piece);
    return argv;
}

std::string finish(const std::string& farmDir) {
    Plan plan = loadPlan(farmDir);
    std::error_code ec;
    std::map<int, std::vector<std::string>> byFrame;
    std::vector<int> missing;
    for (size_t i = 0; i < plan.tasks.size(); ++i) {
        const std::string piece = pieceFile(plan, plan.tasks[i]).string();
        if (fs::exists(piece, ec))
            byFrame[plan.tasks[i].frame].push_back(piece);
        else
            missing.push_back(int(i));
    }
    std::set<int> incomplete;
    for (int i : missing) incomplete.insert(plan.tasks[size_t(i)].frame);
    int merged = 0, kept = 0;
    for (int f = plan.frameFirst; f <= plan.frameLast; ++f) {
        if (incomplete.count(f)) continue;
        const std::string out = frameFile(plan, f).string();
        if (fs::exists(out, ec)) {
            ++kept;  // a finished frame is never overwritten
            continue;
        }
        mergePieces(byFrame[f], out, false);
        ++merged;
    }
    std::string report = "merged " + std::to_string(merged) + " frame(s), " + std::to_string(kept) + " already written";
    if (missing.empty()) return report + "; the farm is complete";
    std::string list;
    for (size_t i = 0; i < missing.size() && i < 20; ++i) list += (i ? ", " : "") + plan.tasks[size_t(missing[i])].piece;
    if (missing.size() > 20) list += ", ...";
    if (plan.attempts >= plan.retries)
        throw IoError(report + "; " + std::to_string(missing.size()) + " piece(s) still missing after " + std::to_string(plan.attempts) +
                      " resubmission(s): " + list + " (see the task logs in " + (plan.dir / "logs").string() + ")");
    // The attempt counts once sbatch has queued it: a refused sbatch (the controller down, a full queue) throws here
    // with "attempts" as it was, so running `farm finish` again retries with the same budget.
    std::vector<std::string> commands;
    const std::string renderJob = submitArray(plan.dir, missing, commands);
    plan.document["attempts"] = plan.attempts + 1;
    writeText(plan.planPath, plan.document.dump(1));
    const std::string finishJob = submitFinish(plan.dir, renderJob, missing, commands);
    (void)finishJob;
    return report + "; resubmitted " + std::to_string(missing.size()) + " missing piece(s) (" + list + ") as job " + renderJob +
           ", attempt " + std::to_string(plan.attempts + 1) + " of " + std::to_string(plan.retries);
}

std::string status(const std::string& farmDir) {
    const Plan plan = loadPlan(farmDir);
    std::error_code ec;
    int done = 0;
    for (const PlanTask& t : plan.tasks) done += fs::exists(pieceFile(plan, t), ec) ? 1 : 0;
    int frames = 0, written = 0;
    for (int f = plan.frameFirst; f <= plan.frameLast; ++f, ++frames) written += fs::exists(frameFile(plan, f), ec) ? 1 : 0;
    std::ostringstream s;
    s << "farm " << plan.dir.string() << ": " << done << "/" << plan.tasks.size() << " pieces, " << written << "/" << frames
      << " frames written, " << plan.attempts << " resubmission(s)\n";
    // jobs.txt is the farm's own record, but it is read as untrusted text: job ids are digits, anything else is skipped.
    std::vector<std::string> ids;
    if (fs::exists(plan.dir / "jobs.txt", ec)) {
        std::istringstream jobs(readBounded(plan.dir / "jobs.txt", uintmax_t(16) << 20, "the job list"));
        std::string line;
        while (std::getline(jobs, line)) {
            const std::string id = line.substr(0, line.find(' '));
            if (!id.empty() && id.size() <= 20 && std::all_of(id.begin(), id.end(), [](char c) { return std::isdigit((unsigned char)c); }))
                ids.push_back(id);
        }
    }
    if (ids.empty()) return s.str() + "no jobs submitted (a dry run?)\n";
    std::string joined;
    for (const std::string& id : ids) joined += (joined.empty() ? "" : ",") + id;
    std::string out;
    if (runProgram({"squeue", "-h", "-j", joined, "-o", "%i %T %R"}, out) == 0)
        s << (trim(out).empty() ? "squeue: no job of the farm is queued or running\n" : "squeue:\n" + trim(out) + "\n");
    else
        s << "squeue unavailable: " << lastLine(out) << "\n";
    if (runProgram({"sacct", "-n", "-P", "-X", "-j", joined, "-o", "JobID,State,ExitCode"}, out) == 0 && !trim(out).empty()) {
        s << "sacct:\n" << trim(out) << "\n";
    } else {
        // Accounting off: the tasks' logs say how each ended (the last progress event).
        s << "sacct unavailable (accounting off); task logs:\n";
        std::vector<fs::path> logs;
        for (const auto& e : fs::directory_iterator(plan.dir / "logs", ec))
            if (e.is_regular_file(ec)) logs.push_back(e.path());
        std::sort(logs.begin(), logs.end());
        for (const fs::path& l : logs) {
            // The last line of the last 64 KiB: a log is never read whole.
            std::ifstream f(l, std::ios::binary);
            f.seekg(0, std::ios::end);
            const std::streamoff bytes = f.tellg();
            const std::streamoff from = std::max<std::streamoff>(0, bytes - 65536);
            f.seekg(from);
            std::string tail(size_t(std::max<std::streamoff>(0, bytes - from)), '\0');
            f.read(tail.data(), std::streamsize(tail.size()));
            const std::string last = lastLine(tail);
            s << "  " << l.filename().string() << ": " << (last.size() > 160 ? last.substr(0, 160) + "..." : last) << "\n";
        }
    }
    return s.str();
}

}  // namespace specula::farm
