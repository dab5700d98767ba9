// The `specula merge` and `specula farm` subcommands: thin front ends over core/farm/farm.h (pieces merged bit for bit;
// Slurm job arrays submitted, watched, finished). docs/farm.md.
#pragma once

namespace CLI {
class App;
}

namespace specula {

// Registers `merge -o OUT.exr PIECE... [--force]` and `farm submit|status|finish|task`; callbacks store the exit code:
// kExitOk, kExitBadInput (mismatched or incomplete pieces, bad plan), kExitUsage, kExitIo (sbatch, files).
void addFarmCommands(CLI::App& app, int& exitCode);

}  // namespace specula
