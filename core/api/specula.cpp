// Front-end policies of libspecula (core/api/specula.h).
#include "core/api/specula.h"

#include "core/util/input_files.h"

#include <nlohmann/json.hpp>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace specula {

namespace {
std::string lowerExtension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}
}  // namespace

bool isPngOutput(const std::string& outPath) { return lowerExtension(outPath) == ".png"; }

WrittenFiles writeRenderOutputs(const std::string& outPath, const Scene& scene, const ImageSet& images) {
    // Every file is written to a temporary first and renamed only once all exist: a PNG that cannot be written
    // (a full disk, a folder in its place) must not leave a new EXR over the old one (issue 16).
    WrittenFiles w;
    const bool pngOnly = isPngOutput(outPath);
    w.exr = pngOnly ? std::string() : outPath;
    w.png = pngOnly ? outPath : fs::path(outPath).replace_extension(".png").string();
    // A rename onto a folder fails: find that before either file is committed.
    for (const std::string& target : {w.exr, w.png})
        if (!target.empty() && fs::is_directory(target))
            throw ImageIoError("cannot write '" + target + "': a folder has that name");
    std::string tmpExr, tmpPng;
    auto removeTemporaries = [&] {
        std::error_code ec;
        if (!tmpExr.empty()) fs::remove(tmpExr, ec);
        if (!tmpPng.empty()) fs::remove(tmpPng, ec);
    };
    try {
        if (!pngOnly) {
            tmpExr = createTempFileNear(w.exr);
            writeExr(tmpExr, images, *scene.colorConfig);
        }
        tmpPng = createTempFileNear(w.png);
        writePng(tmpPng, images, *scene.colorConfig, scene.color.view, scene.color.exposure);
    } catch (const ImageIoError& e) {
        removeTemporaries();
        // The temporaries' names mean nothing to the user: name the file that was asked for.
        std::string msg = e.what();
        for (auto [tmp, real] : {std::pair{tmpExr, w.exr}, std::pair{tmpPng, w.png}})
            for (size_t at; !tmp.empty() && (at = msg.find(tmp)) != std::string::npos;) msg.replace(at, tmp.size(), real);
        throw ImageIoError(msg);
    } catch (...) {
        removeTemporaries();
        throw;
    }
    if (!pngOnly) commitTempFile(tmpExr, w.exr);
    commitTempFile(tmpPng, w.png);
    return w;
}

std::string partialOutputPath(const std::string& outPath) {
    return fs::path(outPath).replace_extension(".partial.exr").string();
}

void refuseOverwritingInput(const std::string& output, const std::vector<std::string>& inputs, const std::string& option) {
    if (!output.empty()) refuseOverwritingInputs(output, inputs, option);
}

void checkOutputPath(const std::string& exrPath, const std::string& inputPath) {
    const std::string ext = lowerExtension(exrPath);
    if (ext != ".exr" && ext != ".png")
        throw Error(ErrorCode::Usage, "", "output '" + exrPath + "' must end in .exr (every AOV, and the viewed PNG beside "
                                          "it) or .png (the viewed image only)");
    if (!inputPath.empty()) {
        for (const std::string& out : {exrPath, fs::path(exrPath).replace_extension(".png").string(), partialOutputPath(exrPath)})
            if (sameFile(out, inputPath))
                throw Error(ErrorCode::Usage, "", "output '" + out + "' would overwrite the input '" + inputPath + "'");
    }
    fs::path dir = fs::path(exrPath).parent_path();
    if (!dir.empty() && !fs::is_directory(dir))
        throw Error(ErrorCode::Io, "", "output folder '" + dir.string() + "' does not exist");
}

WrittenFiles writeRenderResult(const std::string& exrPath, const Scene& scene, ImageSet& images, const RenderStats& st) {
    WrittenFiles w;
    if (st.cancelled) {
        // Never clobber the target: the partial image goes to a separate file.
        w.exr = partialOutputPath(exrPath);
        w.partial = true;
        images.metadata["specula:partial"] = "true";
        writeExr(w.exr, images, *scene.colorConfig);
        return w;
    }
    return writeRenderOutputs(exrPath, scene, images);
}

void checkOption(const OptionRule& rule, double value) {
    if (rule.contains(value)) return;
    auto text = [](double v) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.10g", v);
        return std::string(buf);
    };
    throw Error(ErrorCode::Usage, "", std::string(rule.name) + " " + text(value) + " is outside " + text(rule.min) + ".." + text(rule.max));
}

int exitCodeFor(const std::exception& e) {
    if (auto* err = dynamic_cast<const Error*>(&e)) return err->exitCode();
    if (dynamic_cast<const std::invalid_argument*>(&e)) return kExitUsage;
    return kExitBadInput;
}

namespace {
std::string jsonString(const std::string& s) { return nlohmann::json(s).dump(); }
}  // namespace

std::string tileEventJson(const RenderProgress& p) {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "{\"event\":\"tile\",\"done\":%d,\"total\":%d,\"progress\":%.6f,\"x0\":%d,\"y0\":%d,\"x1\":%d,\"y1\":%d,"
                  "\"elapsed\":%.3f,\"samples_per_second\":%.1f,\"eta\":%.3f}",
                  p.tilesDone, p.tilesTotal, p.tilesTotal ? double(p.tilesDone) / p.tilesTotal : 1.0, p.tileX0, p.tileY0,
                  p.tileX1, p.tileY1, p.elapsedSeconds, p.samplesPerSecond, p.etaSeconds);
    return buf;
}

std::string cancelledEventJson(const RenderStats& st, const std::string& partialPath) {
    return "{\"event\":\"cancelled\",\"done\":" + std::to_string(st.tilesDone) + ",\"total\":" +
           std::to_string(st.tilesTotal) + ",\"partial\":" + jsonString(partialPath) + "}";
}

std::string doneEventJson(const RenderStats& st, const std::string& exrPath, const std::string& pngPath) {
    double sps = st.seconds > 0 ? double(st.samples) / st.seconds : 0.0;
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "{\"event\":\"done\",\"seconds\":%.3f,\"samples\":%llu,\"invalid_samples\":%llu,"
                  "\"samples_per_second\":%.1f,",
                  st.seconds, (unsigned long long)st.samples, (unsigned long long)st.invalidSamples, sps);
    return buf + std::string("\"exr\":") + (exrPath.empty() ? std::string("null") : jsonString(exrPath)) +
           ",\"png\":" + jsonString(pngPath) + "}";
}

}  // namespace specula
