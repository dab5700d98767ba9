// bsdf.glint: procedural glints (Chermain et al. 2020) with geometric glint anti-aliasing and slope correlation
// (Chermain et al. 2021), spec glint-brdf.md §3 S0-S7; CPU: GlintLobe (glint_bsdf.h), GLSL: glint.glsl.
//
// GGAA derivatives: with quad neighbours (render "derivatives": "quad") the half vector is differenced against the
// partner pixels in their own normal-mapped frames (as dFdx on a GPU); otherwise dh is formed analytically from the
// rotation of the BSDF frame (dN/dx on T, B) plus, on the CPU only, dwo/dx and, for point lights, dwi/dx from
// the query's light distance. The GLSL uses the frame rotation only (SpeculaShadingInputs carries no dwo or light distance). Fresnel: Schlick at wo.h with the 'f0' input (f0 = 1 gives the authors' F = 1).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/bsdf/glint/glint_bsdf.h"

namespace specula::nodes {
namespace {

using namespace specula::glint;

enum In {
    kWeight, kSigmaX, kSigmaY, kRho, kLogDensity, kRelArea, kJitter, kMaxAniso, kGgaa, kKernelScale, kDeriv, kF0,
    kLeanMean, kLeanCov, kNormal, kTangent, kUv, kDuvdx, kDuvdy, kUvScale, kInputCount
};

void cpu(EvalContext& c, const Instr& i) {
    GlintParams p;
    p.sigmaX = inF(c, i, kSigmaX);
    p.sigmaY = inF(c, i, kSigmaY);
    p.rho = std::clamp(inF(c, i, kRho), -0.99f, 0.99f);
    p.logDensity = inF(c, i, kLogDensity);
    p.relArea = inF(c, i, kRelArea);
    p.jitter = inF(c, i, kJitter);
    p.maxAniso = std::max(inF(c, i, kMaxAniso), 1.f);
    p.ggaa = inEnum(i, kGgaa) == 0;
    p.kernelScale = inF(c, i, kKernelScale);
    p.mode = inEnum(i, kDeriv) == 1 ? DerivMode::HalfSlope : DerivMode::ProjectedHalf;
    p.sigmaX = std::clamp(p.sigmaX, 0.01f, 1.f);
    p.sigmaY = std::clamp(p.sigmaY, 0.01f, 1.f);
    Frame f = bsdfFrame(inV3(c, i, kNormal), inV3(c, i, kTangent));
    const ShadingPoint* sp = c.sp;
    if (leanCombine(p.sigmaX, p.sigmaY, p.rho, inV3(c, i, kLeanCov))) {
        Vec3 wo = sp ? sp->wo : f.n;
        f = bsdfFrame(leanNormal(f.t, f.b, f.n, inV2(c, i, kLeanMean), wo), f.t);
    }
    const float scale = inF(c, i, kUvScale);
    GlintEvalInputs in;
    in.uv = inV2(c, i, kUv) * scale;
    in.duvdx = inV2(c, i, kDuvdx) * scale;
    in.duvdy = inV2(c, i, kDuvdy) * scale;
    if (sp) {
        in.diff.dnx = Vec2(glm::dot(f.t, sp->dndx), glm::dot(f.b, sp->dndx));
        in.diff.dny = Vec2(glm::dot(f.t, sp->dndy), glm::dot(f.b, sp->dndy));
        in.diff.dwox = f.toLocal(sp->dwodx);
        in.diff.dwoy = f.toLocal(sp->dwody);
        in.diff.dpx = f.toLocal(sp->dpdx);
        in.diff.dpy = f.toLocal(sp->dpdy);
        for (int k = 0; k < 2; ++k) {
            const ShadingPoint::QuadNeighbour& q = sp->quad[k];
            if (!q.valid) continue;
            GlintNeighbour& nb = in.diff.nb[k];
            nb.valid = true;
            nb.sign = q.sign;
            nb.dp = f.toLocal(q.p - sp->p);
            nb.wo = f.toLocal(q.wo);
            nb.t = f.toLocal(q.frame.t), nb.b = f.toLocal(q.frame.b), nb.n = f.toLocal(q.frame.n);
        }
    }
    const Fresnel fr = Fresnel::schlick(inV3(c, i, kF0));
    emitLobe(c, i, 0, f, inV3(c, i, kWeight), c.arena->make<GlintLobe>(Dictionary::instance(), p, in, fr));
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "bsdf.glint";
    s.category = "bsdf";
    s.doc = "Procedural glints (Chermain et al. 2020) with geometric glint anti-aliasing and slope correlation "
            "(Chermain et al. 2021); converges to Cook-Torrance with a correlated Beckmann NDF as density grows.";
    s.inputs = {
        std::move(PortSpec::c3("weight", Vec3(1.f), "tint / layer weight")).range(0.f, 1.f),
        std::move(PortSpec::f("sigma_x", 0.16f, "RMS slope of the converged lobe along the tangent (alpha = sqrt(2) sigma)")).range(0.05f, 1.f),
        std::move(PortSpec::f("sigma_y", 0.16f, "RMS slope along the bitangent")).range(0.05f, 1.f),
        std::move(PortSpec::f("rho", 0.f, "slope correlation (C21 Eq. 18), clamped to +-0.99")).range(-0.9f, 0.9f),
        std::move(PortSpec::f("log_density", 15.f, "lambda = ln(microfacets per unit UV area)")).range(5.f, 40.f),
        std::move(PortSpec::f("relative_area", 1.f, "A: probability that a cell holds microfacets")).range(0.05f, 1.f),
        std::move(PortSpec::f("density_jitter", 2.f, "zeta: std of the per-cell dictionary-LOD jitter")).range(0.f, 3.f),
        std::move(PortSpec::f("max_anisotropy", 8.f, "largest allowed footprint anisotropy")).range(1.f, 16.f),
        PortSpec::choice("ggaa", {"on", "off"}, "geometric glint anti-aliasing (C21 §4.2)"),
        std::move(PortSpec::f("kernel_scale", 0.5f, "s_K: GGAA kernel scale (C21 Eq. 19); 1 = conservative")).range(0.f, 2.f),
        PortSpec::choice("derivative", {"projected_half", "half_slope"},
                         "GGAA derivative: projected half vector (C21 Eq. 21) or half slope (Eq. 20)"),
        std::move(PortSpec::c3("f0", Vec3(1.f), "Fresnel: Schlick F0 at wo.h (1 = no Fresnel)")).range(0.f, 1.f),
        std::move(PortSpec::v2("lean_mean", Vec2(0.f), "LEAN mean slope (E[x], E[y]) of the normal map (spec S6.4)")).range(-0.3f, 0.3f),
        std::move(PortSpec::v3("lean_cov", Vec3(0.f), "LEAN slope covariance (var_x, var_y, cov_xy); 0 = no LEAN")).range(0.f, 0.05f),
        std::move(PortSpec::n3("normal", Vec3(0, 0, 1), "shading normal")).bind(GeomBinding::N),
        std::move(PortSpec::v3("tangent", Vec3(1, 0, 0), "tangent: direction of sigma_x")).bind(GeomBinding::T),
        std::move(PortSpec::v2("uv", Vec2(0.f), "texture coordinates of the cell grid")).range(0.f, 1.f).bind(GeomBinding::UV),
        std::move(PortSpec::v2("duvdx", Vec2(0.f), "footprint: d(uv)/dx")).range(-0.01f, 0.01f).bind(GeomBinding::DUVDX),
        std::move(PortSpec::v2("duvdy", Vec2(0.f), "footprint: d(uv)/dy")).range(-0.01f, 0.01f).bind(GeomBinding::DUVDY),
        std::move(PortSpec::f("uv_scale", 1.f, "multiplies uv and its derivatives")).range(0.5f, 4.f)};
    s.outputs = {PortSpec::out("bsdf", TypeDesc::Closure, "the glinty specular closure")};
    s.flags = kGlslShading | kGlslDirections | kNeedsDerivatives;
    s.cpu = &cpu;
    s.glslFunction = "spc_bsdf_glint";
    s.glslFile = "bsdf/glint/glint.glsl";
    s.parityTolerance = 0.12f;
    s.parityNote = "GGAA off (textureLod, level 0): measured 2.1e-5 on llvmpipe. GGAA on: textureGrad's MIP level is "
                   "computed by the GL implementation (llvmpipe's LOD approximation) while the CPU uses the exact "
                   "log2, so the blend between two MIPs differs: measured 9.4e-2 worst case over 1024 samples";
    r.add(std::move(s));
}
static_assert(kInputCount == 20, "port list and enum must agree");

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
