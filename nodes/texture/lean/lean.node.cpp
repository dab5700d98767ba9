// texture.lean: LEAN mapping (Olano & Baker 2010) of a tangent-space normal map: slope-moment MIP pyramid built
// on load (core/texture/lean_moments.h), filtered with the ray-differential footprint; outputs the mean normal,
// mean slope, (σx, σy, ρ) and the slope covariance Σ for bsdf.beckmann_lean, bsdf.ggx_filtered and bsdf.glint.
#include "nodes/node_common.h"

#include "nodes/shared/normal_map_source.h"

#include "core/graph/closure_util.h"
#include "nodes/shared/lean_resource.h"
#include "nodes/shared/texture_ports.h"
#include "core/graph/graph_material.h"
#include "core/texture/lean_moments.h"
#include "core/texture/texture_store.h"
#include "core/util/error.h"

#include <cstring>
#include <filesystem>

namespace specula::nodes {
namespace {

enum class LeanFilterChoice : int { Anisotropic, Trilinear, None };
enum class LeanCorrelation : int { Full, Ignore };
enum class LeanWrapChoice : int { Repeat, Clamp };

}  // namespace
}  // namespace specula::nodes

SPECULA_ENUM(specula::nodes::LeanFilterChoice, "SPC_LEAN_FILTER", "anisotropic", "trilinear", "none");
SPECULA_ENUM(specula::nodes::LeanCorrelation, "SPC_LEAN_CORRELATION", "full", "ignore");
SPECULA_ENUM(specula::nodes::LeanWrapChoice, "SPC_LEAN_WRAP", "repeat", "clamp");

