// The GLSL prelude shared by every emitted module and by the parity harness: the documented
// SpeculaShadingInputs/SpeculaClosure structs, the BSDF frame and the Fresnel terms (ports of
// core/render/lobes/fresnel.h and Frame::fromNormalTangent, same operation order as the CPU).
#include "core/codegen/glsl_sources.h"

namespace specula::codegen {

const std::string& glslPrelude() {
    static const std::string s = R"GLSL(// ---- Specula prelude -------------------------------------------------------------------------
// Guarded: several material modules may be concatenated into one shader.
#ifndef SPECULA_PRELUDE
#define SPECULA_PRELUDE
const float SPC_PI = 3.14159265358979323846;
const float SPC_INV_PI = 0.31830988618379067154;

// Everything a node may read about the shading point. Fill it with specula_shading_inputs() in a
// fragment shader (derivatives from dFdxFine/dFdyFine: the CPU's "quad" mode differences the same 2x2 pixel quads),
// or set the fields directly (e.g. from a ray tracer).
// All vectors are world space; normal, geometric_normal and tangent.xyz must be unit length.
struct SpeculaShadingInputs {
    vec3 position;          // P
    vec3 normal;            // N: shading normal, same side as geometric_normal
    vec3 geometric_normal;  // Ng
    vec4 tangent;           // xyz: tangent T, w: bitangent sign (B = sign * cross(N, T))
    vec2 uv;                // uv0
    vec3 dPdx, dPdy;        // screen-space derivatives of P per pixel step (CPU: ray differentials)
    vec2 duvdx, duvdy;      // of uv
    vec3 dNdx, dNdy;        // of N
    vec3 dwodx, dwody;      // of the view direction wo (0: orthographic camera)
    bool front_facing;      // the viewer is on the side the surface's normal points to (gl_FrontFacing); false
                            // inside a closed object: refracting nodes (bsdf.dielectric) invert their IOR there
};

// What a closure is asked (CPU: BsdfQuery), the first parameter of every BSDF function. kind DIRECTION: f·cos for the
// pair (wo, wi); kind POLYGON: the integral of f·cos over the polygon polygon[0..vertex_count), unshadowed and without
// the light's radiance (the host applies both), for lobes with a closed form (the LTC lobes: bsdf.diffuse, bsdf.ggx,
// bsdf.ggx_filtered, bsdf.beckmann_lean; the others set SpeculaClosure.partial). light_distance: distance to a point
// light (filtered lobes differentiate wi with it); +inf for directions. horizon (polygon queries): how the LTC lobes
// treat a polygon crossing the horizon of their cosine space, SPC_HORIZON_CLIP (0) = exact clipping,
// SPC_HORIZON_CLIPLESS (1) = the clip-free sphere approximation (CPU: BsdfQuery::polygonHorizon, render.ltc_horizon).
const int SPC_QUERY_DIRECTION = 0;
const int SPC_QUERY_POLYGON = 1;
// kind ENVIRONMENT (the split sum, docs/preview.md): a polygon query over the polygon standing for the hemisphere of
// the shading normal whose LTC lobes each multiply their integral by spc_host_environment(dir, alpha), the radiance
// of the prefiltered environment where the lobe's LTC points (spc_ltc_environment_lookup: its peak direction, world
// space, and the GGX roughness of its peak; alpha < 0 asks for the irradiance E(n)/π, which diffuse lobes read at
// their normal). The answer's f is then the environment's light, not an integral to be scaled. A host that has a
// prefiltered environment defines SPECULA_HOST_ENVIRONMENT before the module and the function after it; otherwise the
// function below answers 1, so f is the lobes' hemisphere integral, to be scaled by the environment's mean radiance.
const int SPC_QUERY_ENVIRONMENT = 2;
const int SPC_HORIZON_CLIP = 0;
const int SPC_HORIZON_CLIPLESS = 1;
struct SpeculaClosureQuery {
    int kind;
    vec3 wo;
    vec3 wi;
    float light_distance;
    vec3 polygon[4];
    int vertex_count;
    int horizon;
};
SpeculaClosureQuery specula_direction_query(vec3 wo, vec3 wi, float light_distance) {
    SpeculaClosureQuery q;
    q.kind = SPC_QUERY_DIRECTION;
    q.wo = wo;
    q.wi = wi;
    q.light_distance = light_distance;
    for (int k = 0; k < 4; ++k) q.polygon[k] = vec3(0.0);
    q.vertex_count = 0;
    q.horizon = SPC_HORIZON_CLIP;
    return q;
}
// A polygon query for a light polygon of count (3 or 4) vertices: wo = unit view direction (world space, away from
// the surface); polygon = world-space offsets of the vertices from the shading point (any length), counter-clockwise
// seen from the shading point. The lobes are one-sided (a polygon wound clockwise gives 0), so the host orients it:
// a one-sided light is skipped for points behind it, a two-sided light has its winding reversed for them (CPU:
// QuadLight::polygon in core/render/lights.cpp). horizon: SPC_HORIZON_CLIP or SPC_HORIZON_CLIPLESS. The answer's f
// is the sum over the lobes of weight · ∫_P f·cos dω.
SpeculaClosureQuery specula_polygon_query(vec3 wo, vec3 polygon[4], int count, int horizon) {
    SpeculaClosureQuery q = specula_direction_query(wo, wo, 1.0 / 0.0);
    q.kind = SPC_QUERY_POLYGON;
    q.polygon = polygon;
    q.vertex_count = clamp(count, 0, 4);
    q.horizon = horizon;
    return q;
}
SpeculaClosureQuery specula_polygon_query(vec3 wo, vec3 p0, vec3 p1, vec3 p2, vec3 p3, int count, int horizon) {
    return specula_polygon_query(wo, vec3[4](p0, p1, p2, p3), count, horizon);
}
// An environment query: hemisphere = the four directions of the polygon standing for the hemisphere of the shading
// normal (CPU: Integrator::rasterLighting lifts the frame's ±T, ±B by kRasterHemisphereLift towards N).
SpeculaClosureQuery specula_environment_query(vec3 wo, vec3 hemisphere[4], int horizon) {
    SpeculaClosureQuery q = specula_polygon_query(wo, hemisphere, 4, horizon);
    q.kind = SPC_QUERY_ENVIRONMENT;
    return q;
}
#ifdef SPECULA_HOST_ENVIRONMENT
vec3 spc_host_environment(vec3 dir, float alpha);
#else
vec3 spc_host_environment(vec3 dir, float alpha) { return vec3(1.0); }
#endif

// A closure's answer to a query: f = BSDF times cos(theta_i) (or its polygon integral), emission = emitted
// radiance; partial = some lobe could not answer a polygon query (the host samples the closure for that light).
struct SpeculaClosure {
    vec3 f;
    vec3 f_diffuse;  // the part of f from diffuse lobes (CPU: BsdfEval::diffuse), for the diffuse/specular AOVs
    vec3 emission;
    bool partial;
};
SpeculaClosure spc_closure_none() {
    SpeculaClosure c;
    c.f = vec3(0.0);
    c.f_diffuse = vec3(0.0);
    c.emission = vec3(0.0);
    c.partial = false;
    return c;
}

SpeculaShadingInputs specula_shading_inputs(vec3 P, vec3 N, vec3 Ng, vec4 T, vec2 uv) {
    SpeculaShadingInputs s;
    s.position = P;
    s.normal = normalize(N);
    s.geometric_normal = normalize(Ng);
    s.tangent = vec4(normalize(T.xyz), T.w < 0.0 ? -1.0 : 1.0);
    s.uv = uv;
    s.dPdx = dFdxFine(P);
    s.dPdy = dFdyFine(P);
    s.duvdx = dFdxFine(uv);
    s.duvdy = dFdyFine(uv);
    s.dNdx = dFdxFine(s.normal);
    s.dNdy = dFdyFine(s.normal);
    s.dwodx = vec3(0.0);
    s.dwody = vec3(0.0);
    s.front_facing = gl_FrontFacing;
    return s;
}
// The same with the view direction wo (unit, towards the viewer), whose screen derivatives filtered lobes use.
SpeculaShadingInputs specula_shading_inputs(vec3 P, vec3 N, vec3 Ng, vec4 T, vec2 uv, vec3 wo) {
    SpeculaShadingInputs s = specula_shading_inputs(P, N, Ng, T, uv);
    s.dwodx = dFdxFine(wo);
    s.dwody = dFdyFine(wo);
    return s;
}

// Orthonormal frame of a BSDF from its normal and tangent inputs (CPU: graph::bsdfFrame, i.e.
// Gram-Schmidt, falling back to Duff et al. 2017, "Building an orthonormal basis, revisited").
void spc_frame(vec3 n, vec3 t, out vec3 T, out vec3 B, out vec3 N) {
    float l2 = dot(n, n);
    N = l2 > 0.0 ? n / sqrt(l2) : vec3(0.0, 0.0, 1.0);
    vec3 tt = t - N * dot(N, t);
    float t2 = dot(tt, tt);
    if (t2 > 1e-12) {
        T = tt / sqrt(t2);
        B = cross(N, T);
    } else {
        float sgn = N.z >= 0.0 ? 1.0 : -1.0;
        float a = -1.0 / (sgn + N.z);
        float b = N.x * N.y * a;
        T = vec3(1.0 + sgn * N.x * N.x * a, sgn * b, -sgn * N.x);
        B = vec3(b, sgn + N.y * N.y * a, -N.y);
    }
}
vec3 spc_to_local(vec3 v, vec3 T, vec3 B, vec3 N) { return vec3(dot(v, T), dot(v, B), dot(v, N)); }

// A reflection pair in the BSDF frame of (normal, tangent): local wo, wi and the unit half vector; false
// when either direction is below the surface or the pair is degenerate (CPU: the lobes' eval preamble).
bool spc_reflection_local(vec3 wo, vec3 wi, vec3 normal, vec3 tangent, out vec3 o, out vec3 i, out vec3 h) {
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    o = spc_to_local(wo, T, B, N);
    i = spc_to_local(wi, T, B, N);
    h = o + i;
    if (o.z <= 0.0 || i.z <= 0.0) return false;
    float len = sqrt(dot(h, h));
    if (len == 0.0) return false;
    h /= len;
    return true;
}

// Exact unpolarised dielectric reflectance, relative IOR eta (CPU: fresnelDielectric).
float spc_fresnel_dielectric(float cosThetaI, float eta) {
    cosThetaI = clamp(cosThetaI, -1.0, 1.0);
    if (cosThetaI < 0.0) {
        eta = 1.0 / eta;
        cosThetaI = -cosThetaI;
    }
    float sin2T = (1.0 - cosThetaI * cosThetaI) / (eta * eta);
    if (sin2T >= 1.0) return 1.0;
    float cosT = sqrt(max(0.0, 1.0 - sin2T));
    float rPar = (eta * cosThetaI - cosT) / (eta * cosThetaI + cosT);
    float rPerp = (cosThetaI - eta * cosT) / (cosThetaI + eta * cosT);
    return 0.5 * (rPar * rPar + rPerp * rPerp);
}

// Exact conductor reflectance for complex IOR eta + i k, one channel (CPU: fresnelConductor).
float spc_fresnel_conductor(float cosThetaI, float eta, float k) {
    float c2 = clamp(cosThetaI * cosThetaI, 0.0, 1.0);
    float s2 = 1.0 - c2;
    float eta2 = eta * eta, k2 = k * k;
    float t0 = eta2 - k2 - s2;
    float a2b2 = sqrt(max(0.0, t0 * t0 + 4.0 * eta2 * k2));
    float t1 = a2b2 + c2;
    float a = sqrt(max(0.0, 0.5 * (a2b2 + t0)));
    float t2 = 2.0 * sqrt(c2) * a;
    float rs = (t1 - t2) / max(t1 + t2, 1e-12);
    float t3 = c2 * a2b2 + s2 * s2;
    float t4 = t2 * s2;
    float rp = rs * (t3 - t4) / max(t3 + t4, 1e-12);
    return 0.5 * (rp + rs);
}

// Schlick's approximation with a coloured F0 (CPU: fresnelSchlick).
vec3 spc_fresnel_schlick(float cosTheta, vec3 f0) {
    float m = clamp(1.0 - cosTheta, 0.0, 1.0);
    float m5 = (m * m) * (m * m) * m;
    return f0 + (vec3(1.0) - f0) * m5;
}
#endif  // SPECULA_PRELUDE
)GLSL";
    return s;
}

}  // namespace specula::codegen
