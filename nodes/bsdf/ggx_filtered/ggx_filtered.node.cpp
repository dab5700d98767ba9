// bsdf.ggx_filtered: GGX reflection whose roughness matrix is widened per pixel from screen-space derivatives
// (NDF filtering for geometric specular anti-aliasing, Tokuyoshi & Kaplanyan 2021; spec shared/specs/filtered-ggx.md).
// Math and lobe: filtered_ggx.h. The roughness matrix is A = diag(α_x², α_y²) + 2Σ (Σ: e.g. LEAN slope covariance),
// τ = det A (A.4). Derivatives: "analytic" from the ShadingPoint's ray differentials (§5.1), "quad" from the renderer's
// 2×2-quad emulation (render setting "derivatives": "quad", §5.2) and dFdxFine/dFdyFine in GLSL.
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/shared/ltc_gpu.h"
#include "core/render/shading.h"
#include "nodes/bsdf/ggx_filtered/filtered_ggx.h"

namespace specula::nodes {
namespace {

using namespace specula::fggx;

// Port order of the enum inputs (the first value is the default); filterOf maps to filtered_ggx.h's Filter.
enum class FilterChoice : int { ProjectedApprox, None, Slope, Projected, IsoMax, IsoSum, IsoMean, IsoRect };
enum class KernelChoice : int { AxisAligned, Full };
enum class DerivativeSource : int { Analytic, Quad };

}  // namespace
}  // namespace specula::nodes

SPECULA_ENUM(specula::nodes::FilterChoice, "SPC_GGXF_FILTER", "projected_approx", "none", "slope", "projected", "iso_max",
             "iso_sum", "iso_mean", "iso_rect");
SPECULA_ENUM(specula::nodes::KernelChoice, "SPC_GGXF_KERNEL", "axis_aligned", "full");
SPECULA_ENUM(specula::nodes::DerivativeSource, "SPC_DERIVATIVES", "analytic", "quad");

