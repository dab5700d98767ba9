// bsdf.glint: procedural glints (Chermain et al. 2020) with geometric glint anti-aliasing and slope correlation
// (Chermain et al. 2021), spec glint-brdf.md §3 S0-S7; CPU: GlintLobe (glint_bsdf.h), GLSL: glint.glsl.
//
// GGAA derivatives (port 'derivatives'): "quad" (default) differences the half vector against the 2x2-quad partner
// pixels in their own (normal-mapped, LEAN) frames: dFdxFine/dFdyFine of the local h in GLSL, the partners of the
// renderer's quad emulation on the CPU (render "derivatives": "quad"; without partners, e.g. with ray differentials,
// the CPU falls back to the analytic form per axis). "analytic" forms dh from the rotation of the BSDF frame (the
// dndx/dndy ports on T, B) plus dwo/dx and, for point lights, dwi/dx from the query's light distance, on both sides.
// Fresnel (spec glint-brdf.md §1): the shared fresnelPorts() choice evaluated per microfacet at wo.h, Schlick by default
// with f0 = 1, which is the authors' F = 1 (scenes written before the conductor ports keep their look); 'base_color'
// multiplies it (the artist tint of the flakes), so f·cos = weight · base_color · F(wo.h) · G D / (4 wo.z).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/bsdf/glint/glint_bsdf.h"
#include "nodes/shared/bsdf_ports.h"

namespace specula::nodes {
namespace {

using namespace specula::glint;

enum class GgaaSwitch : int { On, Off };
enum class GgaaDerivative : int { ProjectedHalf, HalfSlope };
enum class GlintQuadLights : int { Sampled, Integrated };
enum class GlintDerivativeSource : int { Quad, Analytic };
enum class GlintFootprintCentre : int { Sample, Pixel };

}  // namespace
}  // namespace specula::nodes

SPECULA_ENUM(specula::nodes::GgaaSwitch, "SPC_GLINT_GGAA", "on", "off");
SPECULA_ENUM(specula::nodes::GgaaDerivative, "SPC_GLINT_DERIVATIVE", "projected_half", "half_slope");
SPECULA_ENUM(specula::nodes::GlintQuadLights, "SPC_GLINT_QUAD_LIGHTS", "sampled", "integrated");
SPECULA_ENUM(specula::nodes::GlintDerivativeSource, "SPC_GLINT_DERIVATIVES", "quad", "analytic");
SPECULA_ENUM(specula::nodes::GlintFootprintCentre, "SPC_GLINT_FOOTPRINT_CENTRE", "sample", "pixel");

