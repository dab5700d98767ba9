// The `specula` command-line tool: render JSON scenes, compare images, validate scenes. A thin layer
// over the library API (core/api/specula.h); exit codes are documented in docs/cli.md.
#include "core/api/specula.h"
#include "core/util/error.h"
#include "core/util/input_files.h"
#include "core/util/memory_budget.h"
#include "plugin/cli/cli_options.h"
#include "plugin/cli/cli_output.h"
#include "plugin/cli/farm_command.h"
#include "plugin/cli/graph_commands.h"
#include "plugin/cli/normalmap_command.h"
#include "plugin/cli/nodes_command.h"
#include "plugin/cli/preview_command.h"
#include "plugin/cli/validation_cli.h"
#include "plugin/cli/view_command.h"

#include <algorithm>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace specula;

namespace {

std::atomic<bool> gCancel{false};

extern "C" void onSigint(int) { gCancel.store(true); }

std::string formatSeconds(double s) {
    char buf[32];
    if (s < 60)
        std::snprintf(buf, sizeof buf, "%.1fs", s);
    else
        std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
    return buf;
}

void printBar(const RenderProgress& p) {
    const int width = 30;
    int filled = p.tilesTotal ? p.tilesDone * width / p.tilesTotal : width;
    std::string bar(size_t(filled), '#');
    bar.resize(width, '.');
    std::fprintf(stderr, "\r[%s] %d/%d tiles  %.2f Msamples/s  ETA %s   ", bar.c_str(), p.tilesDone, p.tilesTotal,
                 p.samplesPerSecond / 1e6, formatSeconds(p.etaSeconds).c_str());
    std::fflush(stderr);
}

void printJsonTile(const RenderProgress& p) {
    std::printf("%s\n", tileEventJson(p).c_str());
    std::fflush(stdout);
}

bool parsePair(const std::string& s, char sep, int& a, int& b) {
    std::istringstream in(s);
    char c;
    return (in >> a >> c >> b) && c == sep && in.peek() == EOF;
}

// A string as a JSON literal (quotes and escapes), for the machine-readable output lines.
std::string jsonString(const std::string& s) { return nlohmann::json(s).dump(); }

// The --limit NAME=VALUE options of render and info into SceneLimits; a bad one is a usage error (exit 2).
bool readLimitOptions(const std::vector<std::string>& options, SceneLimits& limits, int& exitCode) {
    try {
        for (const std::string& l : options) setSceneLimit(limits, l);
        return true;
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "specula: error: %s\n", e.what());
        exitCode = kExitUsage;
        return false;
    }
}

int reportError(const std::exception& e, int code) {
    std::fprintf(stderr, "specula: error: %s\n", e.what());
    return code;
}

}  // namespace

