// ColorConfig: locates and loads Specula's OCIO config, converts colorspace -> working space and
// working space -> display/view with cached, thread-safe OCIO CPU processors; friendly name errors.
#include "core/color/color_config.h"

#include <OpenColorIO/OpenColorIO.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <unistd.h>

namespace OCIO = OCIO_NAMESPACE;
namespace fs = std::filesystem;

namespace specula {

namespace {

std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower((unsigned char)c));
    return s;
}

size_t levenshtein(const std::string& a, const std::string& b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
        }
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

// "unknown <what> 'name'; did you mean 'x'? valid <what>s: a, b, c"
std::string unknownNameMessage(const std::string& what, const std::string& name,
                               const std::vector<std::string>& valid) {
    std::string best;
    size_t bestD = size_t(-1);
    for (const auto& v : valid) {
        size_t d = levenshtein(lower(name), lower(v));
        if (d < bestD) bestD = d, best = v;
    }
    std::ostringstream ss;
    ss << "unknown " << what << " '" << name << "'";
    if (!best.empty()) ss << "; did you mean '" << best << "'?";
    ss << " Valid " << what << "s: ";
    for (size_t i = 0; i < valid.size(); ++i) ss << (i ? ", " : "") << "'" << valid[i] << "'";
    return ss.str();
}

std::string exeDir() {
    std::vector<char> buf(4096);
    ssize_t n = readlink("/proc/self/exe", buf.data(), buf.size() - 1);
    if (n <= 0) return {};
    buf[size_t(n)] = '\0';
    return fs::path(buf.data()).parent_path().string();
}

// Builtin config search order (documented in color_config.h).
std::string locateBuiltinConfig(std::vector<std::string>& searched) {
    std::vector<std::string> dataDirs;
    if (const char* env = std::getenv("SPECULA_DATA_DIR"); env && *env) dataDirs.push_back(env);
#ifdef SPECULA_DATA_DIR
    dataDirs.push_back(SPECULA_DATA_DIR);
#endif
    std::string exe = exeDir();
    if (!exe.empty()) {
        dataDirs.push_back(exe + "/../data");
        dataDirs.push_back(exe + "/../../data");
        dataDirs.push_back(exe + "/../share/specula/data");
    }
    for (const auto& d : dataDirs) {
        fs::path p = fs::path(d) / "ocio" / "config.ocio";
        searched.push_back(p.string());
        std::error_code ec;
        if (fs::is_regular_file(p, ec)) return fs::weakly_canonical(p, ec).string();
    }
    return {};
}

constexpr OCIO::OptimizationFlags kOptimization = OCIO::OPTIMIZATION_LOSSLESS;

}  // namespace

struct ColorConfig::Impl {
    OCIO::ConstConfigRcPtr config;
    std::string path;
    std::string working;
    std::string display;
    std::string view;
    std::string cacheId;

    mutable std::mutex mutex;
    // Key: canonical source colorspace name. Null processor = identity (data/working).
    mutable std::map<std::string, OCIO::ConstCPUProcessorRcPtr> toWorking;
    mutable std::map<std::string, OCIO::ConstCPUProcessorRcPtr> fromWorking;
    // Key: (view, exposure stops).
    mutable std::map<std::pair<std::string, float>, OCIO::ConstCPUProcessorRcPtr> toDisplay;

    // All names a user may type for a colorspace: names, aliases, roles (for nearest-match errors).
    std::vector<std::string> allColorspaceNames() const {
        std::vector<std::string> out;
        std::set<std::string> seen;
        auto add = [&](const std::string& s) {
            if (!s.empty() && seen.insert(lower(s)).second) out.push_back(s);
        };
        int n = config->getNumColorSpaces(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ALL);
        for (int i = 0; i < n; ++i) {
            const char* name =
                config->getColorSpaceNameByIndex(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ALL, i);
            add(name);
            if (auto cs = config->getColorSpace(name))
                for (size_t a = 0; a < cs->getNumAliases(); ++a) add(cs->getAlias(a));
        }
        for (int i = 0; i < config->getNumRoles(); ++i) add(config->getRoleName(i));
        add("raw");
        return out;
    }

