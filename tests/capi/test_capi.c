/* ctest capi: the C ABI (plugin/capi/specula.h) as a host sees it. Pure C11, not linked with libspecula: it
 * dlopens the library given as argv[1], dlsyms every spc_* function and exercises each one. */
#define _POSIX_C_SOURCE 200809L

#include <specula/specula_c.h>

#include <dlfcn.h>
#include <stddef.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* Every exported function; the struct below holds one pointer of the declared type per name. */
#define SPC_FUNCTIONS(X)                                                                                     \
    X(spc_abi_version) X(spc_version) X(spc_abi_compatible) X(spc_status_name) X(spc_context_create)         \
    X(spc_context_destroy) X(spc_last_error) X(spc_last_error_pointer) X(spc_last_error_suggestion)           \
    X(spc_last_status) X(spc_string_free) X(spc_scene_load_file) X(spc_scene_load_string) X(spc_scene_destroy) \
    X(spc_scene_set_json) X(spc_scene_json) X(spc_tile_aov) X(spc_render) X(spc_render_async) X(spc_job_cancel) \
    X(spc_job_done) X(spc_job_wait) X(spc_job_destroy) X(spc_result_aov_count) X(spc_result_aov)             \
    X(spc_result_aov_named) X(spc_result_stats) X(spc_result_destroy) X(spc_result_write) X(spc_glsl_export)  \
    X(spc_node_catalog_json)

#define DECLARE(name) __typeof__(&name) name;
static struct {
    SPC_FUNCTIONS(DECLARE)
} A;

static int failures = 0;
#define CHECK(cond)                                                                  \
    do {                                                                             \
        if (!(cond)) {                                                               \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
            ++failures;                                                              \
        }                                                                            \
    } while (0)
/* A call that must succeed; prints the context's message otherwise. */
#define OK(ctx, call)                                                                                           \
    do {                                                                                                        \
        spc_status st_ = (call);                                                                                \
        if (st_ != SPC_OK) {                                                                                    \
            fprintf(stderr, "%s:%d: %s -> %s: %s\n", __FILE__, __LINE__, #call, A.spc_status_name(st_),        \
                    A.spc_last_error(ctx));                                                                     \
            ++failures;                                                                                         \
        }                                                                                                       \
    } while (0)

/* 32x24 in 16-pixel tiles (2x2 tiles, one of them 16x8): a GGX sphere on a diffuse floor, one point light. */
static const char* kScene =
    "{\"version\": 1,"
    " \"render\": {\"width\": 32, \"height\": 24, \"spp\": 4, \"seed\": 3, \"tile\": 16},"
    " \"camera\": {\"position\": [0, -4, 1], \"look_at\": [0, 0, 0.6], \"fov\": 40},"
    " \"materials\": {"
    "  \"gold\": {\"nodes\": {\"spec\": {\"type\": \"bsdf.ggx\", \"inputs\": {\"roughness\": 0.3, \"fresnel\": \"schlick\","
    "            \"f0\": [1.0, 0.78, 0.34]}}}, \"output\": \"@spec.bsdf\"},"
    "  \"floor\": {\"nodes\": {\"base\": {\"type\": \"bsdf.diffuse\", \"inputs\": {\"color\": [0.5, 0.5, 0.5]}}},"
    "            \"output\": \"@base.bsdf\"}},"
    " \"shapes\": [{\"type\": \"sphere\", \"radius\": 0.6, \"transform\": {\"translate\": [0, 0, 0.6]}, \"material\": \"gold\"},"
    "            {\"type\": \"quad\", \"size\": [8, 8], \"material\": \"floor\"}],"
    " \"lights\": [{\"type\": \"point\", \"position\": [1.5, -2, 3], \"power\": 400}]}";

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int fileExists(const char* path) {
    struct stat s;
    return stat(path, &s) == 0 && s.st_size > 0;
}

/* ---- progress callbacks ---------------------------------------------------------------------------- */
typedef struct {
    int tiles, badRect, badPixel, badAov, lastTotal, pixelsArea;
    int cancelAfter; /* > 0: return 0 once this many tiles were seen */
} Progress;

