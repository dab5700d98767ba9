// The `specula normalmap` subcommand: writes a deterministic procedural tangent-space normal map
// (core/texture/normal_map_gen.h) as a 16-bit PNG or float EXR, chosen by the output extension.
#pragma once

namespace CLI {
class App;
}

namespace specula {

// Registers `normalmap --kind bumps|brushed|scratches|flakes|stone --size N --seed S -o FILE.(exr|png)`;
// the callback stores its exit code (kExitOk, kExitUsage, kExitIo) in 'exitCode'.
void addNormalmapCommand(CLI::App& app, int& exitCode);

}  // namespace specula