namespace specula::nodes {
namespace {

struct Params {
    Color3 weight;
    float sigmaX, sigmaY, rho, logDensity, relArea, jitter, maxAniso;
    GgaaSwitch ggaa;
    float kernelScale;
    GgaaDerivative derivative;
    GlintDerivativeSource derivatives;
    GlintQuadLights quadLights;
    FresnelModel fresnel;
    Color3 f0;
    float ior;
    Color3 eta, k;
    Color3 baseColor;
    Vec2 leanMean;
    Vec3 leanCov;
    Vec3 normal, tangent;
    Vec2 uv, duvdx, duvdy;
    float uvScale;
    Vec3 dndx, dndy;
    GlintFootprintCentre footprintCentre;
    float flakeSize, flakeRoughness;
};

NodeParams<Params> declare() {
    NodeParams<Params> l;
    l.c3("weight", &Params::weight, Vec3(1.f), "tint / layer weight").range(0.f, 1.f).soft(0.f, 1.f).hard(0.f, 1e6f)
    .f("sigma_x", &Params::sigmaX, 0.16f, "RMS slope of the converged lobe along the tangent (alpha = sqrt(2) sigma)").range(0.05f, 1.f).hard(0.f, 10.f)
    .f("sigma_y", &Params::sigmaY, 0.16f, "RMS slope along the bitangent").range(0.05f, 1.f).hard(0.f, 10.f)
    .f("rho", &Params::rho, 0.f, "slope correlation (C21 Eq. 18), clamped to +-0.99").range(-0.9f, 0.9f).hard(-1.f, 1.f)
    .f("log_density", &Params::logDensity, 15.f, "lambda = ln(microfacets per unit UV area)").range(5.f, 40.f)
    .f("relative_area", &Params::relArea, 1.f, "A: probability that a cell holds microfacets").range(0.05f, 1.f).hard(0.f, 1.f)
    .f("density_jitter", &Params::jitter, 2.f, "zeta: std of the per-cell dictionary-LOD jitter").range(0.f, 3.f).hard(0.f, 100.f)
    .f("max_anisotropy", &Params::maxAniso, 8.f, "largest allowed footprint anisotropy").range(1.f, 16.f).hard(1.f, 1e6f)
    .choice("ggaa", &Params::ggaa, "geometric glint anti-aliasing (C21 §4.2)")
    .f("kernel_scale", &Params::kernelScale, 0.5f, "s_K: GGAA kernel scale (C21 Eq. 19); 1 = conservative").range(0.f, 2.f).hard(0.f, 1e3f)
    .choice("derivative", &Params::derivative, "GGAA derivative: projected half vector (C21 Eq. 21) or half slope (Eq. 20)")
    .choice("quad_lights", &Params::quadLights, "with render.area_lights 'ltc': sampled (the integrator samples the light, "
            "cheapest at equal time with jittered pixels) or integrated (each glint cell's distribution integrated over "
            "the light's half-vector region: noise-free lighting, 10-30x the cost per sample; CPU only)").uniform();
    // Default Schlick with F0 = 1: F = 1, the look of scenes made before the conductor ports.
    fresnelPorts(l, Vec3(1.f));
    l.c3("base_color", &Params::baseColor, Vec3(1.f), "tint of the flakes: multiplies the Fresnel term").range(0.f, 1.f).hard(0.f, 1e6f)
    .v2("lean_mean", &Params::leanMean, Vec2(0.f), "LEAN mean slope (E[x], E[y]) of the normal map (spec S6.4)").range(-0.3f, 0.3f)
    .v3("lean_cov", &Params::leanCov, Vec3(0.f), "LEAN slope covariance (var_x, var_y, cov_xy); 0 = no LEAN").range(0.f, 0.05f)
    .n3("normal", &Params::normal, Vec3(0, 0, 1), "shading normal").bind(GeomBinding::N)
    .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent: direction of sigma_x").bind(GeomBinding::T)
    .v2("uv", &Params::uv, Vec2(0.f), "texture coordinates of the cell grid").range(0.f, 1.f).bind(GeomBinding::UV)
    .v2("duvdx", &Params::duvdx, Vec2(0.f), "glint LOD footprint d(uv)/dx: one pixel step at any spp").range(-0.01f, 0.01f).bind(GeomBinding::PixelDUVDX)
    .v2("duvdy", &Params::duvdy, Vec2(0.f), "glint LOD footprint d(uv)/dy: one pixel step at any spp").range(-0.01f, 0.01f).bind(GeomBinding::PixelDUVDY)
    .f("uv_scale", &Params::uvScale, 1.f, "multiplies uv and its derivatives").range(0.5f, 4.f)
    .v3("dndx", &Params::dndx, Vec3(0.f), "per-pixel derivative of the normal (connect texture.normal_map dndx)").range(-0.05f, 0.05f).bind(GeomBinding::PixelDNDX)
    .v3("dndy", &Params::dndy, Vec3(0.f), "per-pixel derivative of the normal along y").range(-0.05f, 0.05f).bind(GeomBinding::PixelDNDY)
    // Last in the list: ports added later go after the documented ones (the conformance grid and docs keep their order).
    .choice("derivatives", &Params::derivatives, "where the GGAA derivative comes from: quad (2x2 finite differences of "
            "the half vector in each pixel's own frame, dFdxFine on a GPU; C21 §6.1) or analytic (chain rule from the "
            "dndx/dndy ports, the view and the light)").uniform()
    .choice("footprint_centre", &Params::footprintCentre, "where the LOD footprint is centred: sample (each sample's "
            "uv: the pixel's glints are the footprint convolved with the pixel filter, and which cells a pixel sees "
            "depends on its samples' positions) or pixel (the pixel centre's uv and normal, from the sample's offset "
            "and the duvdx/dndx ports: every sample of a pixel counts the same cells around the same half vectors, "
            "so the sparkle pattern comes from the surface, not the sampler; what a GPU fragment does)").uniform()
    .f("flake_size", &Params::flakeSize, 0.f, "size of a flake in the cell grid's units (uv x uv_scale); 0 = off. Where "
       "a pixel spans less than a flake, each flake is a flat platelet of its own slope (drawn from the lobe), seen as "
       "a separate sparkle; from one flake per pixel on, the glints count one microfacet per flake area (log_density "
       "= ln(1/flake_size^2) replaces the port)").range(0.f, 0.01f).hard(0.f, 1e3f)
    .f("flake_roughness", &Params::flakeRoughness, 0.04f, "RMS slope of each flake's own lobe (kept below 0.89 of the "
       "lobe's smallest RMS slope): how sharply a flake mirrors the light").range(0.005f, 0.1f).hard(0.f, 1.f);
    return l;
}
const NodeParams<Params> kParams = declare();
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf = kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "the glinty specular closure");

// gpuTwin: what spc_bsdf_glint computes, for the raster integrator (GraphMaterial's gpuSubstitutes): the GLSL does
// not integrate quad lights (no polygon answer: the host evaluates the lobe at the light's centre), so neither does
// the twin, whatever quad_lights says.
void shadeGlint(EvalContext& c, const Instr& i, bool gpuTwin) {
    const Params in = kParams.read(c, i);
    GlintParams p;
    p.sigmaX = in.sigmaX;
    p.sigmaY = in.sigmaY;
    p.rho = std::clamp(in.rho, -0.99f, 0.99f);
    p.logDensity = in.logDensity;
    p.relArea = in.relArea;
    p.jitter = in.jitter;
    p.maxAniso = std::max(in.maxAniso, 1.f);
    p.ggaa = in.ggaa == GgaaSwitch::On;
    p.kernelScale = in.kernelScale;
    p.mode = in.derivative == GgaaDerivative::HalfSlope ? DerivMode::HalfSlope : DerivMode::ProjectedHalf;
    p.integrateQuadLights = in.quadLights == GlintQuadLights::Integrated && !gpuTwin;
    p.sigmaX = std::clamp(p.sigmaX, 0.01f, 1.f);
    p.sigmaY = std::clamp(p.sigmaY, 0.01f, 1.f);
    p.flakeSize = in.flakeSize > 0.f && std::isfinite(in.flakeSize) ? in.flakeSize : 0.f;
    p.flakeRoughness = in.flakeRoughness;
    if (p.flakeSize > 0.f) p.logDensity = flakeLogDensity(p.flakeSize);
    const ShadingPoint* sp = c.sp;
    // footprint_centre "pixel": the lobe is the pixel centre's, its uv footprint and its frame both moved back by the
    // sample's offset from the centre (ShadingPoint::pixelOffset; 0 off camera hits and on a GPU, where a fragment is
    // at its pixel centre) to first order: uv - duv·offset, n - dn·offset. Every sample of a pixel then counts the same
    // cells around the same half vectors, and only the light's samples and the pixel's coverage differ between seeds.
    const Vec2 offset = in.footprintCentre == GlintFootprintCentre::Pixel && sp ? sp->pixelOffset : Vec2(0.f);
    Frame f = bsdfFrame(in.normal - in.dndx * offset.x - in.dndy * offset.y, in.tangent);
    if (leanCombine(p.sigmaX, p.sigmaY, p.rho, in.leanCov)) {
        Vec3 wo = sp ? sp->wo : f.n;
        f = bsdfFrame(leanNormal(f.t, f.b, f.n, in.leanMean, wo), f.t);
    }
    GlintEvalInputs ev;
    ev.uv = (in.uv - in.duvdx * offset.x - in.duvdy * offset.y) * in.uvScale;
    ev.duvdx = in.duvdx * in.uvScale;
    ev.duvdy = in.duvdy * in.uvScale;
    if (sp) {
        ev.diff.dnx = Vec2(glm::dot(f.t, in.dndx), glm::dot(f.b, in.dndx));
        ev.diff.dny = Vec2(glm::dot(f.t, in.dndy), glm::dot(f.b, in.dndy));
        // GGAA differentiates over one whole pixel, like the LOD footprint (the ports above bind pixel steps).
        ev.diff.dwox = f.toLocal(sp->dwodx / sp->differentialScale.x);
        ev.diff.dwoy = f.toLocal(sp->dwody / sp->differentialScale.y);
        ev.diff.dpx = f.toLocal(sp->dpdx / sp->differentialScale.x);
        ev.diff.dpy = f.toLocal(sp->dpdy / sp->differentialScale.y);
        for (int k = 0; k < 2 && in.derivatives == GlintDerivativeSource::Quad; ++k) {
            const ShadingPoint::QuadNeighbour& q = sp->quad[k];
            if (!q.valid) continue;
            GlintNeighbour& nb = ev.diff.nb[k];
            nb.valid = true;
            nb.sign = q.sign;
            nb.dp = f.toLocal(q.p - sp->p);
            nb.wo = f.toLocal(q.wo);
            nb.t = f.toLocal(q.frame.t), nb.b = f.toLocal(q.frame.b), nb.n = f.toLocal(q.frame.n);
        }
    }
    // The lobe evaluates F at wo.h per query; the flake tint is a constant factor, so it joins the lobe weight.
    const Fresnel fr = fresnelOf(in);
    emitLobe(c, i, kBsdf, f, in.weight * in.baseColor, c.arena->make<GlintLobe>(Dictionary::instance(), p, ev, fr));
}

void cpu(EvalContext& c, const Instr& i) { shadeGlint(c, i, false); }
void cpuGpuTwin(EvalContext& c, const Instr& i) { shadeGlint(c, i, true); }

// The dictionary the GLSL reads (glint.glsl header): RGBA32F 1D array, 64 texels x 1024 layers, our box MIP chain,
// trilinear, mirrored repeat on s.
ResourceImage dictionaryTexels(const void*) {
    const Dictionary& d = Dictionary::instance();
    ResourceImage r;
    for (int m = 0; m < kMips; ++m) {
        ResourceImage::Level lv;
        lv.width = mipRes(m);
        lv.height = Dictionary::kGpuLayers;
        lv.rgba = d.gpuMipRgba(m);
        r.levels.push_back(std::move(lv));
    }
    r.wrapS = "mirrored_repeat";
    r.wrapT = "clamp_to_edge";
    return r;
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("bsdf.glint",
                             "Procedural glints (Chermain et al. 2020) with geometric glint anti-aliasing and slope "
                             "correlation (Chermain et al. 2021); converges to Cook-Torrance with a correlated "
                             "Beckmann NDF as density grows. The LOD footprint and the GGAA derivatives are one pixel "
                             "step at any spp (C21's real-time setting): the glints are a property of the image, so "
                             "more samples average the same sparkles instead of revealing finer ones. Quad lights in "
                             "closed form on the CPU (polygon queries, render.area_lights \"ltc\"): each EWA cell's "
                             "slope distribution integrated over the light's half-slope region, at the GGAA MIPs of "
                             "the light's centre (glint_area.h). The GLSL function does not answer polygon queries: "
                             "it returns partial = true and the host samples the light. flake_size > 0: explicit flakes where a "
                             "pixel spans less than a flake (a Voronoi platelet per flake, its slope drawn from the "
                             "lobe, glint_flakes.h), handing over to the counting from half a flake to one, on "
                             "both backends; where they show, quad lights are sampled.",
                             kParams, kOutputs, &cpu, kNeedsDerivatives);
    s.resources = {{"dictionary", "sampler1DArray", ResourceSpec::Kind::BuiltinTable,
                    "glint dictionary (Chermain et al. 2020): 64 x 1024 layers RGBA32F, box MIP chain 0..6",
                    &dictionaryTexels}};
    s.glslLibraries = {"shared/fresnel_f0.glsl"};
    s.gpuSubstituteCpu = &cpuGpuTwin;  // no gpuSubstitute sentence: the GLSL is the model, less integrated quad lights
    s.parityTolerance = 5e-4f;
    s.parityNote = "GGAA off and on: measured 5.3e-5 worst case over 1024 samples on llvmpipe (float vs float, both "
                   "MIP blends from the exact log2: the GLSL passes its own LOD to textureLod rather than leave it to "
                   "textureGrad, whose implementation-defined LOD differed by up to 9.4e-2)";
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
