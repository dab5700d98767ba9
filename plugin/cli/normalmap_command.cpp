// `specula normalmap`: CLI front-end of generateNormalMap/writeNormalMap; prints the map's slope statistics
// (mean, RMS per axis, correlation) and its golden hash so example scripts can check what they produced.
#include "plugin/cli/normalmap_command.h"

#include "core/texture/normal_map_gen.h"
#include "core/util/error.h"
#include "plugin/cli/cli_options.h"
#include "plugin/cli/cli_output.h"

#include <CLI/CLI.hpp>

#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace specula {

void addNormalmapCommand(CLI::App& app, int& exitCode) {
    struct Opts {
        std::string kind = "bumps", out;
        int size = 512;
        int64_t seed = 1;
        double angle = 0.0;
        bool quiet = false;
    };
    auto o = std::make_shared<Opts>();
    auto* cmd = app.add_subcommand("normalmap", "Write a procedural tangent-space normal map (OpenGL convention, "
                                                "colour = (n+1)/2): 16-bit PNG or float EXR by extension");
    cmd->add_option("--kind", o->kind, "bumps, brushed, scratches, flakes or stone")
        ->check(CLI::IsMember({"bumps", "brushed", "scratches", "flakes", "stone"}));
    cmd->add_option("--size", o->size, "Width = height in texels")->check(CLI::Range(8, 8192));
    cmd->add_option("--seed", o->seed, "Seed (same kind, size and seed give the same file)")
        ->check(CLI::Range(int64_t(0), int64_t(INT64_MAX)));
    cmd->add_option("-o,--output", o->out, "Output file: .exr (float) or .png (16-bit)")->required();
    auto* angle = cmd->add_option("--angle", o->angle,
                                  "Brush direction of --kind brushed, degrees from +u towards +v (default 26.565); the "
                                  "nearest direction that keeps the tile seamless is used and printed")
                      ->check(optionCheck(option_rules::brushAngle));
    cmd->add_flag("--quiet", o->quiet, "Print nothing on success");
    cmd->callback([o, angle, &exitCode] {
        if (angle->count() > 0 && o->kind != "brushed") {
            std::fprintf(stderr, "specula: error: --angle applies to --kind brushed only (got --kind %s)\n", o->kind.c_str());
            exitCode = kExitUsage;
            return;
        }
        if (!outputFolderExists(o->out)) {
            exitCode = kExitIo;
            return;
        }
        try {
            NormalMapKind kind = parseNormalMapKind(o->kind);
            double used = 0.0;
            NormalMap map = angle->count() > 0 ? generateBrushedNormalMap(o->size, uint64_t(o->seed), o->angle, &used)
                                               : generateNormalMap(kind, o->size, uint64_t(o->seed));
            writeNormalMap(map, o->out);
            if (!o->quiet) {
                SlopeStats s = slopeStats(map);
                std::printf("%s: %s %dx%d seed %" PRId64 "  slope mean (%.4f, %.4f)  rms (%.4f, %.4f)  rho %.3f  "
                            "principal rms (%.4f, %.4f)  hash %016" PRIx64 "\n",
                            o->out.c_str(), o->kind.c_str(), o->size, o->size, o->seed, s.meanX, s.meanY, s.sigmaX(),
                            s.sigmaY(), s.rho(), s.sigmaMajor(), s.sigmaMinor(), normalMapHash(map));
                if (angle->count() > 0) std::printf("brush angle %.3f deg (asked %.3f)\n", used, o->angle);
            }
        } catch (const NormalMapError& e) {
            std::string msg = e.what();
            std::fprintf(stderr, "specula: error: %s\n", msg.c_str());
            exitCode = msg.find("extension") != std::string::npos ? kExitUsage : kExitIo;
        } catch (const std::exception& e) {
            std::fprintf(stderr, "specula: error: %s\n", e.what());
            exitCode = kExitIo;
        }
    });
}

}  // namespace specula
