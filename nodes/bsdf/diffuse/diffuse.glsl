// bsdf.diffuse: f·cos = color/π · cos θi in the frame of 'normal' (CPU: LambertLobe).
void spc_bsdf_diffuse(SpeculaClosureQuery q, vec3 color, vec3 normal, vec3 tangent, out SpeculaClosure bsdf) {
    bsdf = spc_closure_none();
    if (q.kind != SPC_QUERY_DIRECTION) {  // no closed form over polygons: the host samples this lobe
        bsdf.partial = true;
        return;
    }
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    vec3 o = spc_to_local(q.wo, T, B, N);
    vec3 i = spc_to_local(q.wi, T, B, N);
    bsdf.f = (o.z <= 0.0 || i.z <= 0.0) ? vec3(0.0) : color * (SPC_INV_PI * i.z);
}
