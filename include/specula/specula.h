// libspecula's public C++ API (docs/api.md). Only standard-library types cross it: link with
// find_package(Specula) -> Specula::specula, or pkg-config specula.
//
//   namespace sp = specula::api;
//   sp::Scene scene = sp::Scene::fromString(json);               // or fromFile(path)
//   sp::RenderJob job = scene.renderAsync({}, [](const sp::Tile& t) { ...; return true; });
//   sp::RenderResult r = job.wait();
//   scene.writeOutputs(r, "out.exr");                            // atomic, partial-on-cancel, never clobbers
#pragma once

#include "specula/error.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace specula {

// Adds every built-in node to the registry. Idempotent and thread-safe; every entry point below calls it, so
// an application needs it only before using the internal registry directly.
void registerBuiltinNodes();

// The API's classes live in specula::api (specula::Scene etc. are libspecula's internal types).
namespace api {

// "0.1.0".
std::string version();

// The node catalogue: {"nodes": [ {id, version, category, doc, inputs, outputs, ...}, ... ]} (the same JSON
// as `specula nodes --json`), pretty-printed with 'indent' spaces (-1: one line).
std::string nodeCatalogJson(int indent = 2);

// One AOV of a rendered image: 'channels' floats per pixel, rows top to bottom, scene-linear.
struct AovView {
    std::string name;                       // beauty, diffuse, specular, albedo, normal, uv, depth
    std::vector<std::string> channelNames;  // e.g. R,G,B / X,Y,Z / U,V / Z
    int width = 0, height = 0;
    const float* pixels = nullptr;          // width*height*channels()
    int channels() const { return int(channelNames.size()); }
    const float* at(int x, int y) const { return pixels + (size_t(y) * size_t(width) + size_t(x)) * size_t(channels()); }
};

// A finished tile, handed to the progress callback. Rectangle [x0,x1)×[y0,y1) in frame pixels; the
// image (and 'aov') covers the crop window, whose top-left frame pixel is (originX, originY).
struct Tile {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    int originX = 0, originY = 0;
    int tilesDone = 0, tilesTotal = 0;
    double elapsedSeconds = 0, samplesPerSecond = 0, etaSeconds = 0;
    // Pixel access: the tile's own pixels are final; pixels of other tiles may still be changing.
    AovView aov(const std::string& name = "beauty") const;
    // Beauty RGB of frame pixel (x, y) inside this tile.
    const float* rgb(int x, int y) const;

    const void* images_ = nullptr;  // internal
};

// Return false to cancel the render. Called serially (one tile at a time, under a lock) from the render's
// worker threads, never concurrently with itself: keep it short, and synchronise with the thread that
// waits if you share data.
using TileCallback = std::function<bool(const Tile&)>;

// Overrides applied when a scene is loaded (the camera depends on the image size).
struct LoadOptions {
    int spp = 0;                                         // 0: the scene's
    int64_t seed = -1;                                   // <0: the scene's
    int width = 0, height = 0;                           // 0: the scene's
    int cropX0 = 0, cropY0 = 0, cropX1 = 0, cropY1 = 0;  // all 0: the whole frame
    // The animation frame (the scene's "animation" block, docs/scene-format.md#animation; `specula render --frame`);
    // hasFrame false: the scene's frame_start. A frame outside the range fails with Error bad_input.
    bool hasFrame = false;
    int frame = 0;
    // A host's caps on what the scene may ask for (docs/reliability.md "Limits"); 0: the built-in maximum, and no cap
    // can exceed it. Beyond a cap the load fails with Error bad_input at the JSON pointer of what exceeds it.
    int64_t maxPixels = 0, maxTriangles = 0;
    int maxSpp = 0, maxTextureSide = 0, maxGraphNodes = 0, maxJsonDepth = 0;
    // Sets one cap by the CLI's name (`specula render --limit NAME=VALUE`: pixels, spp, triangles, texture_side,
    // graph_nodes, json_depth). Throws Error (usage) for an unknown name, naming the nearest, or a value outside
    // 1 .. the built-in maximum.
    void setLimit(const std::string& name, int64_t value);
};

struct RenderOptions {
    int threads = 0;  // 0: all cores. The image does not depend on it.
    // Refuse (Error, bad_input, pointer "/render") a render estimated to need more bytes than this, or than the
    // process can still get (address-space and cgroup limits, available memory); 0: only the system's limits.
    uint64_t maxMemoryBytes = 0;
};

struct RenderStats {
    uint64_t samples = 0, invalidSamples = 0;
    double seconds = 0;
    int tilesDone = 0, tilesTotal = 0;
    bool cancelled = false;
};

class RenderResult {
public:
    RenderResult();
    ~RenderResult();
    RenderResult(RenderResult&&) noexcept;
    RenderResult& operator=(RenderResult&&) noexcept;
    int width() const;
    int height() const;
    const RenderStats& stats() const;
    std::vector<std::string> aovNames() const;
    AovView aov(const std::string& name) const;  // throws Error (bad_input) for an unknown AOV

    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// A render running on its own thread (and TBB workers). Destroying a running job cancels and waits.
class RenderJob {
public:
    RenderJob();
    ~RenderJob();
    RenderJob(RenderJob&&) noexcept;
    RenderJob& operator=(RenderJob&&) noexcept;
    void cancel();           // asynchronous: the workers stop within 32 samples of their current pixel
    bool done() const;
    RenderResult wait();     // blocks; once. Rethrows an error of the render as Error.

    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The paths written by writeOutputs.
struct WrittenOutputs {
    std::string exr, png;  // exr empty for an OUT.png output, png empty for a partial image
    bool partial = false;
};

// A GLSL 4.50 module of one material, with the resources it binds.
struct GlslModule {
    std::string source;
    std::string resourcesJson;  // the module's manifest (docs/graph-format.md, "Resources"): entry points, uniform
                                // block {binding, set, size, members}, resources [{name, binding, glsl_type, kind,
                                // levels, format, colorspace, sampler state}], node_types
};

class Scene;

// A scene built in memory, one typed call at a time (each piece is the scene format's JSON object,
// docs/graph-format.md and docs/scene-schema.json); build() validates and compiles it like a file.
class SceneBuilder {
public:
    SceneBuilder();
    ~SceneBuilder();
    SceneBuilder& resolution(int width, int height);
    SceneBuilder& samples(int spp, int64_t seed = 1);
    SceneBuilder& camera(const float position[3], const float lookAt[3], float fovDegrees);
    SceneBuilder& material(const std::string& name, const std::string& graphJson);  // {"nodes":{..},"output":".."}
    SceneBuilder& sphere(const float center[3], float radius, const std::string& material);
    SceneBuilder& shape(const std::string& shapeJson);  // any shape object
    SceneBuilder& light(const std::string& lightJson);  // any light object
    std::string json(int indent = 2) const;             // the document so far
    Scene build(const std::string& baseDir = "", const LoadOptions& opts = {}) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// A loaded scene: geometry, camera, lights, compiled materials. Movable, not copyable; a const Scene may be
// rendered by several jobs at once, but setLiteral must not run while a job renders it.
class Scene {
public:
    static Scene fromFile(const std::string& path, const LoadOptions& opts = {});
    // 'baseDir' resolves relative paths (textures, meshes); empty: the current folder. 'name' is for messages.
    static Scene fromString(const std::string& json, const std::string& baseDir = "", const LoadOptions& opts = {},
                            const std::string& name = "<string>");
    Scene();
    ~Scene();
    Scene(Scene&&) noexcept;
    Scene& operator=(Scene&&) noexcept;

