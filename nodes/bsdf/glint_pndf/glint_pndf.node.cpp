// bsdf.glint_pndf: position-normal manifold glints (Wu et al. 2024) of an explicit high-resolution normal map: the exact
// P-NDF of the pixel footprint (pndf_eval.h) as the microfacet D, sampled for MIS (pndf_sample.h), separable Smith
// masking from the analytic projected area or its GGX fit (pndf_masking.h); CPU lobe pndf_lobe.h.
//
// GPU: the exact P-NDF (a triangle search through a ~34 MB hierarchy per query) is not supported. The GLSL function
// (glint_pndf.glsl) is a declared substitute, LEAN-filtered GGX of the same map over a footprint of the same variance;
// NodeSpec::gpuSubstitute makes the emitter warn once per module and gpuSubstituteCpu is the substitute's CPU twin,
// which the parity suite compares against. Spec: shared/specs/pndf-manifold.md §1 (footprint), §2–§5.
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/shared/ltc_gpu.h"
#include "nodes/bsdf/ggx_filtered/filtered_ggx.h"
#include "nodes/bsdf/glint_pndf/pndf_cache.h"
#include "nodes/bsdf/glint_pndf/pndf_lobe.h"
#include "nodes/shared/bsdf_ports.h"
#include "nodes/shared/lean_resource.h"
#include "nodes/shared/normal_map_source.h"
#include "nodes/shared/texture_ports.h"
#include "core/util/error.h"

#include <map>
#include <mutex>

namespace specula::nodes {
namespace {

enum class PndfKernel : int { Gaussian, Box, Disk };
enum class PndfMasking : int { GgxFit, Analytic };
enum class PndfFootprintCentre : int { Sample, Pixel };

}  // namespace
}  // namespace specula::nodes

SPECULA_ENUM(specula::nodes::PndfKernel, "SPC_PNDF_KERNEL", "gaussian", "box", "disk");
SPECULA_ENUM(specula::nodes::PndfMasking, "SPC_PNDF_MASKING", "ggx_fit", "analytic");
SPECULA_ENUM(specula::nodes::PndfFootprintCentre, "SPC_PNDF_FOOTPRINT_CENTRE", "sample", "pixel");

