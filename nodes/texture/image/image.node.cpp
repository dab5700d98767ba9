// texture.image: an image file (declared colorspace, converted to the working space by TextureStore)
// filtered with the ray-differential footprint (duvdx, duvdy); GLSL: sampler2D + textureGrad.
#include "nodes/node_common.h"

#include "core/graph/graph_material.h"
#include "core/texture/texture_store.h"
#include "core/util/error.h"

#include <filesystem>

namespace specula::nodes {
namespace {

struct ImageData {
    const TextureStore* store;
    TextureHandle handle;
    TextureWrap wrap;
};

std::shared_ptr<const void> prepare(const PrepareContext& pc) {
    const std::string& file = (*pc.strings)[0];
    const std::string& cs = (*pc.strings)[1];
    if (!pc.load || !pc.load->textures)
        throw InputError(pc.pointers[0], "texture.image needs a texture store (none was given to the graph loader)");
    std::filesystem::path p(file);
    if (p.is_relative() && !pc.load->baseDir.empty()) p = std::filesystem::path(pc.load->baseDir) / p;
    auto d = std::make_shared<ImageData>();
    d->store = pc.load->textures;
    static const TextureWrap wraps[] = {TextureWrap::Repeat, TextureWrap::Clamp, TextureWrap::Mirror};
    const std::string& w = (*pc.strings)[2];
    d->wrap = w == "clamp" ? wraps[1] : w == "mirror" ? wraps[2] : wraps[0];
    try {
        d->handle = pc.load->textures->load(p.string(), cs);
    } catch (const std::exception& e) {
        throw InputError(pc.pointers[0], std::string("cannot load texture: ") + e.what());
    }
    return d;
}

void cpu(EvalContext& c, const Instr& i) {
    const auto* d = static_cast<const ImageData*>(i.data);
    float px[4];
    d->store->sample(d->handle, inV2(c, i, 3), inV2(c, i, 4), inV2(c, i, 5), px, 4, d->wrap);
    outV3(c, i, 0, Vec3(px[0], px[1], px[2]));
    outF(c, i, 1, px[3]);
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "texture.image";
    s.category = "texture";
    s.doc = "Filtered image lookup. v = 0 is the bottom row (OpenGL convention).";
    s.inputs = {PortSpec::str("file", "image path (relative to the scene file)"),
                PortSpec::str("colorspace", "colorspace of the file (OCIO name/alias, or \"raw\" for data)"),
                PortSpec::choice("wrap", {"repeat", "clamp", "mirror"}, "wrap mode"),
                std::move(PortSpec::v2("uv", Vec2(0.f), "texture coordinates")).range(-1.f, 2.f).bind(GeomBinding::UV),
                std::move(PortSpec::v2("duvdx", Vec2(0.f), "footprint: d(uv)/dx")).range(-0.01f, 0.01f).bind(GeomBinding::DUVDX),
                std::move(PortSpec::v2("duvdy", Vec2(0.f), "footprint: d(uv)/dy")).range(-0.01f, 0.01f).bind(GeomBinding::DUVDY)};
    s.outputs = {PortSpec::out("color", TypeDesc::Color3, "RGB in the working space"),
                 PortSpec::out("alpha", TypeDesc::Float, "alpha (1 if the file has none)")};
    s.flags = kNeedsDerivatives | kGlslTexture;
    s.cpu = &cpu;
    s.prepare = &prepare;
    s.glslFunction = "spc_texture_image";
    s.glslFile = "texture/image/image.glsl";
    s.parityTolerance = 2e-4f;
    s.parityNote = "bilinear lookups (zero footprint): OIIO vs llvmpipe filter-weight rounding, measured 8.4e-5; "
                   "non-zero footprints use different filters (OIIO anisotropic vs GL trilinear) and are not compared";
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
