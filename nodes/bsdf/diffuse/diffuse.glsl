// bsdf.diffuse: f·cos = color/π · cos θi in the frame of 'normal' (CPU: LambertLobe).
void spc_bsdf_diffuse(vec3 wo, vec3 wi, vec3 color, vec3 normal, vec3 tangent, out SpeculaClosure bsdf) {
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    vec3 o = spc_to_local(wo, T, B, N);
    vec3 i = spc_to_local(wi, T, B, N);
    bsdf.emission = vec3(0.0);
    bsdf.f = (o.z <= 0.0 || i.z <= 0.0) ? vec3(0.0) : color * (SPC_INV_PI * i.z);
}
