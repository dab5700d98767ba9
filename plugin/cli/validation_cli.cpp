#include "plugin/cli/validation_cli.h"

#include "core/api/specula.h"
#include "plugin/cli/validation_metrics.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace specula {

void addCameraShiftOptions(CLI::App& render, CameraShiftOptions& o) {
    render.add_option("--camera-shift-px", o.shift,
                      "Translate camera position and look_at by DX,DY pixels at the look-at distance "
                      "(+x right, +y down the image)");
    render.add_flag("--print-camera", o.printCamera, "Print the camera (after overrides) as JSON and exit");
}

Scene loadSceneForRender(const std::string& path, const SceneOverrides& ov, const CameraShiftOptions& o) {
    if (o.shift.empty()) return loadScene(path, ov);
    double dx = 0, dy = 0;
    if (!parseCameraShift(o.shift, dx, dy))
        throw std::invalid_argument("--camera-shift-px expects DX,DY (two numbers), got '" + o.shift + "'");
    std::string text;
    try {
        text = readJsonText(path);  // bounded (issue 35)
    } catch (const std::exception&) {
        return loadScene(path, ov);  // the loader's own message
    }
    nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("camera")) return loadScene(path, ov);
    // The pixel is measured on the image that will be rendered: the scene's size unless --resolution overrides it
    // (the loader's defaults, RenderSettings, when the scene names none).
    const nlohmann::json rs = j.contains("render") && j["render"].is_object() ? j["render"] : nlohmann::json::object();
    const RenderSettings defaults;
    const int width = ov.width > 0 ? ov.width : rs.value("width", defaults.width);
    const int height = ov.height > 0 ? ov.height : rs.value("height", defaults.height);
    try {
        shiftCameraJson(j, dx, dy, width, height);
    } catch (const std::runtime_error& e) {
        throw std::invalid_argument(std::string("--camera-shift-px: ") + e.what());
    }
    std::string base = fs::path(path).parent_path().string();
    return loadSceneFromString(j.dump(), base.empty() ? "." : base, ov, path);
}

bool printCameraIfAsked(const Scene& scene, const CameraShiftOptions& o) {
    if (!o.printCamera) return false;
    const auto& c = scene.camera;
    std::printf("{\"position\":[%.9g,%.9g,%.9g],\"look_at\":[%.9g,%.9g,%.9g],\"width\":%d,\"height\":%d}\n",
                c.position.x, c.position.y, c.position.z, c.lookAt.x, c.lookAt.y, c.lookAt.z, scene.render.width,
                scene.render.height);
    return true;
}

void addCompareMaskOptions(CLI::App& compare, CompareMaskOptions& o) {
    compare.add_option("--mask", o.masks,
                       "Restrict the metrics to pixels where any channel of layer LAYER of FILE is > 0 (FILE:LAYER; "
                       "repeat for a union; 'all' = every pixel). Adds rel_rmse and mask_pixels to the output");
    compare.add_option("--mask-top-rows", o.topRows,
                       "Keep only the first N/D of the mask's rows (from its topmost row), e.g. 1/3");
    compare.add_option("--frames", o.frames,
                       "Flicker over K frames: A, B and the masks are printf patterns of the frame index (e.g. "
                       "t_%02d.exr); the mask is the union over the frames")
        ->check(CLI::Range(1, 100000));
}

namespace {

std::string framePath(const std::string& pattern, int frames, int t) {
    if (frames <= 0) return pattern;
    char buf[4096];
    std::snprintf(buf, sizeof buf, pattern.c_str(), t);
    return buf;
}

const AovBuffer& layer(const ImageSet& img, const std::string& path, const std::string& name) {
    const AovBuffer* a = img.find(name);
    if (!a) {
        std::string have;
        for (const auto& x : img.aovs) have += (have.empty() ? "" : ", ") + x.name;
        throw std::runtime_error("'" + path + "' has no layer '" + name + "' (layers: " + have + ")");
    }
    return *a;
}

}  // namespace

