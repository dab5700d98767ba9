// texture.image: an image file (declared colorspace, converted to the working space by TextureStore) filtered with the
// footprint (duvdx, duvdy): OpenImageIO's filter on the CPU; on the GPU GL's rules with the LOD and anisotropic probes
// computed in the shader over a host-built MIP chain (GlMipChain), whose CPU twin the raster integrator runs.
#include "nodes/node_common.h"

#include "nodes/shared/normal_map_source.h"
#include "nodes/shared/texture_ports.h"

#include "core/graph/graph_material.h"
#include "core/texture/gl_mip_chain.h"
#include "core/texture/texture_store.h"
#include "core/util/error.h"

#include <filesystem>
#include <mutex>

namespace specula::nodes {
namespace {

struct Params {
    ImageWrap wrap;  // read by prepare() as its string
    Vec2 uv, duvdx, duvdy;
    float uvScale;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .str("file", "image path (relative to the scene file), or 'generate:<kind>:<size>:<seed>' for a generated normal "
                 "map (core/texture/normal_map_gen.h; use colorspace raw)")
    .str("colorspace", "colorspace of the file (OCIO name/alias, or \"raw\" for data)")
    .choice("wrap", &Params::wrap, "wrap mode (sampler state)").uniform()
    .v2("uv", &Params::uv, Vec2(0.f), "texture coordinates").range(-1.f, 2.f).bind(GeomBinding::UV)
    .v2("duvdx", &Params::duvdx, Vec2(0.f), "footprint: d(uv)/dx").range(-0.01f, 0.01f).bind(GeomBinding::DUVDX)
    .v2("duvdy", &Params::duvdy, Vec2(0.f), "footprint: d(uv)/dy").range(-0.01f, 0.01f).bind(GeomBinding::DUVDY)
    .f("uv_scale", &Params::uvScale, 1.f, "multiplies uv and its footprint (tiling that keeps the filter right)").range(0.5f, 4.f);
OutputList kOutputs;
const OutPort<Vec3> kColor = kOutputs.add<Vec3>("color", TypeDesc::Color3, "RGB in the working space");
const OutPort<float> kAlpha = kOutputs.add<float>("alpha", TypeDesc::Float, "alpha (1 if the file has none)");
const OutPort<Vec3> kDcolorDu = kOutputs.add<Vec3>(
    "dcolor_du", TypeDesc::Color3, "texture gradient d(color)/du per unit of the uv input (for texture.normal_map derivatives)");
const OutPort<Vec3> kDcolorDv = kOutputs.add<Vec3>("dcolor_dv", TypeDesc::Color3, "texture gradient d(color)/dv");

struct ImageData {
    const TextureStore* store;
    TextureHandle handle;
    TextureWrap wrap;
    // The GPU's MIP chain (RGBA, rows bottom-up, missing channels expanded like TextureStore::sample), built on first
    // use: a GLSL export or the raster integrator's GPU twin; a CPU render never needs it.
    mutable std::once_flag chainOnce;
    mutable GlMipChain chain;
    const GlMipChain& glChain() const {
        std::call_once(chainOnce, [&] {
            const int w = store->width(handle), h = store->height(handle), c = store->channels(handle);
            const std::vector<float>& src = store->pixels(handle);
            std::vector<float> rgba(size_t(w) * h * 4);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x)
                    for (int k = 0; k < 4; ++k) {
                        const float* p = &src[(size_t(h - 1 - y) * w + x) * c];
                        rgba[(size_t(y) * w + x) * 4 + k] = k < c ? p[k] : (k == 3 ? 1.f : p[c - 1]);
                    }
            chain = GlMipChain::build(w, h, std::move(rgba));
        });
        return chain;
    }
};

std::shared_ptr<const void> prepare(const PrepareContext& pc) {
    const std::string& file = pc.str("file");
    const std::string& cs = pc.str("colorspace");
    if (!pc.load || !pc.load->textures)
        throw InputError(pc.pointer("file"), "texture.image needs a texture store (none was given to the graph loader)");
    const std::string path = resolveTexturePath(pc, file);
    auto d = std::make_shared<ImageData>();
    d->store = pc.load->textures;
    static const TextureWrap wraps[] = {TextureWrap::Repeat, TextureWrap::Clamp, TextureWrap::Mirror};
    const std::string& w = pc.str("wrap");
    d->wrap = w == "clamp" ? wraps[1] : w == "mirror" ? wraps[2] : wraps[0];
    try {
        d->handle = pc.load->textures->load(path, cs);
    } catch (const TextureColorspaceError& e) {
        throw InputError(pc.pointer("colorspace"), e.what());  // the key to fix is colorspace, not file
    } catch (const std::exception& e) {
        throwTextureLoadError(pc.pointer("file"), path, std::string("cannot load texture: ") + e.what(), e);
    }
    return d;
}

// The sampler the GLSL reads: the working-space image's MIP chain as GlMipChain builds it (every level given, so no
// glGenerateMipmap: the GPU and the CPU twin filter the same texels), GL_LINEAR_MIPMAP_LINEAR, the node's wrap mode.
ResourceImage imageTexels(const void* prepared) {
    const auto* d = static_cast<const ImageData*>(prepared);
    const GlMipChain& chain = d->glChain();
    ResourceImage r;
    for (int l = 0; l < chain.levels(); ++l) {
        ResourceImage::Level lv;
        lv.width = chain.level(l).width;
        lv.height = chain.level(l).height;
        lv.rgba = chain.level(l).texels;
        r.levels.push_back(std::move(lv));
    }
    r.colorspace = "working";
    const char* wrap = d->wrap == TextureWrap::Clamp ? "clamp_to_edge" : d->wrap == TextureWrap::Mirror ? "mirrored_repeat" : "repeat";
    r.wrapS = r.wrapT = wrap;
    return r;
}

// lookup(uv, dx, dy) -> RGBA: OpenImageIO's filter (the CPU model) or the GL rules on the GPU's chain (its twin).
template <class Lookup>
void shadeImage(EvalContext& c, const Instr& i, const ImageData& d, Lookup lookup) {
    const Params p = kParams.read(c, i);
    const Vec2 uv = p.uv * p.uvScale, dx = p.duvdx * p.uvScale, dy = p.duvdy * p.uvScale;
    const Vec4 px = lookup(uv, dx, dy);
    set(c, i, kColor, Vec3(px));
    set(c, i, kAlpha, px.w);
    if (wanted(i, kDcolorDu) || wanted(i, kDcolorDv)) {
        // Central differences one level-0 texel apart, each lookup with the same footprint (the gradient of the
        // filtered image), times uv_scale for the derivative with respect to the uv input. GLSL: the same lookups.
        const float hu = 1.f / float(d.store->width(d.handle)), hv = 1.f / float(d.store->height(d.handle));
        auto at = [&](Vec2 o) { return Vec3(lookup(uv + o, dx, dy)); };
        set(c, i, kDcolorDu, (at(Vec2(hu, 0.f)) - at(Vec2(-hu, 0.f))) * (p.uvScale / (2.f * hu)));
        set(c, i, kDcolorDv, (at(Vec2(0.f, hv)) - at(Vec2(0.f, -hv))) * (p.uvScale / (2.f * hv)));
    }
}

void cpu(EvalContext& c, const Instr& i) {
    const auto* d = static_cast<const ImageData*>(i.data);
    shadeImage(c, i, *d, [d](Vec2 uv, Vec2 dx, Vec2 dy) {
        float q[4];
        d->store->sample(d->handle, uv, dx, dy, q, 4, d->wrap);
        return Vec4(q[0], q[1], q[2], q[3]);
    });
}

// What spc_texture_image computes (the raster integrator's GPU twin, NodeSpec::gpuSubstituteCpu).
void cpuGpuTwin(EvalContext& c, const Instr& i) {
    const auto* d = static_cast<const ImageData*>(i.data);
    const GlMipChain& chain = d->glChain();
    shadeImage(c, i, *d, [&chain, d](Vec2 uv, Vec2 dx, Vec2 dy) { return chain.anisotropic(uv, dx, dy, d->wrap); });
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("texture.image",
                             "Filtered image lookup. v = 0 is the bottom row (OpenGL convention).",
                             kParams, kOutputs, &cpu, kNeedsDerivatives);
    s.notes = "`colorspace`: any OCIO name/alias or `raw`; `color` is converted to the working space. CPU: "
              "`TextureStore::sample` (OIIO TextureSystem, bilinear + anisotropic MIP filtering with the footprint, v "
              "= 0 bottom). GLSL: the host-built MIP chain (`GlMipChain`) read with `textureLod` at GL's LOD, in "
              "EXT_texture_filter_anisotropic probes computed in the shader (up to 16; footprints within 0.1 % of "
              "isotropic take one); the raster integrator runs the same filter on the CPU; the emitter declares the "
              "sampler.";
    s.resources = {{"image", "sampler2D", ResourceSpec::Kind::ImageFile,
                    "the image in the working space, RGBA, rows bottom-up, MIP-mapped, trilinear, wrap as the input",
                    &imageTexels, "file", "colorspace"}};
    s.gpuSubstituteCpu = &cpuGpuTwin;  // the GLSL filters by GL's rules, OpenImageIO's filter is the CPU model
    s.prepare = &prepare;
    s.parityTolerance = 5e-3f;
    s.parityNote = "against the GPU twin (GL rules on the same MIP chain, footprints included): colour and alpha within "
                   "llvmpipe's bilinear-weight rounding (8.4e-5 at zero footprint); the texture gradients divide a "
                   "difference of two lookups by two texels (x8 on the 16-texel test image): measured 2.95e-3";
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
