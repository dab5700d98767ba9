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
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace specula::farm {

namespace {

// ---- piece metadata ------------------------------------------------------------------------------------------------

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

bool parseInts(const std::string& text, char sep, std::vector<long long>& out) {
    out.clear();
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, sep)) {
        try {
            size_t used = 0;
            out.push_back(std::stoll(item, &used));
            if (used != item.size()) return false;
        } catch (const std::exception&) {
            return false;
        }
    }
    return true;
}

constexpr long long kMaxSide = 16384;

}  // namespace

// ---- merge ---------------------------------------------------------------------------------------------------------

MergeSummary mergePieces(const std::vector<std::string>& paths, const std::string& outPath, bool overwrite) {
    if (paths.empty()) throw InputError("merge", "merge needs at least one piece");
    if (fs::path(outPath).extension() != ".exr") throw InputError("merge", "merge writes an EXR: '" + outPath + "' does not end in .exr");
    std::error_code ec;
    for (const std::string& p : paths)
        if (fs::exists(outPath, ec) && fs::equivalent(p, outPath, ec))
            throw InputError("merge", "the output '" + outPath + "' is one of the pieces; choose another file");
    if (!overwrite && fs::exists(outPath, ec))
        throw IoError("'" + outPath + "' exists; merge never overwrites a finished frame (pass --force to replace it)");

    std::vector<Piece> pieces;
    for (const std::string& path : paths) {
        Piece p;
        p.path = path;
        p.images = readImageSet(path);
        pieces.push_back(std::move(p));
    }
    const Piece& ref = pieces.front();
    MergeSummary sum;
    sum.sceneHash = meta(ref, "scene_hash");
    std::vector<long long> size;
    if (!parseInts(meta(ref, "frame_size"), 'x', size) || size.size() != 2 || size[0] < 1 || size[1] < 1 ||
        size[0] > kMaxSide || size[1] > kMaxSide)
        throw InputError("merge", "'" + ref.path + "' has a malformed specula:frame_size '" + meta(ref, "frame_size") + "'");
    sum.width = int(size[0]), sum.height = int(size[1]);
    sum.frame = std::stoi(meta(ref, "frame"));
    for (Piece& p : pieces) {
        for (const char* key : {"scene_hash", "frame", "frame_size", "spp", "seed", "sample_block"})
            if (meta(p, key) != meta(ref, key))
                throw InputError("merge", "'" + p.path + "' belongs to another render than '" + ref.path + "' (specula:" + key +
                                         " " + meta(p, key) + " against " + meta(ref, key) + ")");
        auto partial = p.images.metadata.find("specula:partial");
        if (partial != p.images.metadata.end() && partial->second == "true")
            throw InputError("merge", "'" + p.path + "' is a partial (interrupted) render; render that piece again");
        std::vector<long long> c;
        if (!parseInts(meta(p, "crop"), ',', c) || c.size() != 4 || c[0] < 0 || c[1] < 0 || c[2] > sum.width ||
            c[3] > sum.height || c[0] >= c[2] || c[1] >= c[3] || p.images.width != c[2] - c[0] || p.images.height != c[3] - c[1])
            throw InputError("merge", "'" + p.path + "' has a crop window '" + meta(p, "crop") + "' that does not fit its " +
                                     std::to_string(p.images.width) + "x" + std::to_string(p.images.height) + " pixels in the " +
                                     std::to_string(sum.width) + "x" + std::to_string(sum.height) + " frame");
        p.x0 = int(c[0]), p.y0 = int(c[1]), p.x1 = int(c[2]), p.y1 = int(c[3]);
        auto split = p.images.metadata.find("specula:sample_split");
        if (split != p.images.metadata.end()) {
            std::vector<long long> s;
            if (!parseInts(split->second, '/', s) || s.size() != 2 || s[1] < 2 || s[0] < 0 || s[0] >= s[1] || s[1] > (1 << 20))
                throw InputError("merge", "'" + p.path + "' has a malformed specula:sample_split '" + split->second + "'");
            p.splitIndex = int(s[0]), p.splitCount = int(s[1]);
            if (!p.images.find("samples")) throw InputError("merge", "'" + p.path + "' is a sample split without its 'samples' layer");
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
        for (int i = 0; i < k; ++i)
            if (!bySplit[size_t(i)]) missing += (missing.empty() ? "" : ", ") + std::to_string(i) + "/" + std::to_string(k);
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
    writeExr(outPath, out, *ColorConfig::load("builtin"));
    return sum;
}

// ---- plans ---------------------------------------------------------------------------------------------------------

namespace {

std::string shellQuote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

std::string readText(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw IoError("cannot read '" + path + "'");
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

void writeText(const std::string& path, const std::string& text) {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        if (!f) throw IoError("cannot write '" + tmp + "'");
        f << text;
        if (!f) throw IoError("cannot write '" + tmp + "'");
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw IoError("cannot rename '" + tmp + "' to '" + path + "': " + ec.message());
}

// Runs a command line through the shell; returns its exit status and standard output.
int runCommand(const std::string& cmd, std::string& out) {
    out.clear();
    FILE* p = popen((cmd + " 2>&1").c_str(), "r");
    if (!p) return -1;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    const int st = pclose(p);
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

Json loadPlan(const std::string& dir) {
    const std::string path = (fs::path(dir) / "plan.json").string();
    std::error_code ec;
    if (!fs::exists(path, ec)) throw IoError("'" + dir + "' is not a farm folder (no plan.json; see specula farm submit)");
    try {
        return Json::parse(readText(path));
    } catch (const Json::exception& e) {
        throw InputError("farm submit", "'" + path + "' is not a farm plan: " + std::string(e.what()));
    }
}

std::string pieceFile(const Json& plan, const Json& task) {
    return (fs::path(plan.at("dir").get<std::string>()) / task.at("piece").get<std::string>()).string();
}

std::string frameFile(const Json& plan, int frame) {
    char name[64];
    std::snprintf(name, sizeof name, "_%04d.exr", frame);
    return (fs::path(plan.at("dir").get<std::string>()) / "frames" / (plan.at("name").get<std::string>() + name)).string();
}

// sbatch for the given task indices, then the finish job after them; returns the job ids and records them.
std::vector<std::string> submitJobs(const Json& plan, const std::vector<int>& tasks, std::vector<std::string>& commands,
                                    bool dryRun) {
    const fs::path dir = plan.at("dir").get<std::string>();
    std::string array;
    for (size_t i = 0; i < tasks.size(); ++i) array += (i ? "," : "") + std::to_string(tasks[i]);
    const std::string renderCmd = "sbatch --parsable --array=" + array + " " + shellQuote((dir / "render.sbatch").string());
    commands.push_back(renderCmd);
    if (dryRun) {
        commands.push_back("sbatch --parsable --dependency=afterany:<render job> " + shellQuote((dir / "finish.sbatch").string()));
        return {};
    }
    std::string out;
    if (runCommand(renderCmd, out) != 0) throw IoError("sbatch failed: " + lastLine(out));
    const std::string renderJob = trim(out).substr(0, trim(out).find(';'));
    const std::string finishCmd =
        "sbatch --parsable --dependency=afterany:" + renderJob + " " + shellQuote((dir / "finish.sbatch").string());
    commands.push_back(finishCmd);
    if (runCommand(finishCmd, out) != 0) {
        std::ofstream jobs(dir / "jobs.txt", std::ios::app);
        jobs << renderJob << " render " << array << "\n";
        throw IoError("sbatch (finish job) failed: " + lastLine(out) + "; the render job " + renderJob +
                      " is queued: run `specula farm finish " + dir.string() + "` when it ends");
    }
    const std::string finishJob = trim(out).substr(0, trim(out).find(';'));
    std::ofstream jobs(dir / "jobs.txt", std::ios::app);
    jobs << renderJob << " render " << array << "\n" << finishJob << " finish\n";
    return {renderJob, finishJob};
}

}  // namespace

SubmitResult submit(const SubmitOptions& o) {
    SubmitResult r;
    std::error_code ec;
    const std::string scene = fs::absolute(o.scene, ec).lexically_normal().string();
    SceneOverrides ov;
    ov.spp = o.spp;
    Json doc;
    try {
        doc = Json::parse(readText(scene));
    } catch (const Json::exception&) {
        doc = Json::object();  // the loader below reports it properly
    }
    const AnimationRange range = animationRangeOf(doc);
    const int first = o.frameFirst.value_or(range.present ? range.frameStart : 0);
    const int last = o.frameLast.value_or(range.present ? range.frameEnd : first);
    if (last < first) throw InputError("farm submit", "--frames " + std::to_string(first) + "-" + std::to_string(last) + " is an empty range");
    if (last - first >= 100000) throw InputError("farm submit", "--frames spans more than 100000 frames");
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
    if (fs::exists(dir / "plan.json", ec))
        throw IoError("'" + dir.string() + "' already holds a farm plan; use another --dir (or specula farm status)");
    const long long taskCount = (long long)(last - first + 1) * o.tilesX * o.tilesY * o.sppSplit;
    if (taskCount > 1000000) throw InputError("farm submit", "the farm would have " + std::to_string(taskCount) + " tasks (limit 1000000)");

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
    std::string lines;
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
    // the piece exists, so a resubmission renders only what is missing).
    const std::string exe = shellQuote(o.executable), d = shellQuote(dir.string());
    std::string common = "#!/bin/bash\n#SBATCH --job-name=specula-" + name + "\n";
    if (!o.partition.empty()) common += "#SBATCH --partition=" + o.partition + "\n";
    const std::string renderScript = common + "#SBATCH --cpus-per-task=" + std::to_string(o.threadsPerTask) +
                                     "\n#SBATCH --requeue\n#SBATCH --output=" + (dir / "logs" / "task_%A_%a.log").string() +
                                     "\n# One piece of the render per array task (docs/farm.md).\nexec " + exe + " farm task " + d +
                                     " \"$SLURM_ARRAY_TASK_ID\"\n";
    const std::string finishScript = common + "#SBATCH --cpus-per-task=1\n#SBATCH --output=" + (dir / "logs" / "finish_%j.log").string() +
                                     "\n# Merge finished frames; resubmit missing pieces while retries are left.\nexec " + exe +
                                     " farm finish " + d + "\n";
    fs::create_directories(dir / "pieces", ec);
    fs::create_directories(dir / "logs", ec);
    fs::create_directories(dir / "frames", ec);
    if (ec) throw IoError("cannot create the farm folder '" + dir.string() + "': " + ec.message());
    writeText((dir / "render.sbatch").string(), renderScript);
    writeText((dir / "finish.sbatch").string(), finishScript);
    fs::permissions(dir / "render.sbatch", fs::perms::owner_exec, fs::perm_options::add, ec);
    fs::permissions(dir / "finish.sbatch", fs::perms::owner_exec, fs::perm_options::add, ec);
    std::vector<int> all(size_t(r.tasks));
    for (int i = 0; i < r.tasks; ++i) all[size_t(i)] = i;
    if (o.dryRun) {
        submitJobs(plan, all, r.commands, true);
        plan["dry_run"] = true;
        writeText((dir / "plan.json").string(), plan.dump(1));
        return r;
    }
    writeText((dir / "plan.json").string(), plan.dump(1));
    try {
        r.jobIds = submitJobs(plan, all, r.commands, false);
    } catch (const IoError&) {
        // Nothing was queued when the array itself was refused: take the plan back, so that the same command can be
        // run again (a plan left behind would make the folder look like a running farm).
        std::ifstream jobs(dir / "jobs.txt");
        if (!jobs) fs::remove(dir / "plan.json", ec);
        throw;
    }
    return r;
}

std::vector<std::string> taskCommand(const std::string& farmDir, int taskIndex) {
    const Json plan = loadPlan(farmDir);
    const Json& tasks = plan.at("tasks");
    if (taskIndex < 0 || size_t(taskIndex) >= tasks.size())
        throw InputError("farm task", "task " + std::to_string(taskIndex) + " is not in the plan (0-" + std::to_string(tasks.size() - 1) + ")");
    const Json& t = tasks.at(size_t(taskIndex));
    const std::string piece = pieceFile(plan, t);
    std::error_code ec;
    if (fs::exists(piece, ec)) return {};
    std::vector<std::string> argv = {plan.at("specula").get<std::string>(), "render", plan.at("scene").get<std::string>(),
                                     "--frame", std::to_string(t.at("frame").get<int>())};
    const Json& c = t.at("crop");
    argv.push_back("--crop");
    argv.push_back(std::to_string(c[0].get<int>()) + "," + std::to_string(c[1].get<int>()) + "," + std::to_string(c[2].get<int>()) +
                   "," + std::to_string(c[3].get<int>()));
    if (plan.at("spp_split").get<int>() > 1) {
        argv.push_back("--sample-split");
        argv.push_back(std::to_string(t.at("split")[0].get<int>()) + "/" + std::to_string(t.at("split")[1].get<int>()));
    }
    argv.push_back("--spp");
    argv.push_back(std::to_string(plan.at("spp").get<int>()));
    argv.push_back("--threads");  // the CPUs Slurm gave the task (--cpus-per-task)
    argv.push_back(std::to_string(plan.value("threads_per_task", 1)));
    for (const Json& a : plan.at("render_args")) argv.push_back(a.get<std::string>());
    argv.push_back("--progress");
    argv.push_back("json");
    argv.push_back("-o");
    argv.push_back(piece);
    return argv;
}

std::string finish(const std::string& farmDir) {
    Json plan = loadPlan(farmDir);
    std::error_code ec;
    std::map<int, std::vector<std::string>> byFrame;
    std::vector<int> missing;
    const Json& tasks = plan.at("tasks");
    for (size_t i = 0; i < tasks.size(); ++i) {
        const std::string piece = pieceFile(plan, tasks[i]);
        if (fs::exists(piece, ec))
            byFrame[tasks[i].at("frame").get<int>()].push_back(piece);
        else
            missing.push_back(int(i));
    }
    std::set<int> incomplete;
    for (int i : missing) incomplete.insert(tasks[size_t(i)].at("frame").get<int>());
    int merged = 0, kept = 0;
    for (int f = plan.at("frames")[0].get<int>(); f <= plan.at("frames")[1].get<int>(); ++f) {
        if (incomplete.count(f)) continue;
        const std::string out = frameFile(plan, f);
        if (fs::exists(out, ec)) {
            ++kept;  // a finished frame is never overwritten
            continue;
        }
        mergePieces(byFrame[f], out, false);
        ++merged;
    }
    std::string report = "merged " + std::to_string(merged) + " frame(s), " + std::to_string(kept) + " already written";
    if (missing.empty()) return report + "; the farm is complete";
    const int attempts = plan.at("attempts").get<int>();
    std::string list;
    for (size_t i = 0; i < missing.size() && i < 20; ++i) list += (i ? ", " : "") + tasks[size_t(missing[i])].at("piece").get<std::string>();
    if (missing.size() > 20) list += ", ...";
    if (attempts >= plan.at("retries").get<int>())
        throw IoError(report + "; " + std::to_string(missing.size()) + " piece(s) still missing after " + std::to_string(attempts) +
                      " resubmission(s): " + list + " (see the task logs in " + (fs::path(farmDir) / "logs").string() + ")");
    plan["attempts"] = attempts + 1;
    writeText((fs::path(plan.at("dir").get<std::string>()) / "plan.json").string(), plan.dump(1));
    std::vector<std::string> commands;
    std::vector<std::string> ids = submitJobs(plan, missing, commands, false);
    return report + "; resubmitted " + std::to_string(missing.size()) + " missing piece(s) (" + list + ") as job " + ids[0] +
           ", attempt " + std::to_string(attempts + 1) + " of " + std::to_string(plan.at("retries").get<int>());
}

std::string status(const std::string& farmDir) {
    const Json plan = loadPlan(farmDir);
    std::error_code ec;
    const Json& tasks = plan.at("tasks");
    int done = 0;
    for (const Json& t : tasks) done += fs::exists(pieceFile(plan, t), ec) ? 1 : 0;
    int frames = 0, written = 0;
    for (int f = plan.at("frames")[0].get<int>(); f <= plan.at("frames")[1].get<int>(); ++f, ++frames)
        written += fs::exists(frameFile(plan, f), ec) ? 1 : 0;
    std::ostringstream s;
    s << "farm " << plan.at("dir").get<std::string>() << ": " << done << "/" << tasks.size() << " pieces, " << written << "/"
      << frames << " frames written, " << plan.at("attempts").get<int>() << " resubmission(s)\n";
    std::vector<std::string> ids;
    {
        std::ifstream jobs(fs::path(plan.at("dir").get<std::string>()) / "jobs.txt");
        std::string line;
        while (std::getline(jobs, line))
            if (!line.empty()) ids.push_back(line.substr(0, line.find(' ')));
    }
    if (ids.empty()) return s.str() + "no jobs submitted (a dry run?)\n";
    std::string joined;
    for (const std::string& id : ids) joined += (joined.empty() ? "" : ",") + id;
    std::string out;
    if (runCommand("squeue -h -j " + joined + " -o '%i %T %R'", out) == 0) s << (trim(out).empty() ? "squeue: no job of the farm is queued or running\n" : "squeue:\n" + trim(out) + "\n");
    else s << "squeue unavailable: " << trim(out) << "\n";
    if (runCommand("sacct -n -P -X -j " + joined + " -o JobID,State,ExitCode", out) == 0 && !trim(out).empty()) {
        s << "sacct:\n" << trim(out) << "\n";
    } else {
        // Accounting off: the tasks' logs say how each ended (the last progress event).
        s << "sacct unavailable (accounting off); task logs:\n";
        std::vector<fs::path> logs;
        for (const auto& e : fs::directory_iterator(fs::path(plan.at("dir").get<std::string>()) / "logs", ec)) logs.push_back(e.path());
        std::sort(logs.begin(), logs.end());
        for (const fs::path& l : logs) {
            std::ifstream f(l);
            std::string line, last;
            while (std::getline(f, line))
                if (!line.empty()) last = line;
            s << "  " << l.filename().string() << ": " << (last.size() > 160 ? last.substr(0, 160) + "..." : last) << "\n";
        }
    }
    return s.str();
}

}  // namespace specula::farm
