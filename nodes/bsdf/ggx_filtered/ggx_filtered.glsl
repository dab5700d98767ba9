// bsdf.ggx_filtered: the GLSL twin of FilteredGgxLobe::eval (nodes/bsdf/ggx_filtered/filtered_ggx.h): GGX with a
// roughness matrix A = [[a, c], [c, d]] (vec3(a, c, d)) filtered per pixel (Tokuyoshi & Kaplanyan 2021, "TK21").
// Derivative sources: "quad" = dFdxFine/dFdyFine of q in the fragment shader (GL 4.5); "analytic" = the chain rule of
// filtered-ggx.md §5.1 from s.dNdx/s.dNdy, the view-direction derivatives s.dwodx/s.dwody and, for a point light at
// q.light_distance, dwi = -(I - wi wi^T) dP / distance (a directional light, distance +inf, has dwi = 0).

// TK21 Eq. 1 with the A.4 clamp: D(h) = 1 / (π sqrt(max(det A, τ)) (h⊥ᵀ adj(A) h⊥ / max(det A, τ) + h_z²)²)
float spc_ggxf_ndf(vec3 h, vec3 A, float tau) {
    if (h.z <= 0.0) return 0.0;
    float det = max(A.x * A.z - A.y * A.y, tau);
    float q = (A.z * h.x * h.x - 2.0 * A.y * h.x * h.y + A.x * h.y * h.y) / det;
    float e = q + h.z * h.z;
    return 1.0 / (SPC_PI * sqrt(det) * e * e);
}
// Λ and G2 of the matrix GGX (TK21 A.3): spc_ggx_lambda_matrix, spc_ggx_g2_matrix in shared/ggx_microfacet.glsl.
float spc_ggxf_det(vec3 M) { return M.x * M.z - M.y * M.y; }
float spc_ggxf_eigmax(vec3 M) {
    float h = 0.5 * (M.x + M.z);
    return h + sqrt(max(0.0, h * h - spc_ggxf_det(M)));
}
// Σ(q) = σ² (Δ_u q Δ_u qᵀ + Δ_v q Δ_v qᵀ)   (K16; TK21 Eq. 3)
vec3 spc_ggxf_kernel(vec2 du, vec2 dv, float sigma2) {
    return sigma2 * vec3(du.x * du.x + dv.x * dv.x, du.x * du.y + dv.x * dv.y, du.y * du.y + dv.y * dv.y);
}
// Eq. 2 / Eq. 9 (full kernel) and Listing 3 (axis-aligned: κ clamp, saturate).
vec3 spc_ggxf_additive(vec3 A, vec2 du, vec2 dv, int kernel, float sigma2, float kappa) {
    if (kernel == SPC_GGXF_KERNEL_FULL) return A + 2.0 * spc_ggxf_kernel(du, dv, sigma2);
    vec2 w = abs(du) + abs(dv);
    vec2 k = min(2.0 * sigma2 * w * w, vec2(kappa));
    return vec3(clamp(A.x + k.x, 0.0, 1.0), A.y, clamp(A.z + k.y, 0.0, 1.0));
}
// TK21 Eqs. 4–7 in the App. D form: B = A (I − A)⁻¹, B̄ = B + K, d = max(det B̄, det B), M = B̄/d + I, Ā = M/max(det M, 1).
vec3 spc_ggxf_projected(vec3 A, vec2 du, vec2 dv, int kernel, float sigma2, float kappa) {
    vec3 K;
    if (kernel == SPC_GGXF_KERNEL_FULL) {
        K = 2.0 * spc_ggxf_kernel(du, dv, sigma2);
    } else {
        vec2 w = abs(du) + abs(dv);
        vec2 k = min(2.0 * sigma2 * w * w, vec2(kappa));
        K = vec3(k.x, 0.0, k.y);
    }
    if (K.x == 0.0 && K.y == 0.0 && K.z == 0.0) return A;
    if (spc_ggxf_eigmax(A) >= 0.998 || !(spc_ggxf_det(A) > 0.0)) return spc_ggxf_additive(A, du, dv, kernel, sigma2, kappa);
    vec3 IA = vec3(1.0 - A.x, -A.y, 1.0 - A.z);
    vec3 inv = vec3(IA.z, -IA.y, IA.x) / spc_ggxf_det(IA);
    vec3 B = vec3(A.x * inv.x + A.y * inv.y, A.x * inv.y + A.y * inv.z, A.y * inv.y + A.z * inv.z);
    vec3 Bb = B + K;
    float d = max(spc_ggxf_det(Bb), spc_ggxf_det(B));
    if (!(d > 1e-30)) return spc_ggxf_additive(A, du, dv, kernel, sigma2, kappa);
    vec3 M = Bb / d + vec3(1.0, 0.0, 1.0);
    return M / max(spc_ggxf_det(M), 1.0);
}
// TK21 §5 isotropic kernels from the normal derivatives (local frame): iso_max Eq. 10, iso_sum Eq. 13, iso_mean
// Eq. 14, iso_rect K16 Listing 4.
float spc_ggxf_iso(int fmode, vec3 du, vec3 dv, float sigma2, float kappa) {
    float uu = dot(du, du), vv = dot(dv, dv), uv = dot(du, dv);
    if (fmode == SPC_GGXF_FILTER_ISO_MAX) return min(2.0 * sigma2 * spc_ggxf_eigmax(vec3(uu, uv, vv)), kappa);
    if (fmode == SPC_GGXF_FILTER_ISO_SUM) return min(2.0 * sigma2 * (uu + vv), kappa);
    if (fmode == SPC_GGXF_FILTER_ISO_MEAN) return min(sigma2 * (uu + vv), kappa);
    float w = max(abs(du.x) + abs(dv.x), abs(du.y) + abs(dv.y));
    return min(2.0 * sigma2 * w * w, kappa);
}
// Analytic Δq (filtered-ggx.md §5.1): dh = P(h)(dwo + dwi)/|H|, Δh⊥ = dh.xy − h_z dn.xy, Δh∥ = −(Δh⊥ h_z − h⊥ dh_z)/h_z².
vec2 spc_ggxf_dq(vec3 h, float len, vec3 dwo, vec3 dwi, vec3 dn, bool slope) {
    vec3 dH = dwo + dwi;
    vec3 dh = (dH - h * dot(h, dH)) / len;
    vec2 dp = vec2(dh.x - h.z * dn.x, dh.y - h.z * dn.y);
    if (!slope) return dp;
    float dhz = dh.z + dot(h, dn);
    float hz = max(h.z, 1e-12);
    return -(dp * hz - h.xy * dhz) / (hz * hz);
}
vec2 spc_ggxf_q(vec3 h, bool slope) { return slope ? -h.xy / max(abs(h.z), 1e-12) : h.xy; }

