// `specula merge` and `specula farm ...` (plugin/cli/farm_command.h).
#include "plugin/cli/farm_command.h"

#include "core/api/specula.h"
#include "core/farm/farm.h"
#include "core/util/error.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <unistd.h>

namespace specula {

namespace {

int report(const std::exception& e) {
    std::fprintf(stderr, "specula: error: %s\n", e.what());
    return exitCodeFor(e);
}

std::string selfExecutable() {
    std::error_code ec;
    auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
    return ec ? std::string("specula") : p.string();
}

}  // namespace

void addFarmCommands(CLI::App& app, int& exitCode) {
    // ---- merge ----
    auto* merge = app.add_subcommand("merge", "Assemble farm pieces (render --crop / --sample-split) into one frame, bit for bit");
    static std::vector<std::string> pieces;
    static std::string mergeOut;
    static bool force = false;
    merge->add_option("pieces", pieces, "Piece EXRs of one frame (tiles, sample splits)")->required();
    merge->add_option("-o,--output", mergeOut, "The frame (EXR); never overwritten unless --force")->required();
    merge->add_flag("--force", force, "Replace an existing output");
    merge->callback([&] {
        try {
            farm::MergeSummary s = farm::mergePieces(pieces, mergeOut, force);
            std::fprintf(stderr, "specula: merged %d piece(s) (%d tile(s), %d sample split(s)) of frame %d into %s (%dx%d)\n",
                         s.pieces, s.tiles, s.sampleSplits, s.frame, mergeOut.c_str(), s.width, s.height);
        } catch (const std::exception& e) {
            exitCode = report(e);
        }
    });

    // ---- farm ----
    auto* farmCmd = app.add_subcommand("farm", "Render on a Slurm cluster: job arrays of pieces, merged when done (docs/farm.md)");
    farmCmd->require_subcommand(1);
    static farm::SubmitOptions so;
    static std::string frames, tiles = "1x1";
    auto* submit = farmCmd->add_subcommand("submit", "Write the farm folder and submit the task array and its finish job");
    submit->add_option("scene", so.scene, "Scene file")->required();
    submit->add_option("--frames", frames, "Frames A-B (or one frame N; default: the scene's animation range)");
    submit->add_option("--tiles", tiles, "Crop tiles NxM per frame (default 1x1)");
    submit->add_option("--spp-split", so.sppSplit, "Sample splits per tile (divides spp; sets render.sample_block = spp/K)")
        ->check(CLI::Range(1, 4096));
    submit->add_option("--spp", so.spp, "Samples per pixel (overrides the scene)")->check(CLI::Range(1, 1 << 20));
    submit->add_option("--partition", so.partition, "Slurm partition(s): letters, digits, '.', '_', '-' (comma-separated list)");
    submit->add_option("--account", so.account, "Slurm account: letters, digits, '.', '_', '-'");
    submit->add_option("--threads-per-task", so.threadsPerTask, "CPUs per task (default 1)")->check(CLI::Range(1, 1024));
    submit->add_option("--retries", so.retries, "Resubmissions of missing pieces (default 2)")->check(CLI::Range(0, 100));
    submit->add_option("--dir", so.farmDir, "Farm folder (default farm-<scene name>)");
    submit->add_flag("--dry-run", so.dryRun, "Write the folder and print the sbatch commands without submitting");
    submit->callback([&] {
        if (!frames.empty()) {
            int a = 0, b = 0;
            char dash = 0;
            if (std::sscanf(frames.c_str(), "%d%c%d", &a, &dash, &b) == 3 && dash == '-')
                so.frameFirst = a, so.frameLast = b;
            else if (std::sscanf(frames.c_str(), "%d%c", &a, &dash) == 1)
                so.frameFirst = a, so.frameLast = a;
            else {
                std::fprintf(stderr, "specula: error: --frames expects A-B or N, got '%s'\n", frames.c_str());
                exitCode = kExitUsage;
                return;
            }
        }
        char x = 0, extra = 0;
        if (std::sscanf(tiles.c_str(), "%d%c%d%c", &so.tilesX, &x, &so.tilesY, &extra) != 3 || (x != 'x' && x != 'X')) {
            std::fprintf(stderr, "specula: error: --tiles expects NxM, got '%s'\n", tiles.c_str());
            exitCode = kExitUsage;
            return;
        }
        so.executable = selfExecutable();
        try {
            farm::SubmitResult r = farm::submit(so);
            std::printf("farm %s: %d task(s) over %d frame(s)\n", r.farmDir.c_str(), r.tasks, r.frames);
            for (const std::string& c : r.commands) std::printf("%s%s\n", so.dryRun ? "would run: " : "ran: ", c.c_str());
            if (!r.jobIds.empty()) std::printf("jobs: render %s, finish %s\n", r.jobIds[0].c_str(), r.jobIds[1].c_str());
        } catch (const std::exception& e) {
            exitCode = report(e);
        }
    });
    static std::string dir;
    auto* status = farmCmd->add_subcommand("status", "Pieces done, frames written, and the jobs as squeue/sacct (or the logs) see them");
    status->add_option("dir", dir, "Farm folder")->required();
    status->callback([&] {
        try {
            std::printf("%s", farm::status(dir).c_str());
        } catch (const std::exception& e) {
            exitCode = report(e);
        }
    });
    auto* finish = farmCmd->add_subcommand("finish", "Merge complete frames; resubmit missing pieces (the farm's finish job)");
    finish->add_option("dir", dir, "Farm folder")->required();
    finish->callback([&] {
        try {
            std::printf("%s\n", farm::finish(dir).c_str());
        } catch (const std::exception& e) {
            exitCode = report(e);
        }
    });
    static int taskIndex = -1;
    auto* task = farmCmd->add_subcommand("task", "Render one piece of the plan (the array task's body; nothing if it exists)");
    task->add_option("dir", dir, "Farm folder")->required();
    task->add_option("index", taskIndex, "Task index (SLURM_ARRAY_TASK_ID)")->required();
    task->callback([&] {
        try {
            std::vector<std::string> argv = farm::taskCommand(dir, taskIndex);
            if (argv.empty()) {
                std::printf("{\"event\":\"skipped\",\"reason\":\"the piece exists\"}\n");
                return;
            }
            std::fflush(stdout);
            std::vector<char*> args;
            for (std::string& a : argv) args.push_back(a.data());
            args.push_back(nullptr);
            execv(args[0], args.data());
            std::fprintf(stderr, "specula: error: cannot run '%s'\n", args[0]);
            exitCode = kExitIo;
        } catch (const std::exception& e) {
            exitCode = report(e);
        }
    });
}

}  // namespace specula