static int onTile(const spc_tile* t, void* user) {
    Progress* p = (Progress*)user;
    ++p->tiles;
    p->lastTotal = t->tiles_total;
    if (!(t->x0 >= 0 && t->y0 >= 0 && t->x0 < t->x1 && t->y0 < t->y1 && t->x1 <= 32 && t->y1 <= 24 &&
          t->x1 - t->x0 <= 16 && t->y1 - t->y0 <= 16 && t->origin_x == 0 && t->origin_y == 0 &&
          t->tiles_done >= 1 && t->tiles_done <= t->tiles_total && t->elapsed_seconds >= 0))
        ++p->badRect;
    p->pixelsArea += (t->x1 - t->x0) * (t->y1 - t->y0);
    { /* the tile's last pixel through the plain fields: finite, non-negative */
        const float* c = t->beauty + (ptrdiff_t)(t->y1 - 1 - t->y0) * t->beauty_row_stride + (ptrdiff_t)(t->x1 - 1 - t->x0) * 3;
        int i;
        for (i = 0; i < 3; ++i)
            if (!isfinite(c[i]) || c[i] < 0) ++p->badPixel;
        if (t->beauty_row_stride != 32 * 3) ++p->badPixel;
    }
    { /* the same pixel through spc_tile_aov, and another AOV */
        spc_aov_view v, n;
        if (A.spc_tile_aov(t, "beauty", &v) != SPC_OK || v.pixels == NULL || v.channels != 3 || v.width != 32 ||
            v.pixels + ((size_t)t->y0 * 32 + (size_t)t->x0) * 3 != t->beauty)
            ++p->badAov;
        if (A.spc_tile_aov(t, "normal", &n) != SPC_OK || n.channels != 3 || strcmp(n.channel_names[0], "X") != 0) ++p->badAov;
        if (A.spc_tile_aov(t, "no-such-aov", &n) != SPC_BAD_INPUT) ++p->badAov;
        if (A.spc_tile_aov(NULL, "beauty", &n) != SPC_USAGE) ++p->badAov;
    }
    return p->cancelAfter > 0 && p->tiles >= p->cancelAfter ? 0 : 1;
}

/* Async: the callback signals the first tile; the canceller thread waits for it, then cancels the job. */
typedef struct {
    pthread_mutex_t m;
    pthread_cond_t cv;
    int tiles;
    spc_job* job;
    spc_status cancelStatus;
} AsyncState;

static int onTileAsync(const spc_tile* t, void* user) {
    AsyncState* s = (AsyncState*)user;
    (void)t;
    pthread_mutex_lock(&s->m);
    ++s->tiles;
    pthread_cond_signal(&s->cv);
    pthread_mutex_unlock(&s->m);
    return 1;
}

static void* canceller(void* arg) {
    AsyncState* s = (AsyncState*)arg;
    pthread_mutex_lock(&s->m);
    while (s->tiles == 0) pthread_cond_wait(&s->cv, &s->m);
    pthread_mutex_unlock(&s->m);
    s->cancelStatus = A.spc_job_cancel(s->job);
    return NULL;
}

/* ---- helpers ---------------------------------------------------------------------------------------- */
static void checkAov(spc_context* ctx, const spc_result* r, const char* name) {
    spc_aov_view v;
    int32_t i, n;
    double sum = 0;
    int bad = 0;
    OK(ctx, A.spc_result_aov_named(ctx, r, name, &v));
    CHECK(strcmp(v.name, name) == 0);
    CHECK(v.channels == 3 && strcmp(v.channel_names[0], "R") == 0 && strcmp(v.channel_names[2], "B") == 0);
    CHECK(v.width == 32 && v.height == 24 && v.pixels != NULL);
    n = v.width * v.height * v.channels;
    for (i = 0; i < n; ++i) {
        if (!isfinite(v.pixels[i]) || v.pixels[i] < 0) ++bad;
        sum += v.pixels[i];
    }
    CHECK(bad == 0);
    CHECK(sum > 0);
    printf("  aov %s: %dx%d, mean %.4f\n", name, v.width, v.height, sum / n);
}

static int sameBeauty(spc_context* ctx, const spc_result* a, const spc_result* b) {
    spc_aov_view va, vb;
    OK(ctx, A.spc_result_aov(ctx, a, 0, &va));
    OK(ctx, A.spc_result_aov(ctx, b, 0, &vb));
    return va.width == vb.width && va.height == vb.height &&
           memcmp(va.pixels, vb.pixels, sizeof(float) * (size_t)va.width * (size_t)va.height * 3) == 0;
}

