// bsdf.ggx: f·cos = weight · F(wo·h) D(h) G2(wo, wi) / (4 wo.z), the GLSL twin of GgxLobe::eval (and of
// GgxLobe::integratePolygon for polygon queries).
// α, D, Λ and G2 = 1/(1 + Λo + Λi): shared/ggx_microfacet.glsl; F: shared/fresnel_f0.glsl.
// Polygon queries (GgxLobe::integratePolygon): the fitted LTC of this lobe (isotropic 64×64 table, or the anisotropic
// table for αx != αy; shared/ltc.glsl) times F0·mag + (1 − F0)·fres.
void spc_bsdf_ggx(SpeculaClosureQuery q, vec3 weight, float roughness, float anisotropy, int fresnel, vec3 f0, float ior,
                  vec3 eta, vec3 k, vec3 normal, vec3 tangent, sampler2D ltc_matrix, sampler2D ltc_amplitude,
                  sampler2D ltc_anisotropic, out SpeculaClosure bsdf) {
    bsdf = spc_closure_none();
    vec2 alpha = spc_alpha_from_roughness(roughness, anisotropy);
    float ax = max(alpha.x, 1e-4), ay = max(alpha.y, 1e-4);  // ggx::kMinAlpha
    if (q.kind != SPC_QUERY_DIRECTION) {  // polygon and environment queries
        vec3 T, B, N;
        spc_frame(normal, tangent, T, B, N);
        vec3 lo = spc_to_local(q.wo, T, B, N);
        if (lo.z <= 0.0) return;
        mat3 invM;
        vec2 magFres;
        float e = spc_ltc_ggx_polygon(q, ltc_matrix, ltc_amplitude, ltc_anisotropic, ax, ay, lo, T, B, N, invM, magFres);
        bsdf.f = weight * (spc_ltc_fresnel_scale(spc_fresnel_f0(fresnel, f0, ior, eta, k), magFres) * e);
        if (q.kind == SPC_QUERY_ENVIRONMENT) bsdf.f *= spc_ltc_environment(invM, T, B, N);
        return;
    }
    vec3 o, i, h;
    if (!spc_reflection_local(q.wo, q.wi, normal, tangent, o, i, h)) return;
    float d = spc_ggx_ndf(h, ax, ay);
    float g = spc_ggx_g2(o, i, ax, ay);
    vec3 F = spc_fresnel_eval(fresnel, dot(o, h), f0, ior, eta, k);
    bsdf.f = weight * (F * (d * g / (4.0 * o.z)));
}
