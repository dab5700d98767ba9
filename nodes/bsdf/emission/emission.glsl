// bsdf.emission: no scattering; emission = color * strength.
void spc_bsdf_emission(vec3 color, float strength, out SpeculaClosure bsdf) {
    bsdf = spc_closure_none();
    bsdf.emission = color * strength;
}