    std::vector<std::string> materialNames() const;
    std::vector<std::string> warnings() const;  // "<pointer>: <message>", from loading and setLiteral
    std::string json(int indent = 2) const;     // the scene document, with every setLiteral applied

    // Sets one literal of a material, e.g. ("/materials/gold/nodes/spec/inputs/roughness", "0.3"), value as
    // JSON text; recompiles only that material (no reload). Throws Error (bad_input, with the pointer) if the
    // pointer is not inside /materials/<name>/ or the edited material does not compile; the scene is then
    // unchanged.
    void setLiteral(const std::string& pointer, const std::string& valueJson);

    // Sets any value of the scene document by JSON pointer, e.g. ("/render/spp", "8") or ("/camera/fov", "30");
    // "/-" appends to an array. A material literal goes through setLiteral (cheap); anything else re-loads the
    // whole edited document (geometry, acceleration structure, textures: the cost of fromString), keeping
    // baseDir, the file path and the LoadOptions of the original load (which still override the document).
    // Throws Error (bad_input, with the pointer) if the parent of the pointer does not exist or the edited
    // scene does not load; the scene is then unchanged. Not while a job renders the scene.
    void setValue(const std::string& pointer, const std::string& valueJson);

    RenderResult render(const RenderOptions& opts = {}, TileCallback onTile = {}) const;
    // The job keeps a reference to this scene: keep the scene alive (and unmodified) until wait() returns.
    RenderJob renderAsync(const RenderOptions& opts = {}, TileCallback onTile = {}) const;

    // Writes OUT.exr (every AOV, atomically) and its OCIO-viewed PNG beside it, or for OUT.png only the viewed PNG;
    // a cancelled result goes to OUT.partial.exr instead (never over OUT.exr). Refuses (Error usage) a path that is
    // neither .exr nor .png or that is this scene's own file, and (Error io) a missing folder.
    WrittenOutputs writeOutputs(const RenderResult& result, const std::string& exrPath) const;

    // The GLSL module of a material ("" = the only one); literalsAsUniforms false inlines them.
    GlslModule compileGlsl(const std::string& material = "", bool literalsAsUniforms = true) const;

    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The output policy of writeOutputs, for front ends that build their own messages.
std::string partialPathFor(const std::string& exrPath);  // OUT.exr -> OUT.partial.exr

// The progress-event lines of `specula render --progress json` (docs/cli.md), one JSON object without newline.
std::string tileEventJson(const Tile& t);
std::string cancelledEventJson(const RenderStats& s, const std::string& partialPath);
std::string doneEventJson(const RenderStats& s, const std::string& exrPath, const std::string& pngPath);

}  // namespace api
}  // namespace specula
