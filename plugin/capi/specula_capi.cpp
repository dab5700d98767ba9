// The C ABI of plugin/capi/specula.h over libspecula's C++ API (include/specula/specula.h), compiled into
// libspecula. Thin on purpose: every policy (loading, rendering, output files, errors) is the C++ API's; this
// file only converts types, owns C-visible storage and keeps exceptions from crossing the ABI.
#include "plugin/capi/specula.h"

#include "specula/specula.h"

#include <atomic>
#include <cstdlib>
#include <cstddef>
#include <cstring>
#include <deque>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <utility>
#include <vector>

namespace sp = specula::api;
using specula::Error;
using specula::ErrorCode;

struct spc_context {
    spc_status status = SPC_OK;
    std::string message, pointer, suggestion;
};

namespace {

// A scene shared by its handle and the jobs rendering it, so that destroying the handle during a render is safe;
// 'jobs' counts the renders not yet waited for (edits are refused while it is non-zero).
struct SceneBox {
    sp::Scene scene;
    std::atomic<int> jobs{0};
};

// C-visible copy of an AovView's strings (the C++ view holds std::strings by value).
struct ViewStore {
    std::string name;
    std::vector<std::string> channels;
    std::vector<const char*> channelPtrs;
    spc_aov_view view{};
    explicit ViewStore(const sp::AovView& v) : name(v.name), channels(v.channelNames) {
        for (const std::string& c : channels) channelPtrs.push_back(c.c_str());
        view.name = name.c_str();
        view.channels = int32_t(channels.size());
        view.channel_names = channelPtrs.data();
        view.width = v.width;
        view.height = v.height;
        view.pixels = v.pixels;
    }
    ViewStore(const ViewStore&) = delete;
    ViewStore& operator=(const ViewStore&) = delete;
};

// What spc_tile.internal_ points at during one callback.
struct TileScratch {
    const sp::Tile* tile;
    std::deque<ViewStore> views;  // deque: stable addresses
};

struct Callback {
    spc_progress_fn fn = nullptr;
    void* user = nullptr;
};

spc_status statusOf(ErrorCode c) {
    switch (c) {
        case ErrorCode::Ok: return SPC_OK;
        case ErrorCode::BadInput: return SPC_BAD_INPUT;
        case ErrorCode::Usage: return SPC_USAGE;
        case ErrorCode::Io: return SPC_IO;
        case ErrorCode::Interrupted: return SPC_CANCELLED;
    }
    return SPC_INTERNAL;
}

[[noreturn]] void usage(const std::string& message) { throw Error(ErrorCode::Usage, "", message); }

template <class T>
void need(const T* p, const char* fn, const char* what) {
    if (!p) usage(std::string(fn) + ": " + what + " is NULL");
}

// Runs one entry point: clears the context's error, maps every exception to a status and a message.
template <class F>
spc_status guard(spc_context* ctx, F&& f) noexcept {
    if (!ctx) return SPC_USAGE;
    try {
        ctx->status = SPC_OK;
        ctx->message.clear(), ctx->pointer.clear(), ctx->suggestion.clear();
        ctx->status = f();
        return ctx->status;
    } catch (const Error& e) {
        try {
            ctx->message = e.what(), ctx->pointer = e.pointer(), ctx->suggestion = e.suggestion();
        } catch (...) {
        }
        return ctx->status = statusOf(e.code());
    } catch (const std::bad_alloc&) {
        ctx->message.clear(), ctx->pointer.clear(), ctx->suggestion.clear();
        return ctx->status = SPC_OUT_OF_MEMORY;
    } catch (const std::exception& e) {
        try {
            ctx->message = std::string("internal error: ") + e.what();
        } catch (...) {
        }
        return ctx->status = SPC_INTERNAL;
    } catch (...) {
        try {
            ctx->message = "internal error: unknown exception";
        } catch (...) {
        }
        return ctx->status = SPC_INTERNAL;
    }
}

char* dupString(const std::string& s) {
    char* p = static_cast<char*>(std::malloc(s.size() + 1));
    if (!p) throw std::bad_alloc();
    std::memcpy(p, s.c_str(), s.size() + 1);
    return p;
}

sp::LoadOptions loadOptionsOf(const spc_load_options* o) {
    sp::LoadOptions lo;
    if (!o) return lo;
    // ABI 1.0's struct ends at the crop window; the limits were appended in 1.1, the frame in 1.2: each is read only
    // when 'size' has it.
    constexpr size_t kSize10 = offsetof(spc_load_options, max_pixels), kSize11 = offsetof(spc_load_options, has_frame);
    if ((o->size != kSize10 && o->size != kSize11 && o->size != sizeof(spc_load_options)))
        usage("spc_load_options.size is " + std::to_string(o->size) + ", expected " + std::to_string(sizeof(spc_load_options)) +
              " (or " + std::to_string(kSize11) + " / " + std::to_string(kSize10) +
              " from an ABI 1.1 / 1.0 host): initialise it with SPC_LOAD_OPTIONS_INIT");
    lo.spp = o->spp;
    lo.seed = o->seed;
    lo.width = o->width, lo.height = o->height;
    lo.cropX0 = o->crop_x0, lo.cropY0 = o->crop_y0, lo.cropX1 = o->crop_x1, lo.cropY1 = o->crop_y1;
    if (o->size == sizeof(spc_load_options) && o->has_frame) lo.hasFrame = true, lo.frame = o->frame;
    if (o->size < kSize11) return lo;
    const std::pair<const char*, int64_t> limits[] = {
        {"pixels", o->max_pixels},           {"triangles", o->max_triangles},     {"spp", o->max_spp},
        {"texture_side", o->max_texture_side}, {"graph_nodes", o->max_graph_nodes}, {"json_depth", o->max_json_depth}};
    for (const auto& [name, value] : limits)
        if (value != 0) lo.setLimit(name, value);  // a negative or too large cap: SPC_USAGE, naming it
    return lo;
}

sp::RenderOptions renderOptionsOf(const spc_render_options* o) {
    sp::RenderOptions ro;
    if (!o) return ro;
    if (o->size < sizeof(spc_render_options))
        usage("spc_render_options.size is " + std::to_string(o->size) + ": initialise it with SPC_RENDER_OPTIONS_INIT");
    ro.threads = o->threads;
    return ro;
}

// The C++ callback calling the host's: spc_tile from sp::Tile; 0 from the host cancels.
sp::TileCallback tileCallbackOf(std::shared_ptr<Callback> cb) {
    if (!cb->fn) return {};
    return [cb](const sp::Tile& t) -> bool {
        TileScratch scratch{&t, {}};
        spc_tile c{};
        c.x0 = t.x0, c.y0 = t.y0, c.x1 = t.x1, c.y1 = t.y1;
        c.origin_x = t.originX, c.origin_y = t.originY;
        c.tiles_done = t.tilesDone, c.tiles_total = t.tilesTotal;
        c.elapsed_seconds = t.elapsedSeconds, c.samples_per_second = t.samplesPerSecond, c.eta_seconds = t.etaSeconds;
        sp::AovView beauty = t.aov("beauty");
        c.beauty = beauty.at(t.x0 - t.originX, t.y0 - t.originY);
        c.beauty_row_stride = ptrdiff_t(beauty.width) * beauty.channels();
        c.internal_ = &scratch;
        return cb->fn(&c, cb->user) != 0;
    };
}

}  // namespace