/* A call that must fail with 'want', leave a message (containing 'pointer' if given) and a usable context. */
static void expectError(spc_context* ctx, spc_status got, spc_status want, const char* pointer, const char* what) {
    const char* msg = A.spc_last_error(ctx);
    printf("  %s -> %s: %s\n", what, A.spc_status_name(got), msg);
    CHECK(got == want);
    CHECK(A.spc_last_status(ctx) == want);
    CHECK(msg != NULL && msg[0] != '\0');
    if (pointer) {
        CHECK(strstr(msg, pointer) != NULL);
        CHECK(strcmp(A.spc_last_error_pointer(ctx), pointer) == 0);
    }
}

int main(int argc, char** argv) {
    void* lib;
    spc_context* ctx = NULL;
    spc_scene* scene = NULL;
    spc_result *r1 = NULL, *r2 = NULL;
    double t0 = now();
    char dir[] = "/tmp/specula_capi_XXXXXX";
    char path[512];

    if (argc < 2) {
        fprintf(stderr, "usage: test_capi LIBSPECULA.so\n");
        return 2;
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen %s: %s\n", argv[1], dlerror());
        return 1;
    }
#define LOAD(name)                                                        \
    do {                                                                  \
        void* p_ = dlsym(lib, #name);                                     \
        if (!p_) {                                                        \
            fprintf(stderr, "dlsym %s: %s\n", #name, dlerror());          \
            return 1;                                                     \
        }                                                                 \
        memcpy(&A.name, &p_, sizeof p_); /* object -> function pointer */ \
    } while (0);
    SPC_FUNCTIONS(LOAD)
    printf("dlopen + dlsym of every function: ok\n");

    /* ---- version and ABI ---- */
    CHECK(A.spc_abi_version() == SPC_ABI_VERSION);
    CHECK(A.spc_abi_compatible(SPC_ABI_VERSION) == 1);
    CHECK(A.spc_abi_compatible(SPC_ABI_VERSION + (1u << 16)) == 0);           /* another major */
    CHECK(A.spc_abi_compatible(SPC_ABI_VERSION + 1u) == 0);                   /* a newer minor than the library */
    CHECK(A.spc_version() != NULL && strchr(A.spc_version(), '.') != NULL);
    CHECK(strcmp(A.spc_status_name(SPC_CANCELLED), "cancelled") == 0 && strcmp(A.spc_status_name(SPC_OK), "ok") == 0);
    printf("version %s, abi 0x%08x\n", A.spc_version(), (unsigned)A.spc_abi_version());

    /* ---- NULL arguments: SPC_USAGE, no crash ---- */
    CHECK(A.spc_context_create(NULL) == SPC_USAGE);
    OK(ctx, A.spc_context_create(&ctx));
    CHECK(A.spc_scene_load_string(NULL, kScene, NULL, NULL, &scene) == SPC_USAGE);
    CHECK(A.spc_scene_load_string(ctx, NULL, NULL, NULL, &scene) == SPC_USAGE && scene == NULL);
    CHECK(A.spc_last_error(ctx)[0] != '\0');
    CHECK(A.spc_scene_load_string(ctx, kScene, NULL, NULL, NULL) == SPC_USAGE);
    CHECK(A.spc_scene_load_file(ctx, NULL, NULL, &scene) == SPC_USAGE);
    CHECK(A.spc_render(ctx, NULL, NULL, NULL, NULL, &r1) == SPC_USAGE && r1 == NULL);
    CHECK(A.spc_render_async(ctx, NULL, NULL, NULL, NULL, NULL) == SPC_USAGE);
    CHECK(A.spc_job_cancel(NULL) == SPC_USAGE);
    CHECK(A.spc_job_done(NULL, NULL) == SPC_USAGE);
    CHECK(A.spc_job_wait(ctx, NULL, &r1) == SPC_USAGE);
    CHECK(A.spc_result_aov_count(ctx, NULL, NULL) == SPC_USAGE);
    CHECK(A.spc_result_stats(ctx, NULL, NULL) == SPC_USAGE);
    CHECK(A.spc_result_write(ctx, NULL, NULL, NULL, NULL) == SPC_USAGE);
    CHECK(A.spc_glsl_export(ctx, NULL, NULL, 0, NULL, NULL) == SPC_USAGE);
    CHECK(A.spc_node_catalog_json(ctx, NULL) == SPC_USAGE);
    CHECK(A.spc_scene_set_json(ctx, NULL, "/render/spp", "8") == SPC_USAGE);
    CHECK(A.spc_scene_json(ctx, NULL, NULL) == SPC_USAGE);
    CHECK(A.spc_last_status(NULL) == SPC_USAGE && A.spc_last_error(NULL)[0] == '\0');
    CHECK(A.spc_last_error_pointer(NULL)[0] == '\0' && A.spc_last_error_suggestion(NULL)[0] == '\0');
    A.spc_scene_destroy(NULL), A.spc_result_destroy(NULL), A.spc_job_destroy(NULL), A.spc_string_free(NULL);
    A.spc_context_destroy(NULL);
    printf("NULL arguments: usage, no crash\n");

    /* ---- node catalogue ---- */
    {
        char* json = NULL;
        OK(ctx, A.spc_node_catalog_json(ctx, &json));
        CHECK(json != NULL && strstr(json, "\"nodes\"") != NULL && strstr(json, "\"bsdf.glint\"") != NULL);
        CHECK(A.spc_last_error(ctx)[0] == '\0' && A.spc_last_status(ctx) == SPC_OK);
        printf("node catalogue: %zu bytes, has bsdf.glint\n", json ? strlen(json) : 0);
        A.spc_string_free(json);
    }

    /* ---- load, render with progress, AOVs ---- */
    OK(ctx, A.spc_scene_load_string(ctx, kScene, NULL, NULL, &scene));
    if (!scene) return 1;
    {
        Progress p;
        spc_render_options ro = SPC_RENDER_OPTIONS_INIT;
        spc_render_stats s;
        int32_t count = 0, i;
        memset(&p, 0, sizeof p);
        OK(ctx, A.spc_render(ctx, scene, &ro, onTile, &p, &r1));
        CHECK(p.tiles == 4 && p.lastTotal == 4 && p.pixelsArea == 32 * 24);
        CHECK(p.badRect == 0 && p.badPixel == 0 && p.badAov == 0);
        OK(ctx, A.spc_result_stats(ctx, r1, &s));
        CHECK(s.samples == 32 * 24 * 4 && s.tiles_done == 4 && s.tiles_total == 4 && s.cancelled == 0);
        CHECK(s.width == 32 && s.height == 24 && s.seconds >= 0);
        printf("render: %d tiles seen by the callback, %llu samples, %.3f s\n", p.tiles, (unsigned long long)s.samples,
               s.seconds);
        OK(ctx, A.spc_result_aov_count(ctx, r1, &count));
        CHECK(count == 7);
        for (i = 0; i < count; ++i) {
            spc_aov_view v;
            OK(ctx, A.spc_result_aov(ctx, r1, i, &v));
            CHECK(v.name != NULL && v.channels >= 1 && v.channels <= 4 && v.width == 32 && v.height == 24);
        }
        checkAov(ctx, r1, "beauty");
        checkAov(ctx, r1, "specular");
        {
            spc_aov_view v;
            expectError(ctx, A.spc_result_aov(ctx, r1, 7, &v), SPC_USAGE, NULL, "aov index 7");
            expectError(ctx, A.spc_result_aov_named(ctx, r1, "speculr", &v), SPC_BAD_INPUT, NULL, "aov 'speculr'");
            CHECK(strcmp(A.spc_last_error_suggestion(ctx), "specular") == 0);
        }
    }

    /* ---- determinism: the same render twice (and on one thread) is bit-identical ---- */
    {
        spc_render_options one = SPC_RENDER_OPTIONS_INIT;
        one.threads = 1;
        OK(ctx, A.spc_render(ctx, scene, &one, NULL, NULL, &r2));
        CHECK(r2 && sameBeauty(ctx, r1, r2));
        printf("render twice: bit-identical\n");
        A.spc_result_destroy(r2);
        r2 = NULL;
    }

    /* ---- option ranges: the CLI's table (core/api/specula.h option_rules), e.g. --threads 0..1024 (issue 35) ---- */
    {
        spc_render_options bad = SPC_RENDER_OPTIONS_INIT;
        bad.threads = -3;
        expectError(ctx, A.spc_render(ctx, scene, &bad, NULL, NULL, &r2), SPC_USAGE, NULL, "--threads -3 is outside 0..1024");
        CHECK(r2 == NULL);
        bad.threads = 1025;
        expectError(ctx, A.spc_render(ctx, scene, &bad, NULL, NULL, &r2), SPC_USAGE, NULL, "--threads 1025 is outside");
        CHECK(r2 == NULL);
        printf("threads -3 and 1025: SPC_USAGE, as the CLI\n");
    }

    /* ---- overrides by JSON pointer ---- */
    {
        spc_render_stats s;
        char* doc = NULL;
        OK(ctx, A.spc_scene_set_json(ctx, scene, "/render/spp", "8"));
        OK(ctx, A.spc_render(ctx, scene, NULL, NULL, NULL, &r2));
        OK(ctx, A.spc_result_stats(ctx, r2, &s));
        CHECK(s.samples == 32 * 24 * 8);
        printf("set /render/spp 8: %llu samples\n", (unsigned long long)s.samples);
        A.spc_result_destroy(r2);
        /* A material literal (recompiles the material only) changes the picture. */
        OK(ctx, A.spc_scene_set_json(ctx, scene, "/materials/gold/nodes/spec/inputs/roughness", "0.7"));
        OK(ctx, A.spc_scene_set_json(ctx, scene, "/render/spp", "4"));
        OK(ctx, A.spc_render(ctx, scene, NULL, NULL, NULL, &r2));
        CHECK(r2 && !sameBeauty(ctx, r1, r2));
        A.spc_result_destroy(r2);
        r2 = NULL;
        OK(ctx, A.spc_scene_json(ctx, scene, &doc));
        CHECK(doc && strstr(doc, "0.7") != NULL);
        A.spc_string_free(doc);
        /* Load options: 16x12, 2 spp. */
        {
            spc_load_options lo = SPC_LOAD_OPTIONS_INIT;
            spc_scene* small = NULL;
            lo.width = 16, lo.height = 12, lo.spp = 2;
            OK(ctx, A.spc_scene_load_string(ctx, kScene, "", &lo, &small));
            OK(ctx, A.spc_render(ctx, small, NULL, NULL, NULL, &r2));
            OK(ctx, A.spc_result_stats(ctx, r2, &s));
            CHECK(s.width == 16 && s.height == 12 && s.samples == 16 * 12 * 2);
            A.spc_result_destroy(r2);
            r2 = NULL;
            A.spc_scene_destroy(small);
            lo.size = 4; /* a struct from an unknown, older header */
            CHECK(A.spc_scene_load_string(ctx, kScene, "", &lo, &small) == SPC_USAGE && small == NULL);
            lo = (spc_load_options)SPC_LOAD_OPTIONS_INIT;
            lo.crop_x0 = 8, lo.crop_y0 = 4, lo.crop_x1 = 24, lo.crop_y1 = 20;
            OK(ctx, A.spc_scene_load_string(ctx, kScene, "", &lo, &small));
            OK(ctx, A.spc_render(ctx, small, NULL, NULL, NULL, &r2));
            OK(ctx, A.spc_result_stats(ctx, r2, &s));
            CHECK(s.width == 16 && s.height == 16);
            A.spc_result_destroy(r2);
            r2 = NULL;
            A.spc_scene_destroy(small);
            /* ABI 1.1 limits: a cap below the scene's 4 spp is bad input at its pointer; a cap above the built-in
             * maximum is a usage error; a 1.0-sized struct (no limits) still loads. */
            lo = (spc_load_options)SPC_LOAD_OPTIONS_INIT;
            lo.max_spp = 2;
            expectError(ctx, A.spc_scene_load_string(ctx, kScene, "", &lo, &small), SPC_BAD_INPUT, "/render/spp",
                        "max_spp 2 below the scene's 4 spp");
            CHECK(small == NULL);
            lo.max_spp = 0;
            lo.max_json_depth = 1000;
            expectError(ctx, A.spc_scene_load_string(ctx, kScene, "", &lo, &small), SPC_USAGE, NULL,
                        "max_json_depth 1000 above the built-in 64");
            CHECK(strstr(A.spc_last_error(ctx), "json_depth") != NULL);
            lo = (spc_load_options)SPC_LOAD_OPTIONS_INIT;
            lo.size = (uint32_t)offsetof(spc_load_options, max_pixels);
            lo.max_spp = 2; /* beyond a 1.0 host's struct: not read */
            OK(ctx, A.spc_scene_load_string(ctx, kScene, "", &lo, &small));
            A.spc_scene_destroy(small);
            small = NULL;
            /* ABI 1.2 frame: a frame of a scene without an animation block is bad input; a 1.1-sized struct (no frame)
             * still loads. */
            lo = (spc_load_options)SPC_LOAD_OPTIONS_INIT;
            lo.has_frame = 1, lo.frame = 5;
            expectError(ctx, A.spc_scene_load_string(ctx, kScene, "", &lo, &small), SPC_BAD_INPUT, "--frame",
                        "frame 5 of a scene without an animation");
            CHECK(small == NULL);
            lo.size = (uint32_t)offsetof(spc_load_options, has_frame);
            OK(ctx, A.spc_scene_load_string(ctx, kScene, "", &lo, &small));
            A.spc_scene_destroy(small);
            small = NULL;
            printf("load options: resolution, spp, crop, limits and frame applied\n");
        }
    }

    /* ---- bad input: non-OK status, message with the JSON pointer, context still usable ---- */
    {
        spc_scene* bad = NULL;
        expectError(ctx, A.spc_scene_load_string(ctx, "{\"version\": 1, \"render\": {", NULL, NULL, &bad), SPC_BAD_INPUT,
                    NULL, "malformed JSON");
        CHECK(bad == NULL);
        expectError(ctx,
                    A.spc_scene_load_string(ctx, "{\"version\": 1, \"render\": {\"sppp\": 4}, \"shapes\": [], \"lights\": []}",
                                            NULL, NULL, &bad),
                    SPC_BAD_INPUT, "/render/sppp", "unknown key");
        CHECK(strcmp(A.spc_last_error_suggestion(ctx), "spp") == 0);
        expectError(ctx, A.spc_scene_load_file(ctx, "/nonexistent/scene.json", NULL, &bad), SPC_IO, NULL, "missing file");
        expectError(ctx, A.spc_scene_set_json(ctx, scene, "/render/nosuch/x", "1"), SPC_BAD_INPUT, "/render/nosuch",
                    "set_json on a missing parent");
        expectError(ctx, A.spc_scene_set_json(ctx, scene, "/render/sppp", "8"), SPC_BAD_INPUT, "/render/sppp",
                    "set_json of an unknown key");
        expectError(ctx, A.spc_scene_set_json(ctx, scene, "/render/spp", "-3"), SPC_BAD_INPUT, "/render/spp",
                    "set_json out of range");
        expectError(ctx, A.spc_scene_set_json(ctx, scene, "/render/spp", "{oops"), SPC_BAD_INPUT, "/render/spp",
                    "set_json of malformed JSON");
        expectError(ctx, A.spc_scene_set_json(ctx, scene, "/materials/glod/nodes/spec/inputs/roughness", "0.2"),
                    SPC_BAD_INPUT, "/materials/glod", "set_json of an unknown material");
        CHECK(strcmp(A.spc_last_error_suggestion(ctx), "gold") == 0);
        expectError(ctx, A.spc_scene_set_json(ctx, scene, "render/spp", "8"), SPC_BAD_INPUT, NULL, "set_json of a non-pointer");
        /* The scene is unchanged and the context usable. */
        OK(ctx, A.spc_render(ctx, scene, NULL, NULL, NULL, &r2));
        CHECK(A.spc_last_error(ctx)[0] == '\0' && A.spc_last_error_pointer(ctx)[0] == '\0');
        {
            spc_render_stats s;
            OK(ctx, A.spc_result_stats(ctx, r2, &s));
            CHECK(s.samples == 32 * 24 * 4);
        }
        A.spc_result_destroy(r2);
        r2 = NULL;
        printf("bad input: statuses and messages as expected, context usable afterwards\n");
    }

    /* ---- cancel from the callback ---- */
    {
        Progress p;
        spc_render_options one = SPC_RENDER_OPTIONS_INIT;
        spc_render_stats s;
        memset(&p, 0, sizeof p);
        p.cancelAfter = 1;
        one.threads = 1;
        CHECK(A.spc_render(ctx, scene, &one, onTile, &p, &r2) == SPC_CANCELLED);
        CHECK(r2 != NULL);
        OK(ctx, A.spc_result_stats(ctx, r2, &s));
        CHECK(s.cancelled == 1 && s.tiles_done < s.tiles_total && p.tiles == 1);
        printf("cancel from the callback: cancelled, %d/%d tiles\n", s.tiles_done, s.tiles_total);
    }

    /* ---- outputs: complete -> .exr + .png; cancelled -> only .partial.exr ---- */
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    {
        spc_written w;
        char png[512], partial[512], cexr[512], cpng[512], cpartial[512];
        snprintf(path, sizeof path, "%s/full.exr", dir);
        snprintf(png, sizeof png, "%s/full.png", dir);
        snprintf(partial, sizeof partial, "%s/full.partial.exr", dir);
        OK(ctx, A.spc_result_write(ctx, scene, r1, path, &w));
        CHECK(w.partial == 0 && w.exr && strcmp(w.exr, path) == 0 && w.png && strcmp(w.png, png) == 0);
        CHECK(fileExists(path) && fileExists(png) && !fileExists(partial));
        A.spc_string_free(w.exr), A.spc_string_free(w.png);

        snprintf(cexr, sizeof cexr, "%s/cancelled.exr", dir);
        snprintf(cpng, sizeof cpng, "%s/cancelled.png", dir);
        snprintf(cpartial, sizeof cpartial, "%s/cancelled.partial.exr", dir);
        OK(ctx, A.spc_result_write(ctx, scene, r2, cexr, &w));
        CHECK(w.partial == 1 && w.exr && strcmp(w.exr, cpartial) == 0 && w.png && w.png[0] == '\0');
        CHECK(fileExists(cpartial) && !fileExists(cexr) && !fileExists(cpng));
        A.spc_string_free(w.exr), A.spc_string_free(w.png);
        OK(ctx, A.spc_result_write(ctx, scene, r1, path, NULL)); /* out is optional */

        snprintf(cexr, sizeof cexr, "%s/out.tif", dir);
        expectError(ctx, A.spc_result_write(ctx, scene, r1, cexr, &w), SPC_USAGE, NULL, "write to .tif");
        CHECK(w.exr == NULL && w.png == NULL);
        /* OUT.png: the viewed PNG alone, exr "" */
        snprintf(cexr, sizeof cexr, "%s/only.png", dir);
        OK(ctx, A.spc_result_write(ctx, scene, r1, cexr, &w));
        CHECK(w.partial == 0 && w.exr && w.exr[0] == '\0' && w.png && strcmp(w.png, cexr) == 0 && fileExists(cexr));
        A.spc_string_free(w.exr), A.spc_string_free(w.png);
        remove(cexr);
        expectError(ctx, A.spc_result_write(ctx, scene, r1, "/nonexistent/dir/out.exr", NULL), SPC_IO, NULL,
                    "write to a missing folder");
        printf("outputs: full.exr + full.png; cancelled.partial.exr only\n");
        remove(path), remove(png), remove(cpartial);
        A.spc_result_destroy(r2);
        r2 = NULL;
    }

    /* ---- a scene file ---- */
    {
        spc_scene* fromFile = NULL;
        FILE* f;
        snprintf(path, sizeof path, "%s/scene.json", dir);
        f = fopen(path, "w");
        CHECK(f != NULL);
        if (f) {
            fputs(kScene, f);
            fclose(f);
        }
        OK(ctx, A.spc_scene_load_file(ctx, path, NULL, &fromFile));
        OK(ctx, A.spc_render(ctx, fromFile, NULL, NULL, NULL, &r2));
        CHECK(r2 && sameBeauty(ctx, r1, r2));
        /* A scene from a file: outputs beside it. */
        snprintf(path, sizeof path, "%s/scene.exr", dir);
        OK(ctx, A.spc_result_write(ctx, fromFile, r2, path, NULL));
        A.spc_result_destroy(r2);
        r2 = NULL;
        A.spc_scene_destroy(fromFile);
        remove(path);
        snprintf(path, sizeof path, "%s/scene.png", dir);
        remove(path);
        snprintf(path, sizeof path, "%s/scene.json", dir);
        remove(path);
        rmdir(dir);
        printf("scene file: loads, renders the same image\n");
    }

    /* ---- async: wait, then cancel from another thread ---- */
    {
        spc_job* job = NULL;
        int done = 0;
        spc_render_stats s;
        spc_result* sync = NULL;
        OK(ctx, A.spc_render(ctx, scene, NULL, NULL, NULL, &sync));
        OK(ctx, A.spc_render_async(ctx, scene, NULL, NULL, NULL, &job));
        expectError(ctx, A.spc_scene_set_json(ctx, scene, "/render/spp", "2"), SPC_USAGE, NULL, "set_json while rendering");
        OK(ctx, A.spc_job_wait(ctx, job, &r2));
        OK(ctx, A.spc_job_done(job, &done));
        CHECK(done == 1);
        CHECK(r2 && sync && sameBeauty(ctx, sync, r2));
        A.spc_result_destroy(sync);
        A.spc_result_destroy(r2);
        r2 = NULL;
        expectError(ctx, A.spc_job_wait(ctx, job, &r2), SPC_USAGE, NULL, "second wait");
        CHECK(r2 == NULL);
        A.spc_job_destroy(job);
        OK(ctx, A.spc_scene_set_json(ctx, scene, "/render/spp", "4")); /* editable again */

        /* A long render (256x192, 64 spp, 1 thread, ~100 tiles) cancelled from a pthread after its first tile. */
        {
            AsyncState st;
            pthread_t th;
            spc_render_options one = SPC_RENDER_OPTIONS_INIT;
            double t = now();
            spc_status ws;
            one.threads = 1;
            OK(ctx, A.spc_scene_set_json(ctx, scene, "/render/width", "256"));
            OK(ctx, A.spc_scene_set_json(ctx, scene, "/render/height", "192"));
            OK(ctx, A.spc_scene_set_json(ctx, scene, "/render/spp", "64"));
            memset(&st, 0, sizeof st);
            pthread_mutex_init(&st.m, NULL);
            pthread_cond_init(&st.cv, NULL);
            OK(ctx, A.spc_render_async(ctx, scene, &one, onTileAsync, &st, &job));
            st.job = job;
            pthread_create(&th, NULL, canceller, &st);
            ws = A.spc_job_wait(ctx, job, &r2);
            pthread_join(th, NULL);
            CHECK(ws == SPC_CANCELLED && st.cancelStatus == SPC_OK);
            OK(ctx, A.spc_result_stats(ctx, r2, &s));
            CHECK(s.cancelled == 1 && s.tiles_done < s.tiles_total);
            printf("async cancel from a thread: %s, %d/%d tiles, %.2f s\n", A.spc_status_name(ws), s.tiles_done,
                   s.tiles_total, now() - t);
            A.spc_result_destroy(r2);
            r2 = NULL;
            A.spc_job_destroy(job);

            /* Destroying the scene handle while a job renders it is safe; destroying the job cancels it. */
            OK(ctx, A.spc_render_async(ctx, scene, &one, NULL, NULL, &job));
            A.spc_scene_destroy(scene);
            scene = NULL;
            t = now();
            A.spc_job_cancel(job);
            A.spc_job_destroy(job);
            printf("destroy a running job: %.2f s\n", now() - t);
            pthread_mutex_destroy(&st.m);
            pthread_cond_destroy(&st.cv);
        }
    }

    /* ---- GLSL ---- */
    OK(ctx, A.spc_scene_load_string(ctx, kScene, NULL, NULL, &scene));
    {
        char *src = NULL, *manifest = NULL;
        OK(ctx, A.spc_glsl_export(ctx, scene, "gold", 0, &src, &manifest));
        CHECK(src && strstr(src, "specula_eval") != NULL && strstr(src, "#version 450") != NULL);
        CHECK(manifest && manifest[0] == '{' && strstr(manifest, "\"uniform_block\"") != NULL &&
              strstr(manifest, "bsdf.ggx") != NULL);
        printf("glsl 'gold': %zu characters, manifest %zu bytes\n", src ? strlen(src) : 0, manifest ? strlen(manifest) : 0);
        A.spc_string_free(src), A.spc_string_free(manifest);
        OK(ctx, A.spc_glsl_export(ctx, scene, "floor", SPC_GLSL_INLINE_LITERALS, &src, NULL));
        CHECK(src && strstr(src, "specula_eval") != NULL);
        A.spc_string_free(src);
        expectError(ctx, A.spc_glsl_export(ctx, scene, "glod", 0, &src, &manifest), SPC_BAD_INPUT, "/materials/glod",
                    "glsl of an unknown material");
        CHECK(src == NULL && manifest == NULL);
        expectError(ctx, A.spc_glsl_export(ctx, scene, NULL, 0, &src, NULL), SPC_USAGE, "/materials",
                    "glsl of the only material, with two");
    }

    A.spc_result_destroy(r1);
    A.spc_scene_destroy(scene);
    A.spc_context_destroy(ctx);
    printf("%s: %d failure(s), %.2f s\n", failures ? "FAILED" : "PASSED", failures, now() - t0);
    /* No dlclose: TBB's worker threads may still be parking. */
    return failures ? 1 : 0;
}
