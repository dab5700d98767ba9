// bsdf.diffuse: f·cos = color/π · cos θi in the frame of 'normal' (CPU: LambertLobe). Polygon queries: the cosine lobe
// is the LTC with M = I, so ∫_P f·cos = color · (Lambert's form factor of P) (HDHN16 §4; shared/ltc.glsl), exact or
// clip-free by q.horizon; ltc_amplitude is read only by the clip-free path (its sphere channel).
void spc_bsdf_diffuse(SpeculaClosureQuery q, vec3 color, vec3 normal, vec3 tangent, sampler2D ltc_amplitude,
                      out SpeculaClosure bsdf) {
    bsdf = spc_closure_none();
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    vec3 o = spc_to_local(q.wo, T, B, N);
    if (q.kind != SPC_QUERY_DIRECTION) {  // polygon and environment queries (the latter: times the irradiance at N)
        if (o.z <= 0.0) return;
        vec3 p[4];
        spc_ltc_local_polygon(q, T, B, N, p);
        bsdf.f = color * spc_ltc_cosine_integral(p, q.vertex_count, q.horizon, ltc_amplitude);
        if (q.kind == SPC_QUERY_ENVIRONMENT) bsdf.f *= spc_host_environment(N, -1.0);
        bsdf.f_diffuse = bsdf.f;
        return;
    }
    vec3 i = spc_to_local(q.wi, T, B, N);
    bsdf.f = (o.z <= 0.0 || i.z <= 0.0) ? vec3(0.0) : color * (SPC_INV_PI * i.z);
    bsdf.f_diffuse = bsdf.f;
}