struct spc_scene {
    std::shared_ptr<SceneBox> box;
};

struct spc_result {
    sp::RenderResult result;
    std::deque<ViewStore> views;  // one per AOV, in aovNames() order
    explicit spc_result(sp::RenderResult r) : result(std::move(r)) {
        for (const std::string& n : result.aovNames()) views.emplace_back(result.aov(n));
    }
};

struct spc_job {
    std::shared_ptr<SceneBox> box;  // declared first: outlives 'job' (destroyed last)
    std::shared_ptr<Callback> cb;
    sp::RenderJob job;
    bool counted = true;  // still counted in box->jobs
    ~spc_job() {
        job = sp::RenderJob();  // cancels and joins a running render
        if (counted) --box->jobs;
    }
};

namespace {
// The result of a finished job as the host sees it: CANCELLED with a result, or OK.
spc_status finish(sp::RenderResult r, spc_result** out) {
    bool cancelled = r.stats().cancelled;
    *out = new spc_result(std::move(r));
    return cancelled ? SPC_CANCELLED : SPC_OK;
}
}  // namespace

extern "C" {

// ---- version --------------------------------------------------------------------------------------
uint32_t spc_abi_version(void) { return SPC_ABI_VERSION; }

const char* spc_version(void) {
    try {
        static const std::string v = sp::version();
        return v.c_str();
    } catch (...) {
        return "";
    }
}

int spc_abi_compatible(uint32_t host_abi) {
    return (host_abi >> 16) == SPC_ABI_VERSION_MAJOR && (host_abi & 0xffffu) <= SPC_ABI_VERSION_MINOR;
}

const char* spc_status_name(spc_status s) {
    switch (s) {
        case SPC_OK: return "ok";
        case SPC_BAD_INPUT: return "bad_input";
        case SPC_USAGE: return "usage";
        case SPC_IO: return "io";
        case SPC_INTERNAL: return "internal";
        case SPC_OUT_OF_MEMORY: return "out_of_memory";
        case SPC_CANCELLED: return "cancelled";
    }
    return "unknown";
}

// ---- context --------------------------------------------------------------------------------------
spc_status spc_context_create(spc_context** out) {
    if (!out) return SPC_USAGE;
    *out = new (std::nothrow) spc_context();
    return *out ? SPC_OK : SPC_OUT_OF_MEMORY;
}
void spc_context_destroy(spc_context* ctx) { delete ctx; }
const char* spc_last_error(const spc_context* ctx) { return ctx ? ctx->message.c_str() : ""; }
const char* spc_last_error_pointer(const spc_context* ctx) { return ctx ? ctx->pointer.c_str() : ""; }
const char* spc_last_error_suggestion(const spc_context* ctx) { return ctx ? ctx->suggestion.c_str() : ""; }
spc_status spc_last_status(const spc_context* ctx) { return ctx ? ctx->status : SPC_USAGE; }
void spc_string_free(char* s) { std::free(s); }

// ---- scenes ---------------------------------------------------------------------------------------
spc_status spc_scene_load_file(spc_context* ctx, const char* path, const spc_load_options* opts, spc_scene** out) {
    return guard(ctx, [&] {
        need(out, "spc_scene_load_file", "out");
        *out = nullptr;
        need(path, "spc_scene_load_file", "path");
        auto box = std::make_shared<SceneBox>();
        box->scene = sp::Scene::fromFile(path, loadOptionsOf(opts));
        *out = new spc_scene{std::move(box)};
        return SPC_OK;
    });
}

spc_status spc_scene_load_string(spc_context* ctx, const char* json, const char* base_dir, const spc_load_options* opts,
                                 spc_scene** out) {
    return guard(ctx, [&] {
        need(out, "spc_scene_load_string", "out");
        *out = nullptr;
        need(json, "spc_scene_load_string", "json");
        auto box = std::make_shared<SceneBox>();
        box->scene = sp::Scene::fromString(json, base_dir ? base_dir : "", loadOptionsOf(opts));
        *out = new spc_scene{std::move(box)};
        return SPC_OK;
    });
}

void spc_scene_destroy(spc_scene* scene) { delete scene; }

spc_status spc_scene_set_json(spc_context* ctx, spc_scene* scene, const char* pointer, const char* json_value) {
    return guard(ctx, [&] {
        need(scene, "spc_scene_set_json", "scene");
        need(pointer, "spc_scene_set_json", "pointer");
        need(json_value, "spc_scene_set_json", "json_value");
        if (scene->box->jobs.load() > 0)
            usage("spc_scene_set_json: a render job of this scene has not been waited for (spc_job_wait / spc_job_destroy)");
        scene->box->scene.setValue(pointer, json_value);
        return SPC_OK;
    });
}

spc_status spc_scene_json(spc_context* ctx, const spc_scene* scene, char** out_json) {
    return guard(ctx, [&] {
        need(out_json, "spc_scene_json", "out_json");
        *out_json = nullptr;
        need(scene, "spc_scene_json", "scene");
        *out_json = dupString(scene->box->scene.json(2));
        return SPC_OK;
    });
}

// ---- rendering ------------------------------------------------------------------------------------
spc_status spc_tile_aov(const spc_tile* tile, const char* name, spc_aov_view* out) {
    if (!tile || !name || !out || !tile->internal_) return SPC_USAGE;
    try {
        auto* s = const_cast<TileScratch*>(static_cast<const TileScratch*>(tile->internal_));
        s->views.emplace_back(s->tile->aov(name));
        *out = s->views.back().view;
        return SPC_OK;
    } catch (const Error& e) {
        return statusOf(e.code());
    } catch (const std::bad_alloc&) {
        return SPC_OUT_OF_MEMORY;
    } catch (...) {
        return SPC_INTERNAL;
    }
}

spc_status spc_render(spc_context* ctx, const spc_scene* scene, const spc_render_options* opts, spc_progress_fn cb,
                      void* user, spc_result** out) {
    return guard(ctx, [&] {
        need(out, "spc_render", "out");
        *out = nullptr;
        need(scene, "spc_render", "scene");
        auto c = std::make_shared<Callback>(Callback{cb, user});
        return finish(scene->box->scene.render(renderOptionsOf(opts), tileCallbackOf(c)), out);
    });
}

spc_status spc_render_async(spc_context* ctx, spc_scene* scene, const spc_render_options* opts, spc_progress_fn cb,
                            void* user, spc_job** out) {
    return guard(ctx, [&] {
        need(out, "spc_render_async", "out");
        *out = nullptr;
        need(scene, "spc_render_async", "scene");
        auto job = std::make_unique<spc_job>();
        job->box = scene->box;
        job->cb = std::make_shared<Callback>(Callback{cb, user});
        ++job->box->jobs;
        job->job = job->box->scene.renderAsync(renderOptionsOf(opts), tileCallbackOf(job->cb));
        *out = job.release();
        return SPC_OK;
    });
}

spc_status spc_job_cancel(spc_job* job) {
    if (!job) return SPC_USAGE;
    job->job.cancel();  // noexcept in effect: sets an atomic
    return SPC_OK;
}

spc_status spc_job_done(const spc_job* job, int* out_done) {
    if (!job || !out_done) return SPC_USAGE;
    *out_done = job->job.done() ? 1 : 0;
    return SPC_OK;
}

spc_status spc_job_wait(spc_context* ctx, spc_job* job, spc_result** out) {
    return guard(ctx, [&] {
        need(out, "spc_job_wait", "out");
        *out = nullptr;
        need(job, "spc_job_wait", "job");
        if (!job->counted) usage("spc_job_wait: this job has already been waited for");
        struct Uncount {  // the scene may be edited again once the render has ended, even if wait() throws
            spc_job* j;
            ~Uncount() {
                j->counted = false;
                --j->box->jobs;
            }
        };
        sp::RenderResult r;
        {
            Uncount u{job};
            r = job->job.wait();
        }
        return finish(std::move(r), out);
    });
}

void spc_job_destroy(spc_job* job) {
    try {
        delete job;
    } catch (...) {
    }
}

// ---- results --------------------------------------------------------------------------------------
spc_status spc_result_aov_count(spc_context* ctx, const spc_result* result, int32_t* out_count) {
    return guard(ctx, [&] {
        need(out_count, "spc_result_aov_count", "out_count");
        need(result, "spc_result_aov_count", "result");
        *out_count = int32_t(result->views.size());
        return SPC_OK;
    });
}

spc_status spc_result_aov(spc_context* ctx, const spc_result* result, int32_t index, spc_aov_view* out) {
    return guard(ctx, [&] {
        need(out, "spc_result_aov", "out");
        need(result, "spc_result_aov", "result");
        if (index < 0 || size_t(index) >= result->views.size())
            usage("spc_result_aov: index " + std::to_string(index) + " out of range (" +
                  std::to_string(result->views.size()) + " AOVs)");
        *out = result->views[size_t(index)].view;
        return SPC_OK;
    });
}

spc_status spc_result_aov_named(spc_context* ctx, const spc_result* result, const char* name, spc_aov_view* out) {
    return guard(ctx, [&] {
        need(out, "spc_result_aov_named", "out");
        need(result, "spc_result_aov_named", "result");
        need(name, "spc_result_aov_named", "name");
        for (const ViewStore& v : result->views)
            if (v.name == name) {
                *out = v.view;
                return SPC_OK;
            }
        (void)result->result.aov(name);  // throws the library's "unknown AOV" error, with its suggestion
        usage("spc_result_aov_named: unknown AOV");
    });
}

spc_status spc_result_stats(spc_context* ctx, const spc_result* result, spc_render_stats* out) {
    return guard(ctx, [&] {
        need(out, "spc_result_stats", "out");
        need(result, "spc_result_stats", "result");
        const sp::RenderStats& s = result->result.stats();
        *out = spc_render_stats{};
        out->samples = s.samples, out->invalid_samples = s.invalidSamples, out->seconds = s.seconds;
        out->tiles_done = s.tilesDone, out->tiles_total = s.tilesTotal, out->cancelled = s.cancelled ? 1 : 0;
        out->width = result->result.width(), out->height = result->result.height();
        return SPC_OK;
    });
}

void spc_result_destroy(spc_result* result) { delete result; }

spc_status spc_result_write(spc_context* ctx, const spc_scene* scene, const spc_result* result, const char* exr_path,
                            spc_written* out) {
    return guard(ctx, [&] {
        if (out) *out = spc_written{};
        need(scene, "spc_result_write", "scene");
        need(result, "spc_result_write", "result");
        need(exr_path, "spc_result_write", "exr_path");
        sp::WrittenOutputs w = scene->box->scene.writeOutputs(result->result, exr_path);
        if (out) {
            out->exr = dupString(w.exr);
            try {
                out->png = dupString(w.png);
            } catch (...) {
                std::free(out->exr);
                out->exr = nullptr;
                throw;
            }
            out->partial = w.partial ? 1 : 0;
        }
        return SPC_OK;
    });
}

// ---- GLSL and nodes -------------------------------------------------------------------------------
spc_status spc_glsl_export(spc_context* ctx, const spc_scene* scene, const char* material, uint32_t flags,
                           char** out_source, char** out_manifest_json) {
    return guard(ctx, [&] {
        need(out_source, "spc_glsl_export", "out_source");
        *out_source = nullptr;
        if (out_manifest_json) *out_manifest_json = nullptr;
        need(scene, "spc_glsl_export", "scene");
        sp::GlslModule m = scene->box->scene.compileGlsl(material ? material : "", (flags & SPC_GLSL_INLINE_LITERALS) == 0);
        char* src = dupString(m.source);
        if (out_manifest_json) {
            try {
                *out_manifest_json = dupString(m.resourcesJson);
            } catch (...) {
                std::free(src);
                throw;
            }
        }
        *out_source = src;
        return SPC_OK;
    });
}

spc_status spc_node_catalog_json(spc_context* ctx, char** out_json) {
    return guard(ctx, [&] {
        need(out_json, "spc_node_catalog_json", "out_json");
        *out_json = nullptr;
        *out_json = dupString(sp::nodeCatalogJson(2));
        return SPC_OK;
    });
}

}  // extern "C"
