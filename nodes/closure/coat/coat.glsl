// closure.coat: weight · coat + lerp(1, tint · (1 − E(μo)), weight) · base, the GLSL twin of coat.node.cpp. The coat
// is GgxLobe with α = max(roughness², 1e-4) and exact dielectric Fresnel; E from the coat_albedo table
// (coat_albedo.h), interpolated with texelFetch exactly as coat::albedo. D and G2: shared/ggx_microfacet.glsl (isotropic,
// αx = αy = α).

// One axis of the table (coat::axis): lower node i0 and upper weight t of v ∈ [0, 1] on n nodes.
void spc_coat_axis(float v, int n, out int i0, out float t) {
    float x = clamp(v, 0.0, 1.0) * float(n - 1);
    i0 = min(int(x), n - 2);
    t = x - float(i0);
}
float spc_coat_texel(sampler2D tab, int i, int j, int k) { return texelFetch(tab, ivec2(i, k * 32 + j), 0).x; }
float spc_coat_bilinear(sampler2D tab, int i, float ti, int j, float tj, int k) {
    float e0 = spc_coat_texel(tab, i, j, k) + ti * (spc_coat_texel(tab, i + 1, j, k) - spc_coat_texel(tab, i, j, k));
    float e1 = spc_coat_texel(tab, i, j + 1, k) + ti * (spc_coat_texel(tab, i + 1, j + 1, k) - spc_coat_texel(tab, i, j + 1, k));
    return e0 + tj * (e1 - e0);
}
// E(μo, roughness, ior): 32 μo × 32 roughness × 16 F0 = ((η−1)/(η+1))² nodes over [0, 0.25] (coat::albedo).
float spc_coat_albedo(sampler2D tab, float mu, float roughness, float ior) {
    if (!(mu > 0.0)) return 0.0;
    int i, j, k;
    float ti, tj, tk;
    spc_coat_axis(mu, 32, i, ti);
    spc_coat_axis(roughness, 32, j, tj);
    float r = (clamp(ior, 1.0, 3.0) - 1.0) / (clamp(ior, 1.0, 3.0) + 1.0);
    spc_coat_axis(r * r / 0.25, 16, k, tk);
    float a = spc_coat_bilinear(tab, i, ti, j, tj, k), b = spc_coat_bilinear(tab, i, ti, j, tj, k + 1);
    return a + tk * (b - a);
}

void spc_closure_coat(SpeculaClosureQuery q, SpeculaClosure base, float weight, float roughness, float ior, vec3 tint,
                      vec3 normal, vec3 tangent, sampler2D coat_albedo, sampler2D ltc_matrix, sampler2D ltc_amplitude,
                      out SpeculaClosure bsdf) {
    float w = clamp(weight, 0.0, 1.0), eta = clamp(ior, 1.0, 3.0), r = clamp(roughness, 0.0, 1.0);
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    float e = w > 0.0 ? spc_coat_albedo(coat_albedo, dot(q.wo, N), r, eta) : 0.0;
    vec3 baseScale = vec3(1.0 - w) + w * tint * (1.0 - e);
    bsdf.f = base.f * baseScale;
    bsdf.f_diffuse = base.f_diffuse * baseScale;
    bsdf.emission = base.emission * baseScale;
    bsdf.partial = base.partial;
    if (!(w > 0.0)) return;
    float a = max(r * r, 1e-4);
    vec3 o = spc_to_local(q.wo, T, B, N);
    if (q.kind != SPC_QUERY_DIRECTION) {  // GgxLobe::integratePolygon: the isotropic LTC times F0·mag + (1 − F0)·fres
        if (o.z <= 0.0) return;
        mat3 invM;
        vec2 magFres;
        spc_ltc_ggx_isotropic(ltc_matrix, ltc_amplitude, a, o, invM, magFres);
        vec3 p[4];
        spc_ltc_local_polygon(q, T, B, N, p);
        float integral = spc_ltc_integrate(invM, p, q.vertex_count, q.horizon, ltc_amplitude);
        vec3 L = q.kind == SPC_QUERY_ENVIRONMENT ? spc_ltc_environment(invM, T, B, N) : vec3(1.0);
        bsdf.f += w * (spc_ltc_fresnel_scale(vec3(spc_fresnel_dielectric(1.0, eta)), magFres) * integral) * L;
        return;
    }
    vec3 i = spc_to_local(q.wi, T, B, N);
    if (o.z <= 0.0 || i.z <= 0.0) return;
    vec3 hs = o + i;
    float len = sqrt(dot(hs, hs));
    if (len == 0.0) return;
    vec3 h = hs / len;
    float g = spc_ggx_g2(o, i, a, a);
    bsdf.f += vec3(w * spc_fresnel_dielectric(dot(o, h), eta) * spc_ggx_ndf(h, a, a) * g / (4.0 * o.z));
}
