// The Fresnel model the shared fresnel ports select (nodes/shared/bsdf_ports.h fresnelPorts), the one GLSL switch over
// it: spc_fresnel_eval is the twin of fresnelOf(p).eval(cos) (CPU), spc_fresnel_f0 its value at cos = 1, the F0 that LTC
// Fresnel weighting (ltc::fresnelScale) and Schlick stand-ins use; 1 = no Fresnel. SPC_FRESNEL_* come from the calling
// node's own 'fresnel' port. Parity: tests/glsl/test_glsl_formulas.cpp.
vec3 spc_fresnel_eval(int fresnel, float cosTheta, vec3 f0, float ior, vec3 eta, vec3 k) {
    if (fresnel == SPC_FRESNEL_SCHLICK) return spc_fresnel_schlick(cosTheta, f0);
    if (fresnel == SPC_FRESNEL_DIELECTRIC) return vec3(spc_fresnel_dielectric(cosTheta, ior));
    if (fresnel == SPC_FRESNEL_CONDUCTOR)
        return vec3(spc_fresnel_conductor(cosTheta, eta.x, k.x), spc_fresnel_conductor(cosTheta, eta.y, k.y),
                    spc_fresnel_conductor(cosTheta, eta.z, k.z));
    return vec3(1.0);
}
// Schlick at cos = 1 is f0 exactly ((1 − f0) · 0 added).
vec3 spc_fresnel_f0(int fresnel, vec3 f0, float ior, vec3 eta, vec3 k) { return spc_fresnel_eval(fresnel, 1.0, f0, ior, eta, k); }
