// The preview's frame block from its one declaration (preview_frame.h): the packer of a light's record, the GLSL text of
// the block, and the offsets a GL program must report for it.
#include "plugin/preview/preview_frame.h"

#include "core/render/lights.h"
#include "core/render/shadow_maps.h"

namespace specula::preview {

namespace {

void put(float* dst, const Vec3& v, float w) { dst[0] = v.x, dst[1] = v.y, dst[2] = v.z, dst[3] = w; }

}  // namespace

PreviewLight packLight(const RasterLight& r, const ShadowLight& sh) {
    PreviewLight l{};
    const bool env = r.kind == RasterLight::Kind::Environment;
    l.header[0] = float(int(r.kind));
    l.header[1] = env ? (r.hasMap ? 1.f : 0.f) : r.cosOuter;
    l.header[2] = env ? r.mapRotation : r.cosInner;
    l.header[3] = r.twoSided ? 1.f : 0.f;
    put(l.position, r.position, 0.f);
    put(l.direction, r.direction, 0.f);
    put(l.edge_v, r.edgeV, 0.f);
    put(l.value, r.value, 0.f);
    l.shadow[0] = float(int(sh.mode)), l.shadow[1] = float(sh.firstLayer), l.shadow[2] = sh.scale, l.shadow[3] = sh.texelFactor;
    put(l.shadow_origin, sh.origin, sh.reach);
    put(l.shadow_right, sh.right, 0.f);
    put(l.shadow_up, sh.up, 0.f);
    put(l.shadow_axis, sh.axis, 0.f);
    return l;
}

std::string frameBlockGlsl() {
    std::string s = "struct SpcPreviewLight {\n";
#define SPECULA_PREVIEW_FIELD(name, meaning) s += "    vec4 " #name ";  // " meaning "\n";
    SPECULA_PREVIEW_LIGHT_FIELDS(SPECULA_PREVIEW_FIELD)
#undef SPECULA_PREVIEW_FIELD
    s += "};\nlayout(std140, binding = SPC_PREVIEW_FRAME_BINDING) uniform SpeculaPreviewFrame {\n";
#define SPECULA_PREVIEW_FIELD(ctype, name, extent, glslType, glslLength) \
    s += std::string("    ") + glslType + " spc_" #name + (glslLength ? "[" + std::to_string(glslLength) + "]" : "") + ";\n";
    SPECULA_PREVIEW_FRAME_FIELDS(SPECULA_PREVIEW_FIELD)
#undef SPECULA_PREVIEW_FIELD
    return s + "};\n";
}

std::vector<FieldOffset> frameBlockOffsets() {
    std::vector<FieldOffset> r;
#define SPECULA_PREVIEW_FIELD(ctype, name, extent, glslType, glslLength) \
    if (!glslLength) r.push_back({"spc_" #name, offsetof(FrameBlock, name)});
    SPECULA_PREVIEW_FRAME_FIELDS(SPECULA_PREVIEW_FIELD)
#undef SPECULA_PREVIEW_FIELD
    for (size_t i = 0; i < 2; ++i) {
        const std::string light = "spc_lights[" + std::to_string(i) + "].";
#define SPECULA_PREVIEW_FIELD(name, meaning) \
    r.push_back({light + #name, offsetof(FrameBlock, lights) + i * sizeof(PreviewLight) + offsetof(PreviewLight, name)});
        SPECULA_PREVIEW_LIGHT_FIELDS(SPECULA_PREVIEW_FIELD)
#undef SPECULA_PREVIEW_FIELD
    }
    return r;
}

}  // namespace specula::preview