    // Canonical colorspace name, or "" for data / identity ("raw"). Throws ColorError.
    OCIO::ConstColorSpaceRcPtr resolve(const std::string& name) const {
        if (lower(name) == "raw") return nullptr;
        OCIO::ConstColorSpaceRcPtr cs;
        try {
            cs = config->getColorSpace(name.c_str());
        } catch (const OCIO::Exception&) {
            cs = nullptr;
        }
        if (!cs) throw ColorError(unknownNameMessage("colorspace", name, allColorspaceNames()));
        return cs;
    }

    std::vector<std::string> viewNames(const std::string& disp) const {
        std::vector<std::string> out;
        int n = config->getNumViews(disp.c_str());
        for (int i = 0; i < n; ++i) out.push_back(config->getView(disp.c_str(), i));
        return out;
    }
};

std::shared_ptr<const ColorConfig> ColorConfig::load(const std::string& configPathOrBuiltin) {
    std::string path;
    if (configPathOrBuiltin.empty() || configPathOrBuiltin == "builtin") {
        std::vector<std::string> searched;
        path = locateBuiltinConfig(searched);
        if (path.empty()) {
            std::string msg = "cannot find Specula's OCIO config (data/ocio/config.ocio); searched:";
            for (const auto& s : searched) msg += " " + s;
            msg += ". Set $SPECULA_DATA_DIR to the folder that contains ocio/config.ocio.";
            throw ColorError(msg);
        }
    } else {
        path = configPathOrBuiltin;
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) throw ColorError("OCIO config file not found: '" + path + "'");
    }

    auto impl = std::make_unique<Impl>();
    impl->path = path;
    try {
        impl->config = OCIO::Config::CreateFromFile(path.c_str());
        impl->config->validate();
    } catch (const OCIO::Exception& e) {
        throw ColorError("cannot load OCIO config '" + path + "': " + e.what());
    }
    auto scene = impl->config->getColorSpace(OCIO::ROLE_SCENE_LINEAR);
    if (!scene) throw ColorError("OCIO config '" + path + "' has no scene_linear role");
    impl->working = scene->getName();
    impl->display = impl->config->getDefaultDisplay();
    impl->view = impl->config->getDefaultView(impl->display.c_str());
    impl->cacheId = impl->config->getCacheID();
    return std::shared_ptr<const ColorConfig>(new ColorConfig(std::move(impl)));
}

