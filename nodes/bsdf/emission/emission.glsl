// bsdf.emission: no scattering; emission = color * strength.
void spc_bsdf_emission(vec3 color, float strength, out SpeculaClosure bsdf) {
    bsdf.f = vec3(0.0);
    bsdf.emission = color * strength;
}
