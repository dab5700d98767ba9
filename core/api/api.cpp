// libspecula's public C++ API (include/specula/specula.h) over the internal scene loader, renderer, output
// policies (core/api/specula.h), GLSL emitter and node registry.
#include "specula/specula.h"

#include "core/api/node_catalog.h"
#include "core/api/specula.h"
#include "core/util/input_files.h"
#include "core/codegen/glsl_emitter.h"
#include "core/codegen/glsl_manifest.h"
#include "core/graph/graph.h"
#include "core/graph/graph_material.h"
#include "core/graph/node_spec.h"
#include "core/render/material.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <malloc.h>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace specula {

void registerBuiltinNodes() { (void)graph::NodeRegistry::instance(); }

namespace api {
namespace {

// Every exception leaving the API is an Error: libspecula's own errors keep their code, pointer and
// suggestion; other failures get the code the CLI would exit with.
template <class F>
auto guarded(F&& f) -> decltype(f()) {
    try {
        registerBuiltinNodes();
        return f();
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        int code = exitCodeFor(e);
        throw Error(code == kExitUsage ? ErrorCode::Usage : ErrorCode::BadInput, "", e.what());
    }
}

// RFC 6901 unescaping of one reference token.
std::string unescapeToken(const std::string& t) {
    std::string s;
    for (size_t i = 0; i < t.size(); ++i) {
        if (t[i] == '~' && i + 1 < t.size() && (t[i + 1] == '0' || t[i + 1] == '1')) {
            s += t[i + 1] == '0' ? '~' : '/';
            ++i;
        } else {
            s += t[i];
        }
    }
    return s;
}

}  // namespace

void LoadOptions::setLimit(const std::string& name, int64_t value) {
    SceneLimits l;  // the built-in maxima, checked and parsed by the same rule as the CLI's --limit
    try {
        setSceneLimit(l, name + "=" + std::to_string(value));
    } catch (const std::invalid_argument& e) {
        std::string m = e.what();  // the CLI's wording names its option: "--limit: ..." / "--limit spp ..."
        if (m.rfind("--", 0) == 0) m = m.substr(2);
        throw Error(ErrorCode::Usage, "", m);
    }
    const SceneLimits builtin;
    if (l.maxPixels != builtin.maxPixels) maxPixels = l.maxPixels;
    if (l.maxTriangles != builtin.maxTriangles) maxTriangles = l.maxTriangles;
    if (l.maxSpp != builtin.maxSpp) maxSpp = l.maxSpp;
    if (l.maxTextureSide != builtin.maxTextureSide) maxTextureSide = l.maxTextureSide;
    if (l.maxGraphNodes != builtin.maxGraphNodes) maxGraphNodes = l.maxGraphNodes;
    if (l.maxJsonDepth != builtin.maxJsonDepth) maxJsonDepth = l.maxJsonDepth;
}

namespace {

// The options' ranges are the CLI's (core/api/specula.h option_rules); 0 (or a negative seed) keeps the scene's.
SceneOverrides overridesOf(const LoadOptions& o) {
    if (o.spp != 0) checkOption(option_rules::spp, o.spp);
    if (o.seed >= 0) checkOption(option_rules::seed, double(o.seed));
    if (o.width != 0 || o.height != 0) {
        checkOption(option_rules::resolutionSide, o.width);
        checkOption(option_rules::resolutionSide, o.height);
    }
    if (o.hasFrame) checkOption(option_rules::frame, o.frame);
    SceneOverrides ov;
    ov.spp = o.spp;
    ov.seed = o.seed;
    ov.width = o.width;
    ov.height = o.height;
    if (o.cropX0 || o.cropY0 || o.cropX1 || o.cropY1) ov.crop = CropWindow{o.cropX0, o.cropY0, o.cropX1, o.cropY1};
    if (o.hasFrame) ov.frame = o.frame;
    SceneLimits& l = ov.limits;  // starts at the built-in maxima; a positive option can only lower one
    if (o.maxPixels > 0) l.maxPixels = std::min(l.maxPixels, o.maxPixels);
    if (o.maxTriangles > 0) l.maxTriangles = std::min(l.maxTriangles, o.maxTriangles);
    if (o.maxSpp > 0) l.maxSpp = std::min(l.maxSpp, o.maxSpp);
    if (o.maxTextureSide > 0) l.maxTextureSide = std::min(l.maxTextureSide, o.maxTextureSide);
    if (o.maxGraphNodes > 0) l.maxGraphNodes = std::min(l.maxGraphNodes, o.maxGraphNodes);
    if (o.maxJsonDepth > 0) l.maxJsonDepth = std::min(l.maxJsonDepth, o.maxJsonDepth);
    return ov;
}

const specula::ImageSet& imagesOf(const void* p) { return *static_cast<const specula::ImageSet*>(p); }

AovView viewOf(const specula::ImageSet& img, const std::string& name) {
    for (const AovBuffer& b : img.aovs)  // not ImageSet::find: no image I/O module needed for pixel access
        if (b.name == name) return AovView{b.name, b.channelNames, img.width, img.height, b.pixels.data()};
    std::vector<std::string> names;
    for (const AovBuffer& b : img.aovs) names.push_back(b.name);
    throw Error(ErrorCode::BadInput, "", "unknown AOV '" + name + "'", nearestName(name, names));
}

RenderStats statsOf(const specula::RenderStats& s) {
    return RenderStats{s.samples, s.invalidSamples, s.seconds, s.tilesDone, s.tilesTotal, s.cancelled};
}

Tile tileOf(const RenderProgress& p) {
    Tile t;
    t.x0 = p.tileX0, t.y0 = p.tileY0, t.x1 = p.tileX1, t.y1 = p.tileY1;
    t.originX = p.originX, t.originY = p.originY;
    t.tilesDone = p.tilesDone, t.tilesTotal = p.tilesTotal;
    t.elapsedSeconds = p.elapsedSeconds, t.samplesPerSecond = p.samplesPerSecond, t.etaSeconds = p.etaSeconds;
    t.images_ = p.images;
    return t;
}

}  // namespace

std::string version() { return SPECULA_VERSION; }

std::string nodeCatalogJson(int indent) {
    return guarded([&] { return specula::nodeCatalogJson().dump(indent); });
}

// ---- Tile ------------------------------------------------------------------------------------------
AovView Tile::aov(const std::string& name) const { return viewOf(imagesOf(images_), name); }
const float* Tile::rgb(int x, int y) const { return aov("beauty").at(x - originX, y - originY); }

// ---- RenderResult ----------------------------------------------------------------------------------
struct RenderResult::Impl {
    specula::ImageSet images;
    specula::RenderStats internalStats;
    RenderStats stats;
};
RenderResult::RenderResult() : impl_(std::make_unique<Impl>()) {}
RenderResult::~RenderResult() = default;
RenderResult::RenderResult(RenderResult&&) noexcept = default;
RenderResult& RenderResult::operator=(RenderResult&&) noexcept = default;
int RenderResult::width() const { return impl_->images.width; }
int RenderResult::height() const { return impl_->images.height; }
const RenderStats& RenderResult::stats() const { return impl_->stats; }
std::vector<std::string> RenderResult::aovNames() const {
    std::vector<std::string> n;
    for (const AovBuffer& b : impl_->images.aovs) n.push_back(b.name);
    return n;
}
AovView RenderResult::aov(const std::string& name) const { return viewOf(impl_->images, name); }

// ---- Scene -----------------------------------------------------------------------------------------
struct Scene::Impl {
    Json doc;
    std::string baseDir, path;  // path: the file it came from ("" for a string)
    specula::Scene scene;
    LoadOptions options;        // re-applied when setValue re-loads
    std::string name;           // for messages
    std::vector<std::string> inputs;  // every file the load read (the scene, textures, meshes): never an output
};

namespace {
std::unique_ptr<Scene::Impl> loadImpl(const std::string& text, const std::string& baseDir, const LoadOptions& o,
                                      const std::string& name, const std::string& path) {
    auto impl = std::make_unique<Scene::Impl>();
    InputFileScope reads;  // what the loader opens, remembered for writeOutputs (core/util/input_files.h)
    impl->scene = loadSceneFromString(text, baseDir.empty() ? "." : baseDir, overridesOf(o), name);
    impl->inputs = notedInputFiles();
    if (!path.empty()) impl->inputs.push_back(path);
    impl->doc = Json::parse(text);  // valid: the loader accepted it
    impl->baseDir = baseDir.empty() ? "." : baseDir;
    impl->path = path;
    impl->options = o;
    impl->name = name;
    return impl;
}
}  // namespace

Scene::Scene() = default;
Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

Scene Scene::fromFile(const std::string& path, const LoadOptions& opts) {
    return guarded([&] {
        const std::string text = readJsonText(path);  // bounded: /dev/zero is bad input, not a hang
        std::string base = fs::path(path).parent_path().string();
        Scene s;
        s.impl_ = loadImpl(text, base, opts, path, path);
        return s;
    });
}

Scene Scene::fromString(const std::string& text, const std::string& baseDir, const LoadOptions& opts,
                        const std::string& name) {
    return guarded([&] {
        Scene s;
        s.impl_ = loadImpl(text, baseDir, opts, name, "");
        return s;
    });
}

std::vector<std::string> Scene::materialNames() const {
    std::vector<std::string> n;
    for (auto& m : impl_->scene.materials) n.push_back(m->name());
    return n;
}
std::vector<std::string> Scene::warnings() const { return impl_->scene.warnings; }
std::string Scene::json(int indent) const { return impl_->doc.dump(indent); }

void Scene::setLiteral(const std::string& pointer, const std::string& valueJson) {
    guarded([&] {
        const std::string prefix = "/materials/";
        if (pointer.compare(0, prefix.size(), prefix) != 0)
            throw Error(ErrorCode::BadInput, pointer, "setLiteral edits material literals: the pointer must start with /materials/<name>/");
        size_t slash = pointer.find('/', prefix.size());
        std::string key = unescapeToken(pointer.substr(prefix.size(), slash - prefix.size()));
        std::string rel = slash == std::string::npos ? "" : pointer.substr(slash);
        const Json& mats = impl_->doc.contains("materials") ? impl_->doc.at("materials") : Json::object();
        if (!mats.contains(key)) {
            std::vector<std::string> names = materialNames();
            throw Error(ErrorCode::BadInput, "/materials/" + pointerEscape(key), "unknown material '" + key + "'",
                        nearestName(key, names));
        }
        if (rel.empty() || rel == "/") throw Error(ErrorCode::BadInput, pointer, "the pointer names a whole material, not a literal");
        Json value = Json::parse(valueJson, nullptr, false);
        if (value.is_discarded()) throw Error(ErrorCode::BadInput, pointer, "value is not JSON: " + valueJson);
        if (value.is_object()) throw Error(ErrorCode::BadInput, pointer, "a literal is a number, array, string or boolean");
        Json mat = mats.at(key);
        Json::json_pointer jp(rel);
        if (!mat.contains(jp.parent_pointer()) || !mat.at(jp.parent_pointer()).is_object())
            throw Error(ErrorCode::BadInput, pointer, "no such object in the material");
        if (mat.contains(jp) && mat.at(jp).is_object())
            throw Error(ErrorCode::BadInput, pointer, "the pointer names an object, not a literal");
        mat[jp] = value;
        // Recompile this material only; the scene is unchanged if it fails.
        std::string matPtr = "/materials/" + pointerEscape(key);
        auto m = loadGraphMaterial(mat, matPtr,
                                   GraphLoadContext{impl_->scene.textures.get(), impl_->baseDir, &impl_->scene.warnings});
        m->setName(key);
        for (auto& slot : impl_->scene.materials)
            if (slot->name() == key) slot = std::move(m);
        impl_->doc["materials"][key] = std::move(mat);
    });
}

void Scene::setValue(const std::string& pointer, const std::string& valueJson) {
    guarded([&] {
        if (pointer.empty() || pointer[0] != '/')
            throw Error(ErrorCode::BadInput, pointer, "setValue needs a JSON pointer naming a value inside the scene (e.g. /render/spp)");
        Json value = Json::parse(valueJson, nullptr, false);
        if (value.is_discarded()) throw Error(ErrorCode::BadInput, pointer, "value is not JSON: " + valueJson);
        Json::json_pointer jp;
        try {
            jp = Json::json_pointer(pointer);
        } catch (const std::exception&) {
            throw Error(ErrorCode::BadInput, pointer, "not a valid JSON pointer (RFC 6901)");
        }
        const Json::json_pointer parent = jp.parent_pointer();
        // The cheap path: a value inside a material node (/materials/<name>/<at least two more tokens>) that
        // is not an object is a literal edit: setLiteral recompiles that material alone.
        const std::string prefix = "/materials/";
        size_t depth = 0;
        for (char c : pointer) depth += c == '/';
        if (pointer.compare(0, prefix.size(), prefix) == 0 && depth >= 4 && !value.is_object() &&
            impl_->doc.contains(parent) && impl_->doc.at(parent).is_object() &&
            !(impl_->doc.contains(jp) && impl_->doc.at(jp).is_object())) {
            setLiteral(pointer, valueJson);
            return;
        }
        if (!impl_->doc.contains(parent) || !(impl_->doc.at(parent).is_object() || impl_->doc.at(parent).is_array())) {
            // Name the first missing (or non-container) step, with the nearest existing key as the suggestion.
            const Json* node = &impl_->doc;
            std::string at;
            size_t pos = 1;
            while (pos <= pointer.size()) {
                size_t next = pointer.find('/', pos);
                if (next == std::string::npos) next = pointer.size();
                std::string token = unescapeToken(pointer.substr(pos, next - pos));
                std::string here = at + "/" + pointer.substr(pos, next - pos);
                if (node->is_object() && !node->contains(token)) {
                    std::vector<std::string> keys;
                    for (auto it = node->begin(); it != node->end(); ++it) keys.push_back(it.key());
                    throw Error(ErrorCode::BadInput, here, "no key '" + token + "' in " + (at.empty() ? "/" : at),
                                nearestName(token, keys));
                }
                if (!node->is_object() && !node->is_array())
                    throw Error(ErrorCode::BadInput, here, (at.empty() ? std::string("/") : at) + " is not an object or array");
                node = node->is_object() ? &node->at(token) : nullptr;
                if (!node) break;  // an array step: reported below
                at = here;
                pos = next + 1;
            }
            throw Error(ErrorCode::BadInput, pointer, "no such object or array in the scene: " +
                                                          (parent.empty() ? std::string("/") : parent.to_string()));
        }
        Json doc = impl_->doc;
        Json& p = doc.at(parent);
        const std::string token = jp.back();
        if (p.is_array()) {
            if (token == "-") {
                p.push_back(std::move(value));
            } else {
                size_t i = 0;
                bool digits = !token.empty() && token.find_first_not_of("0123456789") == std::string::npos;
                if (digits) i = std::stoul(token);
                if (!digits || i >= p.size())
                    throw Error(ErrorCode::BadInput, pointer, "array index out of range (use /- to append)");
                p[i] = std::move(value);
            }
        } else {
            p[token] = std::move(value);
        }
        // Re-load the edited document; *this is replaced only when it loads.
        impl_ = loadImpl(doc.dump(), impl_->baseDir, impl_->options, impl_->name, impl_->path);
    });
}

RenderResult Scene::render(const RenderOptions& opts, TileCallback onTile) const {
    RenderJob job = renderAsync(opts, std::move(onTile));
    return job.wait();
}

// ---- RenderJob -------------------------------------------------------------------------------------
struct RenderJob::Impl {
    std::atomic<bool> cancel{false}, finished{false};
    std::thread worker;
    RenderResult result;
    std::exception_ptr error;
    bool waited = false;
};

RenderJob::RenderJob() = default;
RenderJob::~RenderJob() {
    if (impl_ && impl_->worker.joinable()) {
        impl_->cancel = true;
        impl_->worker.join();
    }
}
RenderJob::RenderJob(RenderJob&&) noexcept = default;
RenderJob& RenderJob::operator=(RenderJob&& o) noexcept {
    if (this != &o) {
        this->~RenderJob();
        new (this) RenderJob(std::move(o));
    }
    return *this;
}
void RenderJob::cancel() {
    if (impl_) impl_->cancel = true;
}
bool RenderJob::done() const { return !impl_ || impl_->finished.load(); }
RenderResult RenderJob::wait() {
    if (!impl_ || impl_->waited) throw Error(ErrorCode::Usage, "", "RenderJob::wait: no render (or already waited)");
    if (impl_->worker.joinable()) impl_->worker.join();
    impl_->waited = true;
    if (impl_->error) std::rethrow_exception(impl_->error);
    return std::move(impl_->result);
}

RenderJob Scene::renderAsync(const RenderOptions& opts, TileCallback onTile) const {
    return guarded([&] {
        RenderJob job;
        job.impl_ = std::make_unique<RenderJob::Impl>();
        RenderJob::Impl* j = job.impl_.get();
        const specula::Scene* scene = &impl_->scene;
        checkOption(option_rules::threads, opts.threads);
        int threads = opts.threads;
        uint64_t maxMemory = opts.maxMemoryBytes;
        j->worker = std::thread([j, scene, threads, maxMemory, cb = std::move(onTile)] {
            try {
                specula::RenderOptions ro;
                ro.threads = threads;
                ro.maxMemoryBytes = maxMemory;
                ro.cancel = &j->cancel;
                if (cb)
                    ro.onTile = [&](const RenderProgress& p) {
                        if (!cb(tileOf(p))) j->cancel = true;
                    };
                RenderOutput out = renderScene(*scene, ro);
                j->result.impl_->images = std::move(out.images);
                j->result.impl_->internalStats = out.stats;
                j->result.impl_->stats = statsOf(out.stats);
            } catch (const Error&) {  // keeps its code and pointer (e.g. the memory estimate's "/render")
                j->error = std::current_exception();
            } catch (const std::exception& e) {
                try {
                    throw Error(ErrorCode::BadInput, "", e.what());
                } catch (...) {
                    j->error = std::current_exception();
                }
            }
            // Hand the render's freed memory (film, tiles' arenas, the BVH) back to the system: glibc keeps it in the
            // arenas of the threads that freed it, and a host rendering again and again grew by ~12 KiB a render
            // (issue 16's soak: 11 MiB over 900 renders without this).
            malloc_trim(0);
            j->finished = true;
        });
        return job;
    });
}

// ---- outputs ---------------------------------------------------------------------------------------
WrittenOutputs Scene::writeOutputs(const RenderResult& result, const std::string& exrPath) const {
    return guarded([&] {
        checkOutputPath(exrPath, impl_->path);
        for (const std::string& out : {exrPath, fs::path(exrPath).replace_extension(".png").string(), partialOutputPath(exrPath)})
            refuseOverwritingInputs(out, impl_->inputs, "output");
        specula::ImageSet images = result.impl_->images;
        WrittenFiles w;
        try {
            w = writeRenderResult(exrPath, impl_->scene, images, result.impl_->internalStats);
        } catch (const Error&) {
            throw;
        } catch (const std::exception& e) {
            throw Error(ErrorCode::Io, "", e.what());
        }
        return WrittenOutputs{w.exr, w.png, w.partial};
    });
}

std::string partialPathFor(const std::string& exrPath) { return partialOutputPath(exrPath); }

std::string tileEventJson(const Tile& t) {
    RenderProgress p;
    p.tilesDone = t.tilesDone, p.tilesTotal = t.tilesTotal;
    p.tileX0 = t.x0, p.tileY0 = t.y0, p.tileX1 = t.x1, p.tileY1 = t.y1;
    p.elapsedSeconds = t.elapsedSeconds, p.samplesPerSecond = t.samplesPerSecond, p.etaSeconds = t.etaSeconds;
    return specula::tileEventJson(p);
}
std::string cancelledEventJson(const RenderStats& s, const std::string& partialPath) {
    specula::RenderStats st;
    st.tilesDone = s.tilesDone, st.tilesTotal = s.tilesTotal;
    return specula::cancelledEventJson(st, partialPath);
}
std::string doneEventJson(const RenderStats& s, const std::string& exrPath, const std::string& pngPath) {
    specula::RenderStats st;
    st.samples = s.samples, st.invalidSamples = s.invalidSamples, st.seconds = s.seconds;
    return specula::doneEventJson(st, exrPath, pngPath);
}

// ---- GLSL ------------------------------------------------------------------------------------------
GlslModule Scene::compileGlsl(const std::string& material, bool literalsAsUniforms) const {
    return guarded([&] {
        const Json& mats = impl_->doc.contains("materials") ? impl_->doc.at("materials") : Json::object();
        std::string key = material;
        if (key.empty()) {
            if (mats.size() != 1)
                throw Error(ErrorCode::Usage, "/materials", "the scene has " + std::to_string(mats.size()) +
                                                                " materials: name one");
            key = mats.begin().key();
        }
        if (!mats.contains(key))
            throw Error(ErrorCode::BadInput, "/materials/" + pointerEscape(key), "unknown material '" + key + "'",
                        nearestName(key, materialNames()));
        std::string ptr = "/materials/" + pointerEscape(key);
        graph::GraphDesc g = graph::parseGraph(mats.at(key), ptr);
        codegen::GlslOptions o;
        o.materialName = key;
        o.literalsAsUniforms = literalsAsUniforms;
        codegen::GlslModule m = codegen::emitGlsl(g, o);
        // The manifest of codegen::glslManifest: uniform block and every resource with binding, type, size, format,
        // colour space and sampler state (the texels come from the scene's textures).
        std::vector<graph::ResourceImage> images =
            codegen::exportGlslResources(g, m, GraphLoadContext{impl_->scene.textures.get(), impl_->baseDir});
        Json r = codegen::glslManifest(m, images, {});
        r["node_types"] = m.nodeTypes;
        return GlslModule{m.source, r.dump()};
    });
}

// ---- SceneBuilder ----------------------------------------------------------------------------------
struct SceneBuilder::Impl {
    Json doc = {{"version", 1}, {"materials", Json::object()}, {"shapes", Json::array()}, {"lights", Json::array()}};
};
SceneBuilder::SceneBuilder() : impl_(std::make_unique<Impl>()) {}
SceneBuilder::~SceneBuilder() = default;
SceneBuilder& SceneBuilder::resolution(int width, int height) {
    impl_->doc["render"]["width"] = width;
    impl_->doc["render"]["height"] = height;
    return *this;
}
SceneBuilder& SceneBuilder::samples(int spp, int64_t seed) {
    impl_->doc["render"]["spp"] = spp;
    impl_->doc["render"]["seed"] = seed;
    return *this;
}
SceneBuilder& SceneBuilder::camera(const float position[3], const float lookAt[3], float fov) {
    impl_->doc["camera"] = {{"position", {position[0], position[1], position[2]}},
                            {"look_at", {lookAt[0], lookAt[1], lookAt[2]}},
                            {"fov", fov}};
    return *this;
}
namespace {
Json parsePiece(const std::string& text, const std::string& what) {
    Json j = Json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object()) throw Error(ErrorCode::BadInput, "", what + " is not a JSON object: " + text);
    return j;
}
}  // namespace
SceneBuilder& SceneBuilder::material(const std::string& name, const std::string& graphJson) {
    impl_->doc["materials"][name] = parsePiece(graphJson, "material '" + name + "'");
    return *this;
}
SceneBuilder& SceneBuilder::sphere(const float c[3], float radius, const std::string& material) {
    impl_->doc["shapes"].push_back(
        {{"type", "sphere"}, {"radius", radius}, {"transform", {{"translate", {c[0], c[1], c[2]}}}}, {"material", material}});
    return *this;
}
SceneBuilder& SceneBuilder::shape(const std::string& shapeJson) {
    impl_->doc["shapes"].push_back(parsePiece(shapeJson, "shape"));
    return *this;
}
SceneBuilder& SceneBuilder::light(const std::string& lightJson) {
    impl_->doc["lights"].push_back(parsePiece(lightJson, "light"));
    return *this;
}
std::string SceneBuilder::json(int indent) const { return impl_->doc.dump(indent); }
Scene SceneBuilder::build(const std::string& baseDir, const LoadOptions& opts) const {
    return Scene::fromString(impl_->doc.dump(), baseDir, opts, "<SceneBuilder>");
}

}  // namespace api
}  // namespace specula