bool spc_ggxf_isotropic(int fmode) {
    return fmode == SPC_GGXF_FILTER_ISO_MAX || fmode == SPC_GGXF_FILTER_ISO_SUM || fmode == SPC_GGXF_FILTER_ISO_MEAN ||
           fmode == SPC_GGXF_FILTER_ISO_RECT;
}
// Ā for (o, i) in the local frame. quad: dFdxFine/dFdyFine of q (uniform control flow required).
vec3 spc_ggxf_filtered(vec3 A, vec3 o, vec3 i, int fmode, int kernel, float sigma2, float kappa, bool quad, vec3 dn0, vec3 dn1,
                       vec3 dwo0, vec3 dwo1, vec3 dwi0, vec3 dwi1) {
    if (fmode == SPC_GGXF_FILTER_NONE) return A;
    if (spc_ggxf_isotropic(fmode)) {
        return vec3(clamp(A.x + spc_ggxf_iso(fmode, dn0, dn1, sigma2, kappa), 0.0, 1.0), A.y,
                    clamp(A.z + spc_ggxf_iso(fmode, dn0, dn1, sigma2, kappa), 0.0, 1.0));
    }
    bool slope = fmode == SPC_GGXF_FILTER_SLOPE;
    vec3 H = o + i;
    float len = length(H);
    vec3 h = H / len;
    vec2 du, dv;
    if (quad) {
        vec2 q = spc_ggxf_q(h, slope);
        du = dFdxFine(q);
        dv = dFdyFine(q);
    } else {
        du = spc_ggxf_dq(h, len, dwo0, dwi0, dn0, slope);
        dv = spc_ggxf_dq(h, len, dwo1, dwi1, dn1, slope);
    }
    if (fmode == SPC_GGXF_FILTER_PROJECTED) return spc_ggxf_projected(A, du, dv, kernel, sigma2, kappa);
    return spc_ggxf_additive(A, du, dv, kernel, sigma2, kappa);
}

