/* Specula's stable C ABI (docs/capi.md): a thin C11 layer over libspecula's C++ API, for hosts that dlopen
 * libspecula.so (Python, Blender, any C program). Installed as <specula/specula_c.h>. */
#ifndef SPECULA_C_H
#define SPECULA_C_H

#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#define SPC_API __declspec(dllexport)
#elif defined(__GNUC__)
#define SPC_API __attribute__((visibility("default")))
#else
#define SPC_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- version ------------------------------------------------------------------------------------
 * ABI = (major << 16) | minor. The major changes when an existing function, struct or enum value changes
 * meaning or layout; the minor when something is added. A host built against ABI M.m works with a library
 * of the same M and a minor >= m (spc_abi_compatible). */
#define SPC_ABI_VERSION_MAJOR 1
#define SPC_ABI_VERSION_MINOR 2
#define SPC_ABI_VERSION ((uint32_t)((SPC_ABI_VERSION_MAJOR << 16) | SPC_ABI_VERSION_MINOR))

/* The library's ABI version, (major << 16) | minor. */
SPC_API uint32_t spc_abi_version(void);
/* The library's version, e.g. "0.1.0" (static string). */
SPC_API const char* spc_version(void);
/* 1 if a host built against 'host_abi' (pass SPC_ABI_VERSION) can use this library: same major, minor >= host's. */
SPC_API int spc_abi_compatible(uint32_t host_abi);

/* ---- status -------------------------------------------------------------------------------------
 * The values 0..3 and 130 are libspecula's ErrorCode values (and the `specula` CLI's exit codes). */
typedef enum spc_status {
    SPC_OK = 0,
    SPC_BAD_INPUT = 1,     /* invalid scene, graph or value: spc_last_error_pointer names it */
    SPC_USAGE = 2,         /* a bad argument: NULL, bad path, wrong call order */
    SPC_IO = 3,            /* a file or folder cannot be read or written */
    SPC_INTERNAL = 4,      /* an unexpected failure inside the library (a bug) */
    SPC_OUT_OF_MEMORY = 5, /* an allocation failed */
    SPC_CANCELLED = 130    /* the render was cancelled; its (partial) result is still returned */
} spc_status;

/* "ok", "bad_input", "usage", "io", "internal", "out_of_memory", "cancelled" ("unknown" otherwise; static). */
SPC_API const char* spc_status_name(spc_status status);

/* ---- opaque handles ----------------------------------------------------------------------------- */
typedef struct spc_context spc_context; /* error state of one host thread; not thread-safe */
typedef struct spc_scene spc_scene;     /* a loaded scene */
typedef struct spc_result spc_result;   /* the AOV buffers and statistics of one render */
typedef struct spc_job spc_job;         /* a render running on its own thread */

/* ---- context and errors -------------------------------------------------------------------------
 * Every call taking a context clears its error on entry and sets it on failure. The strings below are owned
 * by the context and stay valid until the next call on it. */

/* Creates a context: *out = new context (SPC_USAGE if out is NULL). */
SPC_API spc_status spc_context_create(spc_context** out);
/* Destroys a context (NULL: nothing). Scenes, results and jobs do not depend on it. */
SPC_API void spc_context_destroy(spc_context* ctx);
/* The last failure as the CLI prints it: "<pointer>: <message>[ (did you mean '<suggestion>'?)]"; "" after success. */
SPC_API const char* spc_last_error(const spc_context* ctx);
/* The JSON pointer of the offending value of the last failure ("" when none). */
SPC_API const char* spc_last_error_pointer(const spc_context* ctx);
/* The "did you mean" name of the last failure ("" when none). */
SPC_API const char* spc_last_error_suggestion(const spc_context* ctx);
/* The status of the last call on the context. */
SPC_API spc_status spc_last_status(const spc_context* ctx);

/* Frees a string returned through a char** out-parameter (NULL: nothing). */
SPC_API void spc_string_free(char* s);

/* ---- scenes -------------------------------------------------------------------------------------
 * Load-time overrides (as `specula render --spp/--seed/--resolution/--crop`); they stay in force across
 * spc_scene_set_json. 'size' = sizeof(spc_load_options) lets later minors append fields. */