namespace specula::nodes {
namespace {

using namespace specula::pndf;

struct Params {
    Color3 weight;
    NormalMapConvention convention;
    Vec2 uv, duvdx, duvdy;
    float uvScale, footprintScale;
    PndfKernel kernel;
    PndfFootprintCentre footprintCentre;
    float clusterThreshold, jacobianClamp;
    PndfMasking masking;
    FresnelModel fresnel;
    Color3 f0;
    float ior;
    Color3 eta, k;
    Vec3 normal, tangent;
    float sign;
};

// The GPU substitute's GGX roughness floor: the P-NDF has no intrinsic roughness (a one-texel footprint is a sum of
// clamped-Jacobian spikes, spec §2.3), LEAN of a flat footprint has Σ = 0, and GGX needs α > 0.
constexpr float kSubstituteAlpha = 0.02f;

NodeParams<Params> declare() {
    NodeParams<Params> l;
    l.c3("weight", &Params::weight, Vec3(1.f), "tint / layer weight").range(0.f, 1.f).soft(0.f, 1.f).hard(0.f, 1e6f)
        .str("normal_map", "tangent-space normal map, colour = (n + 1)/2, read as raw data (relative to the scene file), any "
                           "size; or 'generate:<kind>:<size>:<seed>' for a core/texture/normal_map_gen map")
        .choice("convention", &Params::convention, "green channel: opengl = +Y up, directx = +Y down").uniform()
        .v2("uv", &Params::uv, Vec2(0.f), "texture coordinates").range(0.f, 1.f).bind(GeomBinding::UV)
        .v2("duvdx", &Params::duvdx, Vec2(0.f), "footprint d(uv)/dx: one pixel step at any spp").range(-0.01f, 0.01f).bind(GeomBinding::PixelDUVDX)
        .v2("duvdy", &Params::duvdy, Vec2(0.f), "footprint d(uv)/dy: one pixel step at any spp").range(-0.01f, 0.01f).bind(GeomBinding::PixelDUVDY)
        .f("uv_scale", &Params::uvScale, 1.f, "tiles: the map repeats uv_scale times per uv unit").range(0.5f, 16.f).hard(1e-3f, 1e6f)
        .f("footprint_scale", &Params::footprintScale, 2.f,
           "k: the kernel half-width is k (|du/dx| + |du/dy|)/2 in texels, clamped to [1, 128] (spec §1); 2 = one pixel "
           "each side").range(0.5f, 8.f).hard(1e-3f, 1e6f)
        .choice("kernel", &Params::kernel, "footprint kernel: gaussian (std = half-width/3), box or disk").uniform()

        .f("cluster_threshold", &Params::clusterThreshold, float(kDefaultClusterThreshold),
           "eps_c of the cluster cut (spec §3.2, true fit residual); 0 = exact").range(0.f, 0.01f).hard(0.f, 1e6f).uniform()
        .f("jacobian_clamp", &Params::jacobianClamp, float(kDefaultJacobianClamp),
           "eps_J: normal triangles with |J| below it become the equilateral triangle of |J| = eps_J (spec §2.3)")
        .range(1e-8f, 1e-4f).hard(1e-12f, 1e-2f).uniform()
        .choice("masking", &Params::masking, "shadowing-masking: ggx_fit (per-texel GGX fit of the grazing projected "
                                             "area, spec §4.2) or analytic (exact projected area of the footprint, §4.1)").uniform();
    fresnelPorts(l, Vec3(0.95f));
    l.n3("normal", &Params::normal, Vec3(0, 0, 1), "shading normal of the unperturbed surface").bind(GeomBinding::N)
        .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent (+u)").bind(GeomBinding::T)
        .f("sign", &Params::sign, 1.f, "bitangent sign (+v = sign N x T)").range(-1.f, 1.f).bind(GeomBinding::TSign)
        .choice("footprint_centre", &Params::footprintCentre,
                "where the kernel is centred: sample (each sample's uv: the kernel is convolved with the pixel "
                "filter) or pixel (the pixel centre's uv, from the sample's offset: every sample of a pixel sees one "
                "footprint, so with kernel box and k = 1 the pixel converges to the box-filtered surface)").uniform();
    return l;
}
const NodeParams<Params> kParams = declare();
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "the glint closure");

struct Prepared {
    std::shared_ptr<const PndfManifold> manifold;
    std::shared_ptr<const PndfGgxFit> ggxFit;  // masking = ggx_fit
    // The GPU substitute's LEAN pyramid, built on first use (GLSL export, the CPU twin): a CPU render never needs it.
    NormalMapSource source;
    mutable std::once_flag leanOnce;
    mutable std::shared_ptr<const LeanPyramid> lean;
    const LeanPyramid& leanPyramid() const {
        std::call_once(leanOnce, [&] { lean = sharedLeanPyramid(source.encoded, source.width, source.height, source.channels); });
        return *lean;
    }
};

// One GGX masking fit per manifold in the process (materials sharing a map share its manifold through pndf_cache.h, and
// then its fit: 1-2 s to build at 1024²). Keyed by the manifold's address, checked against its owner so that an
// address reused after the manifold died never hands out a stale fit.
std::shared_ptr<const PndfGgxFit> sharedGgxFit(const std::shared_ptr<const PndfManifold>& manifold) {
    struct Entry {
        std::weak_ptr<const PndfManifold> manifold;
        std::weak_ptr<const PndfGgxFit> fit;
    };
    static std::mutex mutex;
    static std::map<const PndfManifold*, Entry> cache;
    std::lock_guard<std::mutex> lock(mutex);
    Entry& e = cache[manifold.get()];
    if (e.manifold.lock() == manifold)
        if (auto fit = e.fit.lock()) return fit;
    auto fit = std::make_shared<const PndfGgxFit>(*manifold);
    e = {manifold, fit};
    return fit;
}

std::shared_ptr<const void> prepare(const PrepareContext& pc) {
    auto d = std::make_shared<Prepared>();
    const bool directx = pc.str("convention") == "directx";
    NormalMapChecks checks;
    checks.requireUnitLength = true;
    checks.normalise = true;
    d->source = loadNormalMapSource(pc, "normal_map", "bsdf.glint_pndf", directx, checks);
    const double epsJ = std::clamp(double(pc.number("jacobian_clamp")), 1e-12, 1e-2);
    try {
        d->manifold = loadOrBuildManifold(d->source.normals, d->source.width, d->source.height, epsJ, defaultPndfCacheDir());
        if (pc.str("masking") == "ggx_fit") d->ggxFit = sharedGgxFit(d->manifold);
    } catch (const std::exception& e) {
        throw InputError(pc.pointer("normal_map"),
                         "bsdf.glint_pndf: cannot build the manifold of '" + d->source.name + "': " + e.what());
    }
    // The decoded normals are the manifold's now; the encoded texels stay for the GPU substitute.
    d->source.normals.clear();
    d->source.normals.shrink_to_fit();
    return d;
}

FootprintKernel kernelOf(PndfKernel k) {
    return k == PndfKernel::Box ? FootprintKernel::Box : k == PndfKernel::Disk ? FootprintKernel::Disk : FootprintKernel::Gaussian;
}

void cpu(EvalContext& c, const Instr& i) {
    const auto* d = static_cast<const Prepared*>(i.data);
    const Params p = kParams.read(c, i);
    const PndfManifold& m = *d->manifold;
    PndfLobeParams lp;
    lp.manifold = &m;
    // Spec §1: σ from the untiled uv's per-pixel differentials, in texels of N·tiles per uv unit, clamped to [1, 128].
    const double tiles = std::max(double(p.uvScale), 1e-6);
    const double k = std::max(double(p.footprintScale), 0.0);
    const double sigmaU = footprintHalfWidth(p.duvdx.x, p.duvdy.x, k, double(m.width()) * tiles);
    const double sigmaV = footprintHalfWidth(p.duvdx.y, p.duvdy.y, k, double(m.height()) * tiles);
    // The kernel's centre: the sample's uv, or the pixel centre's, one pixel step per unit of the sample's offset back.
    Vec2 centre = p.uv;
    if (p.footprintCentre == PndfFootprintCentre::Pixel && c.sp)
        centre -= p.duvdx * c.sp->pixelOffset.x + p.duvdy * c.sp->pixelOffset.y;
    lp.footprint = Footprint::fromUv(centre, tiles, m.width(), m.height(), sigmaU, sigmaV, kernelOf(p.kernel));
    lp.clusterThreshold = std::max(double(p.clusterThreshold), 0.0);
    lp.masking = p.masking == PndfMasking::Analytic ? MaskingModel::Analytic : MaskingModel::GgxFit;
    lp.ggxFit = d->ggxFit.get();
    if (lp.masking == MaskingModel::GgxFit && !lp.ggxFit) lp.masking = MaskingModel::Analytic;
    lp.fresnel = fresnelOf(p);
    lp.flipY = p.sign < 0.f;
    emitLobe(c, i, kBsdf, bsdfFrame(p.normal, p.tangent), p.weight, c.arena->make<PndfLobe>(lp));
}

// ---- GPU substitute ------------------------------------------------------------------------------------------------

// The LEAN footprint that has the P-NDF kernel's variance: texture.lean's anisotropic filter averages about one pixel
// step per derivative (a box of std |duv|/√12), the P-NDF kernel of half-width σ = k |duv|/2 has std σ/3 (Gaussian),
// σ/√3 (box) or σ/2 (disk); glint_pndf.glsl spc_pndf_lean_scale is the same.
float leanFootprintScale(PndfKernel kernel, float k) {
    const float sqrt12 = 3.46410162f;
    switch (kernel) {
        case PndfKernel::Box: return k;
        case PndfKernel::Disk: return k * sqrt12 / 4.f;
        case PndfKernel::Gaussian: break;
    }
    return k * sqrt12 / 6.f;
}

// The CPU twin of spc_bsdf_glint_pndf: texture.lean (anisotropic, repeat, full correlation) of the map over the scaled
// footprint, then bsdf.ggx_filtered with filter none, A = diag(α²) + 2Σ in the frame of the LEAN mean normal, Schlick
// Fresnel with F0 = F(0°) of the chosen model.
void cpuSubstitute(EvalContext& c, const Instr& i) {
    const auto* d = static_cast<const Prepared*>(i.data);
    const Params p = kParams.read(c, i);
    const float scale = leanFootprintScale(p.kernel, p.footprintScale) * p.uvScale;
    const LeanMoments mo = d->leanPyramid().lookup(p.uv * p.uvScale, p.duvdx * scale, p.duvdy * scale,
                                                   LeanFilter::Anisotropic, LeanWrap::Repeat, 16);
    const bool flip = (p.convention == NormalMapConvention::DirectX) != (p.sign < 0.f);
    const LeanStats st = leanStats(mo, 1.f, flip, false);
    const Frame f = bsdfFrame(p.normal, p.tangent);
    const Vec3 nt = st.meanNormal();
    const Vec3 nw = nt.x * f.t + nt.y * f.b + nt.z * f.n;
    const float l2 = glm::dot(nw, nw);
    const Frame lobeFrame = bsdfFrame(l2 > 0.f ? nw / std::sqrt(l2) : f.n, p.tangent);
    fggx::LobeSetup s;
    s.A = fggx::roughnessMatrix(Vec2(kSubstituteAlpha), Vec3(st.varX, st.varY, st.covXY));
    s.params.filter = fggx::Filter::None;
    auto* lobe = c.arena->make<fggx::FilteredGgxLobe>(s, Fresnel::schlick(fresnelOf(p).eval(1.f)));
    if (c.sp) lobe->setSamplingFromMirror(fggx::D3(lobeFrame.toLocal(c.sp->wo)));
    emitLobe(c, i, kBsdf, lobeFrame, p.weight, lobe);
}

ResourceImage momentTexels(const void* prepared) {
    return leanMomentImage(static_cast<const Prepared*>(prepared)->leanPyramid());
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("bsdf.glint_pndf",
                             "Position-normal manifold glints (Wu et al. 2024) of an explicit normal map of any size: "
                             "the exact P-NDF of the pixel footprint (the map triangulated into affine "
                             "position-normal triangles with Jacobian clamping, summed through a min-max quadtree and "
                             "a least-squares cluster hierarchy) as the microfacet D of a conductor or dielectric "
                             "reflection, sampled exactly for MIS, with separable Smith masking. The footprint is one "
                             "pixel step at any spp (the glints are a property of the image, like bsdf.glint). The "
                             "manifold is cached on disk by content hash ($SPECULA_CACHE_DIR, else "
                             "$XDG_CACHE_HOME/specula or ~/.cache/specula). Quad lights are sampled (no polygon "
                             "query).",
                             kParams, kOutputs, &cpu, kNeedsDerivatives);
    s.prepare = &prepare;
    s.gpuSubstitute = "LEAN-filtered GGX of the same normal map (texture.lean over a footprint of the P-NDF kernel's "
                      "variance, then bsdf.ggx_filtered with filter none, alpha floor 0.02, Schlick F0 = F(0 deg)): the "
                      "same mean and spread of normals, without the individual glints.";
    s.gpuSubstituteCpu = &cpuSubstitute;
    s.glslLibraries = {"shared/ltc.glsl", "shared/fresnel_f0.glsl", "shared/ggx_microfacet.glsl", "texture/lean/lean.glsl",
                       "bsdf/ggx_filtered/ggx_filtered.glsl"};
    s.resources = {{"moments", "sampler2D", ResourceSpec::Kind::DerivedImage,
                    "LEAN slope-moment pyramid of the normal map (the GPU substitute), built on first export",
                    &momentTexels, "normal_map", ""},
                   ltc::matrixResource(), ltc::amplitudeResource(), ltc::anisotropicResource()};
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
