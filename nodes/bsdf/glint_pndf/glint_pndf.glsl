// bsdf.glint_pndf on the GPU: a declared substitute, not the exact P-NDF (NodeSpec::gpuSubstitute; the emitter warns).
// LEAN-filtered GGX of the same normal map: texture.lean (anisotropic, repeat, full correlation) over a footprint with
// the variance of the P-NDF kernel, then bsdf.ggx_filtered with filter none, A = diag(α²) + 2Σ in the frame of the LEAN
// mean normal, Schlick F0 = F(0°) of the chosen Fresnel model. CPU twin: cpuSubstitute in glint_pndf.node.cpp.
// The P-NDF-only inputs (kernel shape aside, cluster_threshold, jacobian_clamp, masking) have no effect here, nor does
// footprint_centre: a fragment is at its pixel centre.

// glint_pndf.node.cpp leanFootprintScale: texture.lean averages ~one pixel step per derivative (std |duv|/√12); the
// P-NDF kernel of half-width k|duv|/2 has std σ/3 (gaussian), σ/√3 (box), σ/2 (disk).
float spc_pndf_lean_scale(int kernel, float k) {
    const float sqrt12 = 3.46410162;
    if (kernel == SPC_PNDF_KERNEL_BOX) return k;
    if (kernel == SPC_PNDF_KERNEL_DISK) return k * sqrt12 / 4.0;
    return k * sqrt12 / 6.0;
}

void spc_bsdf_glint_pndf(SpeculaClosureQuery q, SpeculaShadingInputs s, vec3 weight, int convention, vec2 uv, vec2 duvdx,
                         vec2 duvdy, float uv_scale, float footprint_scale, int kernel, int footprint_centre,
                         float cluster_threshold,
                         float jacobian_clamp, int masking, int fresnel, vec3 f0, float ior, vec3 eta, vec3 k,
                         vec3 normal, vec3 tangent, float sign_, sampler2D moments, sampler2D ltc_matrix,
                         sampler2D ltc_amplitude, sampler2D ltc_anisotropic, out SpeculaClosure bsdf) {
    float scale = spc_pndf_lean_scale(kernel, footprint_scale);
    vec3 mean_normal, sigma_rho, covariance;
    vec2 slope;
    spc_texture_lean(moments, convention, SPC_LEAN_FILTER_ANISOTROPIC, SPC_LEAN_CORRELATION_FULL, SPC_LEAN_WRAP_REPEAT, 1.0,
                     uv, duvdx * scale, duvdy * scale, normal, tangent, sign_, uv_scale, mean_normal, slope, sigma_rho,
                     covariance);
    vec2 filtered_alpha;
    spc_bsdf_ggx_filtered(q, s, weight, vec2(0.02), covariance, SPC_GGXF_FILTER_NONE, SPC_GGXF_KERNEL_AXIS_ALIGNED, 0.25, 0.18,
                          SPC_DERIVATIVES_ANALYTIC, 0.0, spc_fresnel_f0(fresnel, f0, ior, eta, k), mean_normal, tangent,
                          vec3(0.0), vec3(0.0), ltc_matrix, ltc_amplitude, ltc_anisotropic, bsdf, filtered_alpha);
}