int runMaskedCompare(const std::string& a, const std::string& b, const std::string& aov, const CompareMaskOptions& o,
                     bool json, const std::string& diffPng) {
    try {
        if (!diffPng.empty()) compareImages(framePath(a, o.frames, 0), framePath(b, o.frames, 0), aov, diffPng);
        const int frames = o.frames > 0 ? o.frames : 1;
        std::vector<std::vector<float>> test, ref;
        int w = 0, h = 0, channels = 0;
        std::vector<char> mask;
        for (int t = 0; t < frames; ++t) {
            const std::string pa = framePath(a, o.frames, t), pb = framePath(b, o.frames, t);
            ImageSet ia = readImageSet(pa), ib = readImageSet(pb);
            const AovBuffer &la = layer(ia, pa, aov), &lb = layer(ib, pb, aov);
            if (ia.width != ib.width || ia.height != ib.height || la.channels() != lb.channels())
                throw std::runtime_error("'" + pa + "' and '" + pb + "' differ in size or channels of '" + aov + "'");
            if (t == 0) w = ia.width, h = ia.height, channels = la.channels();
            if (ia.width != w || ia.height != h || la.channels() != channels)
                throw std::runtime_error("frame " + pa + " differs in size from frame 0");
            test.push_back(la.pixels), ref.push_back(lb.pixels);
            for (const std::string& spec : o.masks) {
                if (spec == "all") {
                    mask.resize(size_t(w) * h, 0);
                    std::fill(mask.begin(), mask.end(), 1);
                    continue;
                }
                const size_t colon = spec.rfind(':');
                if (colon == std::string::npos || colon == 0 || colon + 1 == spec.size())
                    throw std::invalid_argument("--mask expects FILE:LAYER, got '" + spec + "'");
                const std::string pm = framePath(spec.substr(0, colon), o.frames, t);
                ImageSet im = readImageSet(pm);
                if (im.width != w || im.height != h) throw std::runtime_error("mask '" + pm + "' is not " + std::to_string(w) + "x" + std::to_string(h));
                const AovBuffer& lm = layer(im, pm, spec.substr(colon + 1));
                mask.resize(size_t(w) * h, 0);
                for (size_t i = 0; i < mask.size(); ++i)
                    for (int c = 0; c < lm.channels(); ++c)
                        if (lm.pixels[i * lm.channels() + c] > 0) mask[i] = 1;
            }
        }
        if (!o.topRows.empty()) {
            int num = 0, den = 0;
            char slash = 0;
            std::istringstream in(o.topRows);
            if (!(in >> num >> slash >> den) || slash != '/' || in.peek() != EOF || num < 0 || den <= 0)
                throw std::invalid_argument("--mask-top-rows expects N/D, got '" + o.topRows + "'");
            if (mask.empty()) mask.assign(size_t(w) * h, 1);
            int y0 = h, y1 = -1;
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x)
                    if (mask[size_t(y) * w + x]) y0 = std::min(y0, y), y1 = std::max(y1, y);
            const int cut = y1 >= y0 ? y0 + (y1 - y0 + 1) * num / den : 0;
            for (int y = cut; y < h; ++y)
                for (int x = 0; x < w; ++x) mask[size_t(y) * w + x] = 0;
        }
        const size_t maskPixels = mask.empty() ? size_t(w) * h : size_t(std::count(mask.begin(), mask.end(), 1));
        nlohmann::json out;
        out["aov"] = aov;
        out["width"] = w, out["height"] = h, out["channels"] = channels;
        out["mask_pixels"] = maskPixels;
        if (o.frames > 0) {
            out["frames"] = o.frames;
            out["flicker"] = flickerMetric(test, ref, channels, mask);
            out["shimmer"] = flickerMetric(test, {}, channels, mask);
            out["shimmer_ref"] = flickerMetric(ref, {}, channels, mask);
        } else {
            const MaskedError e = maskedError(test[0], ref[0], channels, mask);
            out["rmse"] = e.rmse, out["mae"] = e.mae, out["rel_rmse"] = e.relRmse, out["mean_b"] = e.meanRef;
            out["mean_a"] = maskedError(test[0], test[0], channels, mask).meanRef;
        }
        if (json) {
            std::printf("%s\n", out.dump().c_str());
        } else {
            std::printf("aov   %s (%dx%d, %d channels), mask %zu px\n", aov.c_str(), w, h, channels, maskPixels);
            if (o.frames > 0)
                std::printf("frames   %d\nflicker  %.6g\nshimmer  %.6g (reference %.6g)\n", o.frames,
                            out["flicker"].get<double>(), out["shimmer"].get<double>(), out["shimmer_ref"].get<double>());
            else
                std::printf("RMSE  %.6g\nMAE   %.6g\nrel. RMSE  %.6g\n", out["rmse"].get<double>(), out["mae"].get<double>(),
                            out["rel_rmse"].get<double>());
        }
        return kExitOk;
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "specula: error: %s\n", e.what());
        return kExitUsage;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "specula: error: %s\n", e.what());
        return kExitIo;
    }
}

}  // namespace specula
