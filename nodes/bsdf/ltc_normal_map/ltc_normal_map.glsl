// bsdf.ltc_normal_map: NOT IMPLEMENTED in GLSL. The prefiltered LTC tables exist only on the CPU (core/ltc/
// ltc_prefilter.h); this stub binds the ports and returns no lobe (partial for polygon queries), so shaders compile.
void spc_bsdf_ltc_normal_map(SpeculaClosureQuery q, int convention, float roughness, float strength,
                             vec3 specular_color, vec3 diffuse_color, vec2 uv, vec2 duvdx, vec2 duvdy, vec3 normal,
                             vec3 tangent, float sign_, out SpeculaClosure bsdf) {
    bsdf = spc_closure_none();
    bsdf.partial = q.kind != SPC_QUERY_DIRECTION;
}
