/* libspecula C ABI example (docs/capi.md): check the ABI, load a scene from a string, render it with a progress
 * callback, override the sample count by JSON pointer, read an AOV, write the EXR, export GLSL, show an error.
 * Links libspecula (-lspecula); a host that dlopens it uses the same calls. Usage: specula_capi_example [OUTPUT_DIR] */
#include <specula/specula_c.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char* kScene =
    "{\"version\": 1, \"render\": {\"width\": 48, \"height\": 32, \"spp\": 2, \"seed\": 1, \"tile\": 16},"
    " \"camera\": {\"position\": [0, -4, 1], \"look_at\": [0, 0, 0.6], \"fov\": 40},"
    " \"materials\": {\"gold\": {\"nodes\": {\"s\": {\"type\": \"bsdf.ggx\", \"inputs\": {\"roughness\": 0.2,"
    "   \"fresnel\": \"schlick\", \"f0\": [1.0, 0.78, 0.34]}}}, \"output\": \"@s.bsdf\"}},"
    " \"shapes\": [{\"type\": \"sphere\", \"radius\": 0.6, \"transform\": {\"translate\": [0, 0, 0.6]}, \"material\": \"gold\"}],"
    " \"lights\": [{\"type\": \"point\", \"position\": [1.5, -2, 3], \"power\": 400}]}";

/* Counts tiles; the callback runs on a render thread, serially. */
static int onTile(const spc_tile* t, void* user) {
    int* tiles = (int*)user;
    ++*tiles;
    (void)t->beauty; /* RGB of pixel (x0, y0); pixel (x, y) = beauty + (y-y0)*beauty_row_stride + (x-x0)*3 */
    return 1;        /* 0 cancels */
}

/* Prints the context's error and exits: every call returns a status, the message stays in the context. */
static void check(spc_context* ctx, spc_status s, const char* what) {
    if (s == SPC_OK) return;
    fprintf(stderr, "capi_example: %s: %s: %s\n", what, spc_status_name(s), spc_last_error(ctx));
    exit(1);
}

int main(int argc, char** argv) {
    const char* outDir = argc > 1 ? argv[1] : ".";
    char path[1024];
    spc_context* ctx;
    spc_scene* scene;
    spc_result* result;
    spc_render_stats stats;
    spc_aov_view beauty;
    spc_written written;
    char *glsl, *manifest;
    int tiles = 0, i;
    double sum = 0;

    if (!spc_abi_compatible(SPC_ABI_VERSION)) {
        fprintf(stderr, "libspecula ABI 0x%08x, built for 0x%08x\n", (unsigned)spc_abi_version(), (unsigned)SPC_ABI_VERSION);
        return 1;
    }
    printf("libspecula %s, C ABI %u.%u\n", spc_version(), (unsigned)(spc_abi_version() >> 16),
           (unsigned)(spc_abi_version() & 0xffffu));
    if (spc_context_create(&ctx) != SPC_OK) return 1;

    check(ctx, spc_scene_load_string(ctx, kScene, NULL, NULL, &scene), "load");
    check(ctx, spc_scene_set_json(ctx, scene, "/render/spp", "4"), "set /render/spp");
    check(ctx, spc_render(ctx, scene, NULL, onTile, &tiles, &result), "render");
    check(ctx, spc_result_stats(ctx, result, &stats), "stats");
    check(ctx, spc_result_aov_named(ctx, result, "beauty", &beauty), "beauty");
    for (i = 0; i < beauty.width * beauty.height * beauty.channels; ++i) sum += beauty.pixels[i];
    printf("render: %dx%d, %d tiles, %llu samples, beauty mean %s\n", stats.width, stats.height, tiles,
           (unsigned long long)stats.samples, sum > 0 ? "positive" : "ZERO");

    snprintf(path, sizeof path, "%s/capi_example.exr", outDir);
    check(ctx, spc_result_write(ctx, scene, result, path, &written), "write");
    printf("wrote %s and %s\n", strrchr(written.exr, '/') + 1, strrchr(written.png, '/') + 1);
    spc_string_free(written.exr);
    spc_string_free(written.png);

    check(ctx, spc_glsl_export(ctx, scene, "gold", 0, &glsl, &manifest), "glsl");
    printf("glsl: %s, manifest %s\n", strstr(glsl, "specula_eval") ? "has specula_eval" : "NO specula_eval",
           strstr(manifest, "\"uniform_block\"") ? "lists the uniform block" : "MISSING");
    spc_string_free(glsl);
    spc_string_free(manifest);

    /* An error: status, message, JSON pointer and suggestion; the context stays usable. */
    if (spc_scene_set_json(ctx, scene, "/materials/gold/nodes/s/inputs/roughnes", "0.5") != SPC_OK)
        printf("error: %s, pointer %s\n", spc_status_name(spc_last_status(ctx)), spc_last_error_pointer(ctx));

    spc_result_destroy(result);
    spc_scene_destroy(scene);
    spc_context_destroy(ctx);
    return 0;
}
