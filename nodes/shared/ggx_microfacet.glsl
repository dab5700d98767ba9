// The GGX microfacet formulas every GGX-based node's GLSL shares (NodeSpec::glslLibraries "shared/ggx_microfacet.glsl"):
// roughness -> α, the anisotropic D, the Smith Λ in its diagonal and its matrix form, and G2.
// CPU homes: alphaFromRoughness (nodes/shared/bsdf_ports.h); ggx::ndf, ggx::lambdaOfTan2, ggx::lambda, ggx::g2
// (core/render/lobes/ggx.h); fggx::lambda (nodes/bsdf/ggx_filtered/filtered_ggx.h). Parity: tests/glsl/test_glsl_formulas.cpp.

// α = roughness² (Burley 2012); anisotropy stretches it by the aspect a = sqrt(1 − 0.9·anisotropy): (αx, αy) = (α/a, α·a)
// (Burley 2012, addendum B.2). Unclamped: each lobe applies its own floor (GGX: 1e-4, ggx::kMinAlpha).
vec2 spc_alpha_from_roughness(float roughness, float anisotropy) {
    float alpha = roughness * roughness;
    float aspect = sqrt(max(1.0 - 0.9 * anisotropy, 0.0));
    return vec2(alpha / aspect, alpha * aspect);
}
// D(h) = 1 / (π αx αy (hx²/αx² + hy²/αy² + hz²)²)   (Walter et al. 2007, Eq. 33, anisotropic form)
float spc_ggx_ndf(vec3 h, float ax, float ay) {
    if (h.z <= 0.0) return 0.0;
    float hx = h.x / ax, hy = h.y / ay;  // ggx::ndf's operation order (α ~ 1e-4 amplifies rounding)
    float e = hx * hx + hy * hy + h.z * h.z;
    return 1.0 / (SPC_PI * ax * ay * e * e);
}
// Λ = (−1 + sqrt(1 + α²tan²θ)) / 2 (Heitz 2014, Eq. 86), from the projected α²tan²θ of the direction.
float spc_ggx_lambda_of_tan2(float a2tan2) { return 0.5 * (-1.0 + sqrt(1.0 + a2tan2)); }
// Λ(w) of the axis-aligned anisotropic GGX: α²tan²θ = ((αx wx)² + (αy wy)²) / wz².
float spc_ggx_lambda(vec3 w, float ax, float ay) {
    float z2 = w.z * w.z;
    if (z2 <= 0.0) return 1e30;
    float px = ax * w.x, py = ay * w.y;
    return spc_ggx_lambda_of_tan2((px * px + py * py) / z2);
}
// Λ(w) of the GGX with roughness matrix A = [[a, c], [c, d]] = vec3(a, c, d): α²tan²θ = w⊥ᵀ A w⊥ / wz² (Tokuyoshi &
// Kaplanyan 2021, A.3); A = diag(αx², αy²) is spc_ggx_lambda.
float spc_ggx_lambda_matrix(vec3 w, vec3 A) {
    float z2 = w.z * w.z;
    if (z2 <= 0.0) return 1e30;
    float s = max(A.x * w.x * w.x + 2.0 * A.y * w.x * w.y + A.z * w.y * w.y, 0.0);
    return spc_ggx_lambda_of_tan2(s / z2);
}
// Height-correlated masking-shadowing G2 = 1 / (1 + Λ(wo) + Λ(wi))   (Heitz 2014, Eq. 99)
float spc_ggx_g2(vec3 o, vec3 i, float ax, float ay) {
    return 1.0 / (1.0 + spc_ggx_lambda(o, ax, ay) + spc_ggx_lambda(i, ax, ay));
}
float spc_ggx_g2_matrix(vec3 o, vec3 i, vec3 A) {
    return 1.0 / (1.0 + spc_ggx_lambda_matrix(o, A) + spc_ggx_lambda_matrix(i, A));
}