typedef struct spc_load_options {
    uint32_t size;                               /* sizeof(spc_load_options) */
    int32_t spp;                                 /* 0: the scene's */
    int64_t seed;                                /* < 0: the scene's */
    int32_t width, height;                       /* 0: the scene's */
    int32_t crop_x0, crop_y0, crop_x1, crop_y1;  /* all 0: the whole frame; else [x0,x1)x[y0,y1) frame pixels */
    /* Since ABI 1.1: a host's caps on what the scene may ask for (as `specula render --limit`; docs/reliability.md
     * "Limits"); 0: the built-in maximum, which no cap can exceed (a larger one is SPC_USAGE). Beyond a cap the
     * load fails with SPC_BAD_INPUT at the JSON pointer of what exceeds it. A host built against 1.0 passes the
     * smaller size and gets the built-in maxima. */
    int64_t max_pixels, max_triangles;
    int32_t max_spp, max_texture_side, max_graph_nodes, max_json_depth;
    /* Since ABI 1.2: has_frame != 0 renders animation frame 'frame' (the scene's "animation" block, as `specula
     * render --frame`; docs/scene-format.md); 0: the scene's frame_start. A frame outside the range: SPC_BAD_INPUT. */
    int32_t has_frame, frame;
} spc_load_options;
#define SPC_LOAD_OPTIONS_INIT {(uint32_t)sizeof(spc_load_options), 0, -1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}

/* Loads a scene file (relative paths inside resolve against its folder); opts may be NULL. */
SPC_API spc_status spc_scene_load_file(spc_context* ctx, const char* path, const spc_load_options* opts, spc_scene** out);
/* Loads a scene from JSON text; base_dir (NULL or "": the current folder) resolves relative paths; opts may be NULL. */
SPC_API spc_status spc_scene_load_string(spc_context* ctx, const char* json, const char* base_dir,
                                         const spc_load_options* opts, spc_scene** out);
/* Destroys a scene (NULL: nothing). Safe while jobs render it: they keep it alive until they are destroyed. */
SPC_API void spc_scene_destroy(spc_scene* scene);
/* Sets one value by JSON pointer, value as JSON text, e.g. ("/render/spp", "8"). A material literal
 * (/materials/<m>/nodes/<n>/inputs/<i>) recompiles that material only; any other value re-loads the whole
 * scene (the cost of a load). On failure the scene is unchanged. SPC_USAGE while a job renders the scene. */
SPC_API spc_status spc_scene_set_json(spc_context* ctx, spc_scene* scene, const char* pointer, const char* json_value);
/* The scene document with every edit applied, pretty-printed (free with spc_string_free). */
SPC_API spc_status spc_scene_json(spc_context* ctx, const spc_scene* scene, char** out_json);

/* ---- rendering ---------------------------------------------------------------------------------- */
typedef struct spc_render_options {
    uint32_t size;   /* sizeof(spc_render_options) */
    int32_t threads; /* 0: all cores; the image does not depend on it */
} spc_render_options;
#define SPC_RENDER_OPTIONS_INIT {(uint32_t)sizeof(spc_render_options), 0}

/* One AOV buffer: 'channels' floats per pixel, rows top to bottom, scene-linear. Pixel (x, y) of the buffer
 * is pixels + (y * width + x) * channels. Owned by the result (or, in a callback, valid during the call). */
typedef struct spc_aov_view {
    const char* name;                 /* beauty, diffuse, specular, albedo, normal, uv, depth */
    int32_t channels;                 /* 1..4 */
    const char* const* channel_names; /* e.g. R,G,B / X,Y,Z / U,V / Z */
    int32_t width, height;
    const float* pixels;
} spc_aov_view;

/* A finished tile, passed to the progress callback; valid only during the call. */
typedef struct spc_tile {
    int32_t x0, y0, x1, y1;         /* the tile, frame pixels, x1/y1 exclusive */
    int32_t origin_x, origin_y;     /* top-left frame pixel of the buffers (the crop window) */
    int32_t tiles_done, tiles_total;
    double elapsed_seconds, samples_per_second, eta_seconds;
    const float* beauty;            /* beauty RGB of frame pixel (x0, y0); final for this tile */
    ptrdiff_t beauty_row_stride;    /* floats between rows: pixel (x, y) = beauty + (y-y0)*stride + (x-x0)*3 */
    const void* internal_;          /* for spc_tile_aov */
} spc_tile;

/* Progress callback: runs on a worker thread, once per finished tile, serially (never concurrently with
 * itself); return 0 to cancel the render. Call only spc_tile_aov and spc_job_cancel from inside it. */
typedef int (*spc_progress_fn)(const spc_tile* tile, void* user);

