// F(cos = 1) of the Fresnel model the shared fresnel ports select (nodes/shared/bsdf_ports.h fresnelPorts): the F0 that
// LTC Fresnel weighting (ltc::fresnelScale) and Schlick stand-ins use; 1 = no Fresnel. SPC_FRESNEL_* come from the
// calling node's own 'fresnel' port.
vec3 spc_fresnel_f0(int fresnel, vec3 f0, float ior, vec3 eta, vec3 k) {
    if (fresnel == SPC_FRESNEL_SCHLICK) return f0;
    if (fresnel == SPC_FRESNEL_DIELECTRIC) return vec3(spc_fresnel_dielectric(1.0, ior));
    if (fresnel == SPC_FRESNEL_CONDUCTOR)
        return vec3(spc_fresnel_conductor(1.0, eta.x, k.x), spc_fresnel_conductor(1.0, eta.y, k.y), spc_fresnel_conductor(1.0, eta.z, k.z));
    return vec3(1.0);
}