// Polygon queries (FilteredGgxLobe::integratePolygon): the LTC of GGX with the sampling matrix Ā_s, i.e. the filter
// evaluated at the mirror configuration (h = n, directional light) with the analytic derivatives (for normal-based
// filters and `none` the exact filtered matrix), through its principal axes in the anisotropic table
// (spc_ltc_ggx_matrix), times F0·mag + (1 − F0)·fres with the Schlick F0. In quad-derivative mode dFdxFine(N) is
// taken before the polygon branch returns: keep q.kind uniform over a 2×2 quad.
void spc_bsdf_ggx_filtered(SpeculaClosureQuery q, SpeculaShadingInputs s, vec3 weight, vec2 alpha, vec3 covariance, int filter_,
                           int kernel, float sigma2, float kappa, int derivatives, float derivative_scale, vec3 f0, vec3 normal,
                           vec3 tangent, vec3 dndx, vec3 dndy, sampler2D ltc_matrix, sampler2D ltc_amplitude,
                           sampler2D ltc_anisotropic, out SpeculaClosure bsdf, out vec2 filtered_alpha) {
    bsdf = spc_closure_none();
    filtered_alpha = alpha;
    int fmode = filter_;
    // A = diag(α²) + 2Σ, Σ made positive semi-definite; τ = det A (A.4).
    vec2 a = clamp(alpha, vec2(1e-4), vec2(0.999));
    // covariance = (var_x, var_y, cov_xy), as texture.lean outputs it
    float sxx = max(covariance.x, 0.0), syy = max(covariance.y, 0.0), lim = sqrt(sxx * syy);
    vec3 A = vec3(a.x * a.x + 2.0 * sxx, 2.0 * clamp(covariance.z, -lim, lim), a.y * a.y + 2.0 * syy);
    float tau = max(spc_ggxf_det(A), 1e-37);
    sigma2 = max(sigma2, 0.0);
    kappa = max(kappa, 0.0);
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    vec3 o = spc_to_local(q.wo, T, B, N);
    vec3 i = spc_to_local(q.wi, T, B, N);
    bool quad = derivatives == SPC_DERIVATIVES_QUAD;
    float sc = derivative_scale;
    vec3 dn0, dn1;
    if (quad) {
        dn0 = spc_to_local(dFdxFine(N), T, B, N) * sc;
        dn1 = spc_to_local(dFdyFine(N), T, B, N) * sc;
    } else {
        dn0 = spc_to_local(dndx, T, B, N) * sc;
        dn1 = spc_to_local(dndy, T, B, N) * sc;
    }
    vec3 dwo0 = spc_to_local(s.dwodx, T, B, N) * sc, dwo1 = spc_to_local(s.dwody, T, B, N) * sc;
    vec3 dwi0 = vec3(0.0), dwi1 = vec3(0.0);
    if (!isinf(q.light_distance) && q.light_distance > 0.0) {
        vec3 dp0 = spc_to_local(s.dPdx, T, B, N) * sc, dp1 = spc_to_local(s.dPdy, T, B, N) * sc;
        dwi0 = -(dp0 - i * dot(i, dp0)) / q.light_distance;
        dwi1 = -(dp1 - i * dot(i, dp1)) / q.light_distance;
    }
    // The sampling matrix Ā_s (FilteredGgxLobe::setSamplingFromMirror): Ā at the mirror configuration (h = n,
    // directional light) from the analytic derivatives, whose normal derivatives are the dndx/dndy inputs whatever the
    // derivative source (the CPU lobe's Differentials); normal-based filters use the mode's normal derivatives.
    // Also the debug output filtered_alpha.
    bool isoFilter = spc_ggxf_isotropic(fmode);
    vec3 dna0 = isoFilter ? dn0 : spc_to_local(dndx, T, B, N) * sc, dna1 = isoFilter ? dn1 : spc_to_local(dndy, T, B, N) * sc;
    vec3 Am = (o.z > 0.0 || isoFilter) ? spc_ggxf_filtered(A, o, vec3(-o.x, -o.y, o.z), fmode, kernel, sigma2, kappa, false, dna0, dna1, dwo0, dwo1,
                                                           vec3(0.0), vec3(0.0))
                                       : A;
    filtered_alpha = sqrt(vec2(Am.x, Am.z));
    if (q.kind != SPC_QUERY_DIRECTION) {  // polygon and environment queries
        if (o.z <= 0.0) return;
        mat3 invM;
        vec2 magFres;
        spc_ltc_ggx_matrix(ltc_matrix, ltc_amplitude, ltc_anisotropic, Am, o, invM, magFres);
        vec3 p[4];
        spc_ltc_local_polygon(q, T, B, N, p);
        float e = spc_ltc_integrate(invM, p, q.vertex_count, q.horizon, ltc_amplitude);
        bsdf.f = weight * (spc_ltc_fresnel_scale(f0, magFres) * e);
        if (q.kind == SPC_QUERY_ENVIRONMENT) bsdf.f *= spc_ltc_environment(invM, T, B, N);
        return;
    }
    // Quad derivatives are taken before any divergent return (dFdxFine needs the whole quad).
    vec3 Ab = spc_ggxf_filtered(A, o, i, fmode, kernel, sigma2, kappa, quad, dn0, dn1, dwo0, dwo1, dwi0, dwi1);
    if (o.z <= 0.0 || i.z <= 0.0) return;
    vec3 H = o + i;
    float len = sqrt(dot(H, H));
    if (len == 0.0) return;
    vec3 h = H / len;
    float d = spc_ggxf_ndf(h, Ab, tau);
    float g = spc_ggx_g2_matrix(o, i, Ab);
    vec3 F = spc_fresnel_schlick(dot(o, h), f0);
    bsdf.f = weight * (F * (d * g / (4.0 * o.z)));
}
