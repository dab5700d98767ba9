// The GPU preview's per-frame uniform block and its light record, declared once: the C++ structs the preview packs and
// the GLSL text of the same block (frameBlockGlsl) both come from the field lists below, so the two cannot drift.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace specula {
struct RasterLight;
struct ShadowLight;
}  // namespace specula

namespace specula::preview {

inline constexpr int kMaxLights = 64;

// One light of the preview's light loop (plugin/preview/preview_lights.glsl): every field a vec4, so that std140 puts
// field k at 16·k bytes and the record's stride is its size. FIELD(name, meaning).
#define SPECULA_PREVIEW_LIGHT_FIELDS(FIELD)                                                                           \
    FIELD(header, "kind (RasterLight::Kind), cos outer | has a map, cos inner | map rotation, two-sided")            \
    FIELD(position, "point, spot: position; quad: corner")                                                         \
    FIELD(direction, "spot: cone axis; directional: towards the light; quad: edge u")                               \
    FIELD(edge_v, "quad: edge v")                                                                                  \
    FIELD(value, "RasterLight::value")                                                                             \
    FIELD(shadow, "ShadowLight: mode, first layer, scale, texel factor")                                           \
    FIELD(shadow_origin, "ShadowLight: origin, reach")                                                             \
    FIELD(shadow_right, "ShadowLight: right")                                                                      \
    FIELD(shadow_up, "ShadowLight: up")                                                                            \
    FIELD(shadow_axis, "ShadowLight: axis")

struct PreviewLight {
#define SPECULA_PREVIEW_FIELD(name, meaning) float name[4];
    SPECULA_PREVIEW_LIGHT_FIELDS(SPECULA_PREVIEW_FIELD)
#undef SPECULA_PREVIEW_FIELD
};

// The block shared by the vertex and fragment stages: FIELD(C++ type, name, C++ extent, GLSL type, GLSL array length
// or 0), the GLSL member named spc_<name>. std140 offsets equal the C++ ones: every member is 16-byte aligned and a
// multiple of 16 bytes long.
#define SPECULA_PREVIEW_FRAME_FIELDS(FIELD)                                                                           \
    FIELD(float, view_proj, [16], "mat4", 0)                                                                       \
    FIELD(float, eye, [4], "vec4", 0)                                                                              \
    FIELD(float, forward, [4], "vec4", 0)                                                                          \
    FIELD(int, counts, [4], "ivec4", 0) /* light count, LTC horizon, 0, 0 */                                       \
    FIELD(PreviewLight, lights, [kMaxLights], "SpcPreviewLight", kMaxLights)

struct FrameBlock {
#define SPECULA_PREVIEW_FIELD(ctype, name, extent, glslType, glslLength) ctype name extent;
    SPECULA_PREVIEW_FRAME_FIELDS(SPECULA_PREVIEW_FIELD)
#undef SPECULA_PREVIEW_FIELD
};

// The light's record: RasterLight and its shadow maps' ShadowLight as the light loop reads them.
PreviewLight packLight(const RasterLight& r, const ShadowLight& shadow);

// The GLSL declaration of struct SpcPreviewLight and of the std140 block SpeculaPreviewFrame at binding
// SPC_PREVIEW_FRAME_BINDING (a define the host puts first).
std::string frameBlockGlsl();

// Every member's GLSL name and its byte offset in FrameBlock, the light fields for lights 0 and 1 (spc_lights[1].value):
// what a GL program's introspection must report for frameBlockGlsl.
struct FieldOffset {
    std::string glslName;
    size_t offset;
};
std::vector<FieldOffset> frameBlockOffsets();

}  // namespace specula::preview