ColorConfig::ColorConfig(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ColorConfig::~ColorConfig() = default;

const std::string& ColorConfig::workingSpace() const { return impl_->working; }
std::string ColorConfig::defaultDisplay() const { return impl_->display; }
std::string ColorConfig::defaultView() const { return impl_->view; }
const std::string& ColorConfig::configPath() const { return impl_->path; }
const std::string& ColorConfig::cacheId() const { return impl_->cacheId; }

std::vector<std::string> ColorConfig::acceptedColorspaceNames() const { return impl_->allColorspaceNames(); }

std::vector<std::string> ColorConfig::colorspaces() const {
    std::vector<std::string> out;
    auto& cfg = impl_->config;
    int n = cfg->getNumColorSpaces(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ACTIVE);
    for (int i = 0; i < n; ++i)
        out.push_back(cfg->getColorSpaceNameByIndex(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ACTIVE, i));
    return out;
}

std::vector<std::string> ColorConfig::views(const std::string& display) const {
    std::string d = display.empty() ? impl_->display : display;
    bool known = false;
    std::vector<std::string> displays;
    for (int i = 0; i < impl_->config->getNumDisplays(); ++i) {
        displays.push_back(impl_->config->getDisplay(i));
        if (displays.back() == d) known = true;
    }
    if (!known) throw ColorError(unknownNameMessage("display", d, displays));
    return impl_->viewNames(d);
}

bool ColorConfig::hasColorspace(const std::string& name) const {
    try {
        impl_->resolve(name);
        return true;
    } catch (const ColorError&) {
        return false;
    }
}

bool ColorConfig::hasView(const std::string& view) const {
    for (const auto& v : impl_->viewNames(impl_->display))
        if (v == view) return true;
    return false;
}

std::string ColorConfig::canonicalColorspace(const std::string& name) const {
    auto cs = impl_->resolve(name);
    if (!cs || cs->isData()) return "raw";
    return cs->getName();
}

bool ColorConfig::isData(const std::string& name) const {
    auto cs = impl_->resolve(name);
    return !cs || cs->isData();
}

namespace {

void applyCpu(const OCIO::ConstCPUProcessorRcPtr& cpu, float* rgb, size_t pixelCount) {
    if (!cpu || pixelCount == 0) return;
    try {
        OCIO::PackedImageDesc img(rgb, long(pixelCount), 1, 3);
        cpu->apply(img);
    } catch (const OCIO::Exception& e) {
        throw ColorError(std::string("OCIO conversion failed: ") + e.what());
    }
}

}  // namespace

// Shared by toWorking/fromWorking: cached processor between 'colorspace' and the working space.
static void convertWorking(const ColorConfig::Impl& I, float* rgb, size_t pixelCount, const std::string& colorspace,
                           bool inverse) {
    auto cs = I.resolve(colorspace);  // throws on unknown names, even for pixelCount == 0
    if (!cs || cs->isData()) return;
    std::string name = cs->getName();
    if (name == I.working) return;

    OCIO::ConstCPUProcessorRcPtr cpu;
    {
        std::lock_guard<std::mutex> lock(I.mutex);
        auto& cache = inverse ? I.fromWorking : I.toWorking;
        auto it = cache.find(name);
        if (it != cache.end()) {
            cpu = it->second;
        } else {
            try {
                auto proc = inverse ? I.config->getProcessor(I.working.c_str(), name.c_str())
                                    : I.config->getProcessor(name.c_str(), I.working.c_str());
                if (!proc->isNoOp()) cpu = proc->getOptimizedCPUProcessor(kOptimization);
            } catch (const OCIO::Exception& e) {
                throw ColorError("cannot convert between colorspace '" + colorspace + "' and '" + I.working +
                                 "': " + e.what());
            }
            cache.emplace(name, cpu);
        }
    }
    applyCpu(cpu, rgb, pixelCount);
}

void ColorConfig::toWorking(float* rgb, size_t pixelCount, const std::string& colorspace) const {
    convertWorking(*impl_, rgb, pixelCount, colorspace, false);
}

void ColorConfig::fromWorking(float* rgb, size_t pixelCount, const std::string& colorspace) const {
    convertWorking(*impl_, rgb, pixelCount, colorspace, true);
}

namespace {
// Exposure (stops, a gain first) then the display's view: the one processor toDisplay and gpuDisplayShader share.
OCIO::ConstProcessorRcPtr displayProcessor(const ColorConfig::Impl& I, const std::string& v, float exposureStops) {
    try {
        auto group = OCIO::GroupTransform::Create();
        if (exposureStops != 0.f) {
            double g = std::exp2(double(exposureStops));
            double m44[16] = {g, 0, 0, 0, 0, g, 0, 0, 0, 0, g, 0, 0, 0, 0, 1};
            auto mtx = OCIO::MatrixTransform::Create();
            mtx->setMatrix(m44);
            group->appendTransform(mtx);
        }
        auto dvt = OCIO::DisplayViewTransform::Create();
        dvt->setSrc(I.working.c_str());
        dvt->setDisplay(I.display.c_str());
        dvt->setView(v.c_str());
        group->appendTransform(dvt);
        return I.config->getProcessor(group);
    } catch (const OCIO::Exception& e) {
        throw ColorError("cannot build display transform for view '" + v + "': " + e.what());
    }
}
}  // namespace

void ColorConfig::toDisplay(float* rgb, size_t pixelCount, const std::string& view, float exposureStops) const {
    std::string v = view.empty() ? impl_->view : view;
    if (!hasView(v)) throw ColorError(unknownNameMessage("view", v, impl_->viewNames(impl_->display)));
    if (!std::isfinite(exposureStops)) throw ColorError("exposure must be finite");

    OCIO::ConstCPUProcessorRcPtr cpu;
    {
        std::lock_guard<std::mutex> lock(impl_->mutex);
        auto key = std::make_pair(v, exposureStops);
        auto it = impl_->toDisplay.find(key);
        if (it != impl_->toDisplay.end()) {
            cpu = it->second;
        } else {
            auto proc = displayProcessor(*impl_, v, exposureStops);
            if (!proc->isNoOp()) cpu = proc->getOptimizedCPUProcessor(kOptimization);
            impl_->toDisplay.emplace(key, cpu);
        }
    }
    applyCpu(cpu, rgb, pixelCount);
}

ColorConfig::GpuDisplayShader ColorConfig::gpuDisplayShader(const std::string& view, float exposureStops,
                                                            const std::string& functionName,
                                                            const std::string& resourcePrefix) const {
    std::string v = view.empty() ? impl_->view : view;
    if (!hasView(v)) throw ColorError(unknownNameMessage("view", v, impl_->viewNames(impl_->display)));
    if (!std::isfinite(exposureStops)) throw ColorError("exposure must be finite");
    GpuDisplayShader out;
    out.functionName = functionName;
    try {
        std::lock_guard<std::mutex> lock(impl_->mutex);
        auto proc = displayProcessor(*impl_, v, exposureStops);
        OCIO::GpuShaderDescRcPtr desc = OCIO::GpuShaderDesc::CreateShaderDesc();
        desc->setLanguage(OCIO::GPU_LANGUAGE_GLSL_4_0);
        desc->setFunctionName(functionName.c_str());
        desc->setResourcePrefix(resourcePrefix.c_str());
        proc->getOptimizedGPUProcessor(kOptimization)->extractGpuShaderInfo(desc);
        if (desc->getNumUniforms() != 0)
            throw ColorError("view '" + v + "' has dynamic properties, which the GPU display path does not set");
        out.glsl = desc->getShaderText();
        for (unsigned i = 0; i < desc->getNumTextures(); ++i) {
            const char *tex = nullptr, *sampler = nullptr;
            unsigned w = 0, h = 0;
            OCIO::GpuShaderDesc::TextureType channel;
            OCIO::Interpolation interp;
            desc->getTexture(i, tex, sampler, w, h, channel, interp);
            const float* values = nullptr;
            desc->getTextureValues(i, values);
            GpuDisplayShader::Lut lut;
            lut.samplerName = sampler;
            lut.width = int(w), lut.height = int(h);
            lut.channels = channel == OCIO::GpuShaderDesc::TEXTURE_RED_CHANNEL ? 1 : 3;
            lut.linear = interp != OCIO::INTERP_NEAREST;
            lut.values.assign(values, values + size_t(w) * h * size_t(lut.channels));
            out.luts.push_back(std::move(lut));
        }
        for (unsigned i = 0; i < desc->getNum3DTextures(); ++i) {
            const char *tex = nullptr, *sampler = nullptr;
            unsigned edge = 0;
            OCIO::Interpolation interp;
            desc->get3DTexture(i, tex, sampler, edge, interp);
            const float* values = nullptr;
            desc->get3DTextureValues(i, values);
            GpuDisplayShader::Lut lut;
            lut.samplerName = sampler;
            lut.width = lut.height = lut.depth = int(edge);
            lut.channels = 3;
            lut.linear = interp != OCIO::INTERP_NEAREST;
            lut.values.assign(values, values + size_t(edge) * edge * edge * 3);
            out.luts.push_back(std::move(lut));
        }
    } catch (const OCIO::Exception& e) {
        throw ColorError("cannot build the GPU display shader for view '" + v + "': " + e.what());
    }
    return out;
}

}  // namespace specula