int main(int argc, char** argv) {
    // Every file the command reads is remembered by identity; no output of it may replace one (core/util/input_files.h).
    InputFileScope inputs;
    CLI::App app{"Specula: physically based renderer for glints and filtered specular materials"};
    app.set_version_flag("--version", std::string("specula ") + SPECULA_VERSION);
    app.require_subcommand(1);
    int exitCode = kExitOk;

    // ---- render ---------------------------------------------------------------------------------
    auto* render = app.add_subcommand("render", "Render a JSON scene to EXR (all AOVs) and an OCIO-viewed PNG");
    std::string scenePath, outPath, resolution, crop, progress;
    int spp = 0, threads = 0;
    int64_t seed = -1;
    render->add_option("scene", scenePath, "Scene file (JSON, format v1)")->required();
    render->add_option("-o,--output", outPath, "Output: OUT.exr (every AOV, with the viewed OUT.png beside it) or OUT.png "
                                               "(the viewed image only); default <scene name>.exr in the current folder");
    render->add_option("--spp", spp, "Samples per pixel (overrides the scene)")->check(optionCheck(option_rules::spp));
    render->add_option("--threads", threads, "Worker threads (default: all cores)")->check(optionCheck(option_rules::threads));
    std::string maxMemory;
    render->add_option("--max-memory", maxMemory,
                       "Refuse a render estimated to need more than SIZE bytes (4G, 512M; default: what the system allows)");
    render->add_option("--seed", seed, "Sampler seed (overrides the scene)")->check(optionCheck(option_rules::seed));
    render->add_option("--resolution", resolution, "Image size WxH (overrides the scene)");
    render->add_option("--crop", crop, "Render only pixels x0,y0,x1,y1 (x1,y1 exclusive); output is the crop");
    int frame = 0, sampleBlock = -1;
    bool frameGiven = false;
    std::string sampleSplit;
    render->add_option("--frame", frame, "Animation frame to render (default: the scene's frame_start)")
        ->check(optionCheck(option_rules::frame))
        ->each([&](const std::string&) { frameGiven = true; });
    render->add_option("--sample-block", sampleBlock, "Sum samples in blocks of N (render.sample_block; farm splits)")
        ->check(optionCheck(option_rules::sampleBlock));
    render->add_option("--sample-split", sampleSplit, "Render only sample block I of K (I/K), keeping sums: a farm piece");
    std::string areaLights;
    render->add_option("--area-lights", areaLights, "Quad lights: ltc (analytic where lobes can) or sampled (overrides render.area_lights)")
        ->check(CLI::IsMember({"ltc", "sampled"}));
    std::string integratorName;
    render->add_option("--integrator", integratorName,
                       "path, direct or raster (the GPU preview's lighting, for image parity; overrides render.integrator)")
        ->check(CLI::IsMember({"path", "direct", "raster"}));
    render->add_option("--progress", progress, "Progress output: bar (stderr), json (stdout lines) or none")
        ->check(CLI::IsMember({"bar", "json", "none"}));
    std::vector<std::string> renderLimits;
    render->add_option("--limit", renderLimits,
                       "Cap what the scene may ask for, NAME=VALUE (pixels, spp, triangles, texture_side, graph_nodes, "
                       "json_depth); repeatable; beyond a cap is bad input (exit 1)");
    CameraShiftOptions shiftOpts;
    addCameraShiftOptions(*render, shiftOpts);
    render->callback([&] {
        SceneOverrides ov;
        ov.spp = spp;
        ov.seed = seed;
        if (!readLimitOptions(renderLimits, ov.limits, exitCode)) return;
        if (!areaLights.empty()) ov.areaLights = areaLights == "ltc" ? AreaLightMode::Ltc : AreaLightMode::Sampled;
        if (!integratorName.empty())
            ov.integrator = integratorName == "path"     ? IntegratorKind::Path
                            : integratorName == "direct" ? IntegratorKind::Direct
                                                         : IntegratorKind::Raster;
        if (!resolution.empty() && !parsePair(resolution, 'x', ov.width, ov.height)) {
            std::fprintf(stderr, "specula: error: --resolution expects WxH, got '%s'\n", resolution.c_str());
            exitCode = kExitUsage;
            return;
        }
        if (!resolution.empty() && !(option_rules::resolutionSide.contains(ov.width) && option_rules::resolutionSide.contains(ov.height))) {
            std::fprintf(stderr, "specula: error: --resolution %s is outside 1x1..16384x16384\n", resolution.c_str());
            exitCode = kExitUsage;
            return;
        }
        if (!crop.empty()) {
            CropWindow c;
            char s1, s2, s3;
            std::istringstream in(crop);
            const bool parsed = bool(in >> c.x0 >> s1 >> c.y0 >> s2 >> c.x1 >> s3 >> c.y1);
            if (!parsed || s1 != ',' || s2 != ',' || s3 != ',' || !(in >> std::ws).eof()) {  // nothing may follow y1
                std::fprintf(stderr, "specula: error: --crop expects x0,y0,x1,y1, got '%s'\n", crop.c_str());
                exitCode = kExitUsage;
                return;
            }
            ov.crop = c;
        }
        if (frameGiven) ov.frame = frame;
        ov.sampleBlock = sampleBlock;
        if (!sampleSplit.empty()) {
            char slash = 0, extra = 0;
            if (std::sscanf(sampleSplit.c_str(), "%d%c%d%c", &ov.sampleSplitIndex, &slash, &ov.sampleSplitCount, &extra) != 3 ||
                slash != '/') {
                std::fprintf(stderr, "specula: error: --sample-split expects I/K, got '%s'\n", sampleSplit.c_str());
                exitCode = kExitUsage;
                return;
            }
        }
        if (outPath.empty()) outPath = fs::path(scenePath).stem().string() + ".exr";
        try {
            checkOutputPath(outPath, scenePath);  // the output policy lives in libspecula (core/api/specula.h)
        } catch (const Error& e) {
            exitCode = reportError(e, e.exitCode());
            return;
        }
        std::string mode = progress.empty() ? (isatty(STDERR_FILENO) ? "bar" : "none") : progress;
        Scene scene;
        try {
            scene = loadSceneForRender(scenePath, ov, shiftOpts);
        } catch (const std::exception& e) {
            exitCode = reportError(e, exitCodeFor(e));
            return;
        }
        for (const std::string& w : scene.warnings) std::fprintf(stderr, "specula: warning: %s\n", w.c_str());
        if (printCameraIfAsked(scene, shiftOpts)) return;
        try {  // the scene is loaded: no output may replace a file it read (a texture, a mesh), checked before rendering
            for (const std::string& out : {outPath, fs::path(outPath).replace_extension(".png").string(), partialOutputPath(outPath)})
                refuseOverwritingInputs(out, {}, "-o");  // the scene itself was noted when read
        } catch (const Error& e) {
            exitCode = reportError(e, e.exitCode());
            return;
        }
        std::signal(SIGINT, onSigint);
        std::signal(SIGTERM, onSigint);
        RenderOptions opts;
        opts.threads = threads;
        opts.cancel = &gCancel;
        if (!maxMemory.empty() && !parseByteSize(maxMemory, opts.maxMemoryBytes)) {
            std::fprintf(stderr, "specula: error: --max-memory expects a size such as 4G, 512M or 1000000000, got '%s'\n",
                         maxMemory.c_str());
            exitCode = kExitUsage;
            return;
        }
        if (mode == "bar") opts.onTile = printBar;
        if (mode == "json") opts.onTile = printJsonTile;
        RenderOutput result;
        try {
            result = renderScene(scene, opts);
        } catch (const std::bad_alloc&) {
            std::fprintf(stderr, "specula: error: out of memory while rendering '%s' (try --crop pieces or a lower "
                                 "--resolution)\n", scenePath.c_str());
            exitCode = kExitBadInput;
            return;
        } catch (const std::exception& e) {
            exitCode = reportError(e, exitCodeFor(e));
            return;
        }
        if (mode == "bar") std::fprintf(stderr, "\n");
        const RenderStats& st = result.stats;
        try {
            WrittenFiles w = writeRenderResult(outPath, scene, result.images, st);
            if (w.partial) {
                std::fprintf(stderr, "specula: interrupted after %d/%d tiles; partial image written to %s\n", st.tilesDone,
                             st.tilesTotal, w.exr.c_str());
                if (mode == "json") std::printf("%s\n", cancelledEventJson(st, w.exr).c_str());
                exitCode = kExitInterrupted;
                return;
            }
            double sps = st.seconds > 0 ? double(st.samples) / st.seconds : 0.0;
            if (mode == "json")
                std::printf("%s\n", doneEventJson(st, w.exr, w.png).c_str());
            else
                std::fprintf(stderr, "specula: rendered %dx%d at %d spp in %s (%.2f Msamples/s); %llu NaN/Inf samples dropped\n"
                                     "specula: wrote %s\n",
                             result.images.width, result.images.height, scene.render.spp, formatSeconds(st.seconds).c_str(),
                             sps / 1e6, (unsigned long long)st.invalidSamples,
                             (w.exr.empty() ? w.png : w.exr + " and " + w.png).c_str());
        } catch (const std::exception& e) {
            exitCode = reportError(e, kExitIo);
        }
    });

    // ---- compare --------------------------------------------------------------------------------
    auto* compare = app.add_subcommand("compare", "Compare two images: RMSE, MAE, PSNR (OpenImageIO)");
    std::string imgA, imgB, aov = "beauty", diffOut;
    bool compareJson = false;
    compare->add_option("a", imgA, "First image")->required();
    compare->add_option("b", imgB, "Second image (reference)")->required();
    compare->add_option("--aov", aov, "AOV (EXR layer) to compare: beauty, diffuse, specular, ...");
    compare->add_option("--diff", diffOut, "Write a false-colour |A-B| map (PNG)");
    compare->add_flag("--json", compareJson, "Print one JSON object instead of text");
    CompareMaskOptions maskOpts;
    addCompareMaskOptions(*compare, maskOpts);
    compare->callback([&] {
        try {
            refuseOverwritingInput(diffOut, {imgA, imgB}, "--diff");
        } catch (const Error& e) {
            exitCode = reportError(e, e.exitCode());
            return;
        }
        if (maskOpts.active()) {  // masked metrics and frame sequences (plugin/cli/validation_cli.cpp)
            exitCode = runMaskedCompare(imgA, imgB, aov, maskOpts, compareJson, diffOut);
            return;
        }
        try {
            CompareResult r = compareImages(imgA, imgB, aov, diffOut);
            if (compareJson)
            {
                // JSON has no infinity: identical images report "psnr": null.
                char psnr[32] = "null";
                if (std::isfinite(r.psnr)) std::snprintf(psnr, sizeof psnr, "%.6g", r.psnr);
                std::printf("{\"aov\":%s,\"rmse\":%.9g,\"mae\":%.9g,\"psnr\":%s,\"psnr_peak\":%.9g,\"mean_a\":%.9g,\"mean_b\":%.9g,"
                            "\"channels\":%s,\"ignored_channels\":%s}\n",
                            jsonString(aov).c_str(), r.rmse, r.mae, psnr, r.peak, r.meanA, r.meanB,
                            nlohmann::json(r.compared).dump().c_str(), nlohmann::json(r.ignored).dump().c_str());
            }
            else {
                std::string channels;
                for (const std::string& c : r.compared) channels += (channels.empty() ? "" : ",") + c;
                std::printf("aov   %s (%dx%d, channels %s)\n", aov.c_str(), r.width, r.height, channels.c_str());
                for (const std::string& c : r.ignored) std::printf("note  channel %s is not compared\n", c.c_str());
                std::printf("RMSE  %.6g\nMAE   %.6g\nPSNR  %.3f dB (peak %.6g: the reference's maximum)\n", r.rmse, r.mae,
                            r.psnr, r.peak);
            }
        } catch (const Error& e) {
            exitCode = reportError(e, e.exitCode());  // NaN/Inf in an image: bad input (1)
        } catch (const std::exception& e) {
            exitCode = reportError(e, kExitIo);
        }
    });

    // ---- info -----------------------------------------------------------------------------------
    auto* info = app.add_subcommand("info", "Validate a scene and print a summary");
    std::string infoScene;
    info->add_option("scene", infoScene, "Scene file")->required();
    std::vector<std::string> infoLimits;
    info->add_option("--limit", infoLimits, "Cap what the scene may ask for, NAME=VALUE, as render --limit");
    info->callback([&] {
        SceneOverrides infoOv;
        if (!readLimitOptions(infoLimits, infoOv.limits, exitCode)) return;
        try {
            Scene s = loadScene(infoScene, infoOv);
            for (const std::string& w : s.warnings) std::fprintf(stderr, "specula: warning: %s\n", w.c_str());
            std::printf("%s", describeScene(s).c_str());
        } catch (const std::exception& e) {
            exitCode = reportError(e, exitCodeFor(e));
        }
    });

    // ---- glsl / bsdf / plot: material authoring tools (plugin/cli/graph_commands.cpp) ------------
    addGraphCommands(app, exitCode);
    // ---- normalmap: deterministic procedural normal maps (plugin/cli/normalmap_command.cpp) --------
    addNormalmapCommand(app, exitCode);
    // ---- preview: the GPU rasteriser over the generated GLSL (plugin/cli/preview_command.cpp) -------
    addPreviewCommand(app, exitCode);
    addViewCommand(app, exitCode);
    addNodesCommand(app, exitCode);
    addFarmCommands(app, exitCode);  // merge, farm (plugin/cli/farm_command.cpp)

    // A first word that is neither an option nor a command: name it and the nearest command (CLI11 only says "A
    // subcommand is required").
    if (argc > 1 && argv[1][0] != '-') {
        std::vector<std::string> names;
        for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) names.push_back(sub->get_name());
        if (std::find(names.begin(), names.end(), argv[1]) == names.end()) {
            const std::string near = nearestName(argv[1], names);
            std::fprintf(stderr, "specula: error: unknown command '%s'%s; see specula --help\n", argv[1],
                         near.empty() ? "" : (" (did you mean '" + near + "'?)").c_str());
            return kExitUsage;
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        int rc = app.exit(e);
        return rc == 0 ? kExitOk : kExitUsage;
    }
    return exitCode;
}