/* Any AOV of the image being rendered, inside the callback (read only the tile's own pixels): SPC_BAD_INPUT
 * for an unknown name, SPC_USAGE for NULL (no context: no message). Valid during the call. */
SPC_API spc_status spc_tile_aov(const spc_tile* tile, const char* name, spc_aov_view* out);

/* Renders synchronously; opts and cb may be NULL. SPC_CANCELLED (the callback returned 0) still sets *out
 * to the partial result (stats.cancelled = 1), which the host destroys. */
SPC_API spc_status spc_render(spc_context* ctx, const spc_scene* scene, const spc_render_options* opts,
                              spc_progress_fn cb, void* user, spc_result** out);
/* Starts a render on its own thread: *out = the job. The scene must not be edited until the job is waited for. */
SPC_API spc_status spc_render_async(spc_context* ctx, spc_scene* scene, const spc_render_options* opts,
                                    spc_progress_fn cb, void* user, spc_job** out);
/* Asks the job to stop (workers stop within 32 samples of their current pixel); from any thread, also from the callback. */
SPC_API spc_status spc_job_cancel(spc_job* job);
/* *out_done = 1 once the render has finished (waiting will not block). */
SPC_API spc_status spc_job_done(const spc_job* job, int* out_done);
/* Blocks until the render ends; once per job. Status and *out as spc_render. */
SPC_API spc_status spc_job_wait(spc_context* ctx, spc_job* job, spc_result** out);
/* Destroys a job (NULL: nothing); a running job is cancelled and joined first. */
SPC_API void spc_job_destroy(spc_job* job);

/* ---- results ------------------------------------------------------------------------------------ */
typedef struct spc_render_stats {
    uint64_t samples, invalid_samples; /* camera samples taken; NaN/Inf samples dropped */
    double seconds;
    int32_t tiles_done, tiles_total;
    int32_t cancelled;                 /* 1 if the render was cancelled */
    int32_t width, height;             /* of the buffers (the crop window) */
} spc_render_stats;

/* The number of AOVs of a result. */
SPC_API spc_status spc_result_aov_count(spc_context* ctx, const spc_result* result, int32_t* out_count);
/* AOV number 'index' (0 .. count-1; 0 is beauty); the view lives as long as the result. */
SPC_API spc_status spc_result_aov(spc_context* ctx, const spc_result* result, int32_t index, spc_aov_view* out);
/* The AOV called 'name'; SPC_BAD_INPUT (with a suggestion) for an unknown name. */
SPC_API spc_status spc_result_aov_named(spc_context* ctx, const spc_result* result, const char* name, spc_aov_view* out);
/* The render's statistics. */
SPC_API spc_status spc_result_stats(spc_context* ctx, const spc_result* result, spc_render_stats* out);
/* Destroys a result (NULL: nothing). */
SPC_API void spc_result_destroy(spc_result* result);

/* What spc_result_write wrote; free both strings with spc_string_free. */
typedef struct spc_written {
    char* exr;       /* OUT.exr, or OUT.partial.exr for a cancelled render; "" when OUT.png was asked for */
    char* png;       /* OUT.png beside it; "" for a partial image */
    int32_t partial; /* 1 for a cancelled render */
} spc_written;

/* Writes the result through libspecula's output policy (docs/api.md "Writing outputs"): OUT.exr (every AOV)
 * + OUT.png, atomically, or OUT.png alone; a cancelled result only OUT.partial.exr, never over OUT.exr. out may be
 * NULL. */
SPC_API spc_status spc_result_write(spc_context* ctx, const spc_scene* scene, const spc_result* result,
                                    const char* exr_path, spc_written* out);

/* ---- GLSL and nodes ----------------------------------------------------------------------------- */
#define SPC_GLSL_INLINE_LITERALS 1u /* inline the literals instead of making them uniforms */

/* The GLSL 4.50 module of a material (NULL or "": the only one) and its resource manifest JSON
 * (docs/graph-format.md "Resources"); free both with spc_string_free. */
SPC_API spc_status spc_glsl_export(spc_context* ctx, const spc_scene* scene, const char* material, uint32_t flags,
                                   char** out_source, char** out_manifest_json);
/* The node catalogue {"nodes":[...]} as `specula nodes --json` (free with spc_string_free). */
SPC_API spc_status spc_node_catalog_json(spc_context* ctx, char** out_json);

#ifdef __cplusplus
}
#endif

#endif /* SPECULA_C_H */