namespace specula::nodes {
namespace {

struct Params {
    Color3 weight;
    Vec2 alpha;
    Vec3 covariance;
    FilterChoice filter;
    KernelChoice kernel;
    float sigma2, kappa;
    DerivativeSource derivatives;
    float derivativeScale;
    Color3 f0;
    Vec3 normal, tangent;
    Vec3 dndx, dndy;
};

const NodeParams<Params> kParams = NodeParams<Params>()
    .c3("weight", &Params::weight, Vec3(1.f), "tint / layer weight").range(0.f, 1.f).soft(0.f, 1.f).hard(0.f, 1e6f)
    .v2("alpha", &Params::alpha, Vec2(0.05f), "unfiltered GGX α along tangent (x) and bitangent (y)").range(0.02f, 0.9f).hard(0.f, 1.f)
    .v3("covariance", &Params::covariance, Vec3(0.f), "slope covariance Σ as (var_x, var_y, cov_xy), added as A + 2Σ (texture.lean covariance)").range(0.f, 0.01f)
    .choice("filter", &Params::filter, "NDF filter (spec §3): projected_approx = TK21 Eq. 9 (Listing 2 reading (a)); slope = K16 (reading (b))")
    .choice("kernel", &Params::kernel, "half-vector filters: bounding rectangle with κ clamp, or full Σ")
    .f("sigma2", &Params::sigma2, float(kDefaultSigma2), "pixel-filter variance σ² (0.25 reproduces K16/TK19)").range(0.05f, 0.5f).hard(0.f, 1e3f)
    .f("kappa", &Params::kappa, float(kDefaultKappa), "kernel clamp κ (axis-aligned and isotropic filters)").range(0.f, 1.f).hard(0.f, 1e3f)
    .choice("derivatives", &Params::derivatives, "analytic: ray differentials; quad: 2×2 finite differences (dFdxFine)").uniform()
    .f("derivative_scale", &Params::derivativeScale, 1.f, "multiplies every screen derivative").range(0.f, 2.f).hard(0.f, 1e3f)
    .c3("f0", &Params::f0, Vec3(0.04f), "Schlick F0 (1 = no Fresnel)").range(0.f, 1.f).hard(0.f, 1.f)
    .n3("normal", &Params::normal, Vec3(0, 0, 1), "shading normal").bind(GeomBinding::N)
    .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent: direction of α_x").bind(GeomBinding::T)
    .v3("dndx", &Params::dndx, Vec3(0.f), "screen derivative of the normal (connect texture.normal_map dndx)").range(-0.05f, 0.05f).bind(GeomBinding::DNDX)
    .v3("dndy", &Params::dndy, Vec3(0.f), "screen derivative of the normal along y").range(-0.05f, 0.05f).bind(GeomBinding::DNDY);
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "the specular closure");
const OutPort<Vec2> kFilteredAlpha =
    kOutputs.add<Vec2>("filtered_alpha", TypeDesc::Vec2, "sqrt of diag(Ā) at the mirror configuration (debug)");

Filter filterOf(FilterChoice f) {
    switch (f) {
        case FilterChoice::ProjectedApprox: return Filter::ProjectedApprox;
        case FilterChoice::None: return Filter::None;
        case FilterChoice::Slope: return Filter::Slope;
        case FilterChoice::Projected: return Filter::Projected;
        case FilterChoice::IsoMax: return Filter::IsoMax;
        case FilterChoice::IsoSum: return Filter::IsoSum;
        case FilterChoice::IsoMean: return Filter::IsoMean;
        case FilterChoice::IsoRect: return Filter::IsoRect;
    }
    return Filter::None;
}

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    LobeSetup s;
    s.A = roughnessMatrix(p.alpha, p.covariance);
    s.params.filter = filterOf(p.filter);
    s.params.kernel = p.kernel == KernelChoice::AxisAligned ? Kernel::AxisAligned : Kernel::Full;
    s.params.sigma2 = std::max(double(p.sigma2), 0.0);
    s.params.kappa = std::max(double(p.kappa), 0.0);
    const bool quad = p.derivatives == DerivativeSource::Quad;
    const double scale = p.derivativeScale;
    Frame f = bsdfFrame(p.normal, p.tangent);
    auto loc = [&](const Vec3& v) { return D3(f.toLocal(v)); };
    const ShadingPoint* sp = c.sp;
    if (sp && sp->hasDifferentials) {
        s.diff.valid = true;
        s.diff.dwo[0] = loc(sp->dwodx) * scale, s.diff.dwo[1] = loc(sp->dwody) * scale;
        s.diff.dn[0] = loc(p.dndx) * scale, s.diff.dn[1] = loc(p.dndy) * scale;
        s.diff.dp[0] = loc(sp->dpdx) * scale, s.diff.dp[1] = loc(sp->dpdy) * scale;
    }
    if (sp && quad) {
        for (int k = 0; k < 2; ++k) {
            const ShadingPoint::QuadNeighbour& q = sp->quad[k];
            if (!q.valid) continue;
            s.quad = true;
            QuadNeighbour& nb = s.nb[k];
            nb.valid = true;
            nb.sign = q.sign * scale;
            nb.dp = loc(q.p - sp->p), nb.wo = loc(q.wo);
            nb.t = loc(q.frame.t), nb.b = loc(q.frame.b), nb.n = loc(q.frame.n);
        }
    }
    auto* lobe = sp ? c.arena->make<FilteredGgxLobe>(s, Fresnel::schlick(p.f0), Color3(1.f), loc(sp->wo))
                    : c.arena->make<FilteredGgxLobe>(s, Fresnel::schlick(p.f0));
    const Sym2& As = lobe->samplingMatrix();
    set(c, i, kFilteredAlpha, Vec2(float(std::sqrt(As.a)), float(std::sqrt(As.d))));
    emitLobe(c, i, kBsdf, f, p.weight, lobe);
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("bsdf.ggx_filtered",
                             "GGX reflection with NDF filtering for specular anti-aliasing (Tokuyoshi & Kaplanyan "
                             "2021): roughness matrix, height-correlated Smith G2, slope-space (K16), projected-space "
                             "exact/approximate and isotropic filters. Quad lights in closed form (polygon queries): "
                             "the LTC of its sampling matrix.",
                             kParams, kOutputs, &cpu, kNeedsDerivatives);
    s.glslLibraries = {"shared/ltc.glsl", "shared/ggx_microfacet.glsl"};
    // Polygon queries (LTC quad lights with the sampling matrix): the isotropic/anisotropic GGX fits, mag/fres/sphere.
    s.resources = {ltc::matrixResource(), ltc::amplitudeResource(), ltc::anisotropicResource()};
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