namespace specula::nodes {
namespace {

struct Params {
    NormalMapConvention convention;
    LeanFilterChoice filter;
    LeanCorrelation correlation;
    LeanWrapChoice wrap;
    float strength;
    Vec2 uv, duvdx, duvdy;
    Vec3 normal, tangent;
    float sign, uvScale;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .str("file", "tangent-space normal map, colour = (n + 1)/2, read as raw data (relative to the scene file), or "
                 "'generate:<kind>:<size>:<seed>' for a generated map")
    .choice("convention", &Params::convention, "green channel: opengl = +Y up, directx = +Y down")
    .choice("filter", &Params::filter,
            "footprint filter: anisotropic probes along the major axis, isotropic trilinear, or none "
            "(bilinear on the full-resolution level: the reference)")
    .choice("correlation", &Params::correlation, "ignore: drop the slope correlation (rho = 0, cov_xy = 0)")
    .choice("wrap", &Params::wrap, "wrap mode")
    .f("strength", &Params::strength, 1.f, "scales the slopes (mean x s, covariance x s^2)").range(0.f, 2.f).hard(0.f, 1e3f)
    .v2("uv", &Params::uv, Vec2(0.f), "texture coordinates").range(-1.f, 2.f).bind(GeomBinding::UV)
    .v2("duvdx", &Params::duvdx, Vec2(0.f), "footprint: d(uv)/dx").range(-0.5f, 0.5f).bind(GeomBinding::DUVDX)
    .v2("duvdy", &Params::duvdy, Vec2(0.f), "footprint: d(uv)/dy").range(-0.5f, 0.5f).bind(GeomBinding::DUVDY)
    .n3("normal", &Params::normal, Vec3(0, 0, 1), "unperturbed surface normal").bind(GeomBinding::N)
    .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent (+u)").bind(GeomBinding::T)
    .f("sign", &Params::sign, 1.f, "bitangent sign (+v = sign N x T)").range(-1.f, 1.f).bind(GeomBinding::TSign)
    .f("uv_scale", &Params::uvScale, 1.f, "multiplies uv and its footprint (tiling that keeps the filter right)").range(0.5f, 4.f);
OutputList kOutputs;
const OutPort<Vec3> kNormal = kOutputs.add<Vec3>("normal", TypeDesc::Normal3, "mean normal normalize(-E[x], -E[y], 1) in world space");
const OutPort<Vec2> kSlope = kOutputs.add<Vec2>("slope", TypeDesc::Vec2, "mean slope (E[x], E[y]) in the (T, N x T) frame");
const OutPort<Vec3> kSigmaRho = kOutputs.add<Vec3>("sigma_rho", TypeDesc::Vector3, "(sigma_x, sigma_y, rho) of the slope Gaussian");
const OutPort<Vec3> kCovariance = kOutputs.add<Vec3>("covariance", TypeDesc::Vector3, "slope covariance (var_x, var_y, cov_xy)");

struct LeanData {
    std::shared_ptr<const LeanPyramid> pyramid;
};

std::shared_ptr<const void> prepare(const PrepareContext& pc) {
    const std::string& file = pc.str("file");
    if (!pc.load || !pc.load->textures)
        throw InputError(pc.pointer("file"), "texture.lean needs a texture store (none was given to the graph loader)");
    const std::string path = resolveTexturePath(pc, file);
    auto d = std::make_shared<LeanData>();
    try {
        TextureStore& store = *pc.load->textures;
        TextureHandle h = store.load(path, "raw");  // normal maps are data: no colour conversion
        if (store.channels(h) < 2)
            throw InputError(pc.pointer("file"), "texture.lean: '" + file + "' has " + std::to_string(store.channels(h)) +
                                                 " channel(s); a tangent-space normal map needs 2 or 3");
        d->pyramid = sharedLeanPyramid(store.pixels(h), store.width(h), store.height(h), store.channels(h));
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throwTextureLoadError(pc.pointer("file"), path, std::string("cannot load normal map: ") + e.what(), e);
    }
    return d;
}

// The sampler the GLSL reads (nodes/shared/lean_resource.h).
ResourceImage momentTexels(const void* prepared) {
    return leanMomentImage(*static_cast<const LeanData*>(prepared)->pyramid);
}

void cpu(EvalContext& c, const Instr& i) {
    const auto* d = static_cast<const LeanData*>(i.data);
    const Params p = kParams.read(c, i);
    static const LeanFilter filters[] = {LeanFilter::Anisotropic, LeanFilter::Trilinear, LeanFilter::None};
    LeanMoments m = d->pyramid->lookup(p.uv * p.uvScale, p.duvdx * p.uvScale, p.duvdy * p.uvScale, filters[int(p.filter)],
                                       p.wrap == LeanWrapChoice::Clamp ? LeanWrap::Clamp : LeanWrap::Repeat, 16);
    // Slopes are expressed in the BSDF frame (T, N×T, N): DirectX maps and left-handed frames (sign < 0) flip y.
    const bool flip = (p.convention == NormalMapConvention::DirectX) != (p.sign < 0.f);
    LeanStats s = leanStats(m, p.strength, flip, p.correlation == LeanCorrelation::Ignore);
    Frame f = bsdfFrame(p.normal, p.tangent);
    Vec3 nt = s.meanNormal();
    Vec3 nw = nt.x * f.t + nt.y * f.b + nt.z * f.n;
    float l2 = glm::dot(nw, nw);
    set(c, i, kNormal, l2 > 0.f ? nw / std::sqrt(l2) : f.n);
    set(c, i, kSlope, s.mean);
    set(c, i, kSigmaRho, Vec3(s.sigmaX, s.sigmaY, s.rho));
    set(c, i, kCovariance, Vec3(s.varX, s.varY, s.covXY));
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("texture.lean",
                             "LEAN mapping (Olano & Baker 2010): footprint-filtered first and second slope moments of "
                             "a tangent-space normal map -> mean normal, mean slope, (sigma_x, sigma_y, rho) and the "
                             "slope covariance, in the frame (T, N x T, N) of the normal/tangent inputs. Slopes: x = "
                             "-nx/nz, y = -ny/nz.",
                             kParams, kOutputs, &cpu, kNeedsDerivatives);
    s.resources = {{"moments", "sampler2D", ResourceSpec::Kind::DerivedImage,
                    "LEAN slope-moment pyramid built from the file on load (LeanPyramid::glslPackedLevel per level)",
                    &momentTexels, "file", ""}};
    s.prepare = &prepare;
    s.parityTolerance = 3e-4f;
    s.parityNote = "the parity image has texels below the horizon (slopes clamped to 16, moments up to 256); the mean "
                   "and covariance of mixed footprints are small differences of such sums (FMA contraction on llvmpipe), "
                   "measured 1.1e-4";
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
