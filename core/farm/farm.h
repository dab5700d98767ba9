// Render farms: a render split into pieces (frames x crop tiles x sample splits) that scheduler tasks render with
// `specula render`, and the merge that assembles them bit for bit into the single-process render (docs/farm.md).
// Slurm is the scheduler driven here (job arrays, a dependent finish job); other managers run the same pieces.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace specula::farm {

// ---- Merge ---------------------------------------------------------------------------------------------------------

struct MergeSummary {
    int width = 0, height = 0;
    int pieces = 0, tiles = 0, sampleSplits = 1;
    int frame = 0;
    std::string sceneHash;
};

// Assembles the pieces of one frame into 'outPath' (EXR, every AOV, written atomically). Pieces are `render --crop`
// and/or `render --sample-split` outputs; the tiles must cover the frame exactly once, and each tile is either one
// whole render or all K of its sample splits, whose sums are added in split order and divided by their total sample
// count exactly as the film does. Refuses (InputError naming the file) pieces of another scene hash, frame, size, spp,
// seed or sample block, partial pieces, overlaps and gaps; refuses an existing output unless 'overwrite' (IoError).
// Nothing is read without a bound (issue 35): a piece must be a regular file (a device such as /dev/zero, a FIFO or a
// folder is an IoError naming it), its header may declare at most maxPiecePixels pixels, and every specula:* attribute
// is parsed as a checked integer inside its range (InputError naming the file, the attribute and the range), as are
// the sample counts of a split's 'samples' layer (finite whole numbers in 0 … spp/K). Failing to write the output (a
// missing folder, a full disk) is an IoError (exit 3).
MergeSummary mergePieces(const std::vector<std::string>& pieces, const std::string& outPath, bool overwrite = false,
                         int64_t maxPiecePixels = int64_t(1) << 26);

// ---- Plans ---------------------------------------------------------------------------------------------------------

struct SubmitOptions {
    std::string scene;        // the scene file
    std::string farmDir;      // where the plan, scripts, pieces, logs and frames go (default: farm-<scene stem>)
    std::string executable;   // the specula binary the tasks run (an absolute path on the shared file system)
    std::optional<int> frameFirst, frameLast;  // default: the scene's animation range (or frame 0 / 1 without one)
    int tilesX = 1, tilesY = 1;
    int sppSplit = 1;         // sample splits per tile (must divide spp; > 1 sets render.sample_block = spp/K)
    int spp = 0, threadsPerTask = 1, retries = 2;
    // Slurm names copied into #SBATCH lines: letters, digits, '.', '_' and '-' (a comma-separated list for the
    // partition); anything else is an InputError naming the option, never a line of the script (issue 35).
    std::string partition, account;
    std::vector<std::string> extraRenderArgs;  // passed to every piece's `specula render` argv (e.g. --seed 3), no shell
    bool dryRun = false;
};

struct SubmitResult {
    std::string farmDir;
    int tasks = 0, frames = 0;
    std::vector<std::string> commands;  // the sbatch command lines (run, or printed for a dry run)
    std::vector<std::string> jobIds;
};

// Writes the farm folder (plan.json, render.sbatch, finish.sbatch) and, unless a dry run, submits the task array and
// the finish job (afterany) with sbatch, run without a shell. Refuses a folder that already holds a plan. The scripts
// hold only checked values: the job name is the scene stem reduced to [A-Za-z0-9._-], partition and account are
// validated, the log paths are relative to the job's working folder (sbatch --chdir=DIR on its command line), and the
// exec line's words are shell-quoted; a farm folder or executable path with a control character is refused.
SubmitResult submit(const SubmitOptions& options);

// The name Slurm sees for a farm of scene 'sceneStem': "specula-" and the stem with every character outside
// [A-Za-z0-9._-] replaced by '_', at most 64 characters.
std::string slurmJobName(const std::string& sceneStem);

// Reads and checks a farm folder's plan.json as every farm command does, returning its task count: every field has its
// type and range, the folder it names is 'farmDir', and every piece and frame path stays inside the farm folder
// (relative, no '..', no symlink out of it). Errors are InputErrors naming the JSON pointer (e.g. /tasks/3/piece);
// a missing, oversized or non-regular plan.json is an IoError.
int checkPlan(const std::string& farmDir);

// The finish job: merges every frame whose pieces are all present (skipping frames already written: a finished frame is
// never overwritten); if pieces are missing (a task failed or was killed) and retries are left, resubmits the missing
// tasks and another finish job; otherwise throws naming the missing pieces. Returns a one-line report. A resubmission
// counts against the retries only once sbatch has queued it: a refused sbatch leaves plan.json's "attempts" as it was.
std::string finish(const std::string& farmDir);

// Pieces done and missing, frames written, and the scheduler's view of the farm's jobs (squeue; sacct when accounting
// is on; otherwise the tasks' logs).
std::string status(const std::string& farmDir);

// Runs one task of the plan (the array task's body): `specula render` of its piece unless the piece exists.
// Returns the command line to exec, or "" when there is nothing to do.
std::vector<std::string> taskCommand(const std::string& farmDir, int taskIndex);

}  // namespace specula::farm
