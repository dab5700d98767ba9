// bsdf.beckmann_lean: f·cos = weight · F(wo·h) D(h) G2(wo, wi) / (4 e(wo)), the GLSL twin of BeckmannLeanLobe
// (nodes/bsdf/beckmann_lean/beckmann_lean.h): D(h) = P22(slope(h)) / hz^4 with P22 the Gaussian of mean `slope` and
// covariance Σ + (α²/2) I (Olano & Baker 2010), Smith Λ of the shifted Gaussian over its mean plane,
// Λ = A⁺/e − 1 with e(w) = w.z − w.xy·slope, G2 = 1/(1 + Λo + Λi); zero below the mean plane (e ≤ 0).
float spc_lean_normal_cdf(float d) {
    float x = abs(d) * 0.70710678118654752;
    float t = 1.0 / (1.0 + 0.3275911 * x);
    float poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    float halfc = 0.5 * poly * exp(-x * x);
    return d >= 0.0 ? 1.0 - halfc : halfc;
}
float spc_lean_lambda(vec3 w, vec2 mean, float a, float b, float c) {
    float e = w.z - (w.x * mean.x + w.y * mean.y);
    if (w.z <= 0.0 || e <= 0.0) return 1e30;
    float s2 = w.x * w.x * a + 2.0 * w.x * w.y * c + w.y * w.y * b;
    float ap;
    if (s2 > 0.0) {
        float s = sqrt(s2);
        float d = e / s;
        ap = e * spc_lean_normal_cdf(d) + s * 0.39894228040143268 * exp(-0.5 * d * d);
    } else {
        ap = e;
    }
    return max(ap / e - 1.0, 0.0);
}
// Polygon queries (BeckmannLeanLobe::integratePolygon): the LTC of an equivalent GGX through shared/ltc.glsl.
void spc_bsdf_beckmann_lean(SpeculaClosureQuery q, vec3 weight, float roughness, vec2 slope, vec3 covariance, int fresnel,
                            vec3 f0, float ior, vec3 eta, vec3 k, vec3 normal, vec3 tangent, sampler2D ltc_matrix,
                            sampler2D ltc_amplitude, sampler2D ltc_anisotropic, out SpeculaClosure bsdf) {
    bsdf = spc_closure_none();
    // makeSlopeGaussian: PSD projection of the LEAN covariance, plus α²/2 per axis (α = roughness², >= 1e-3).
    float xx = max(covariance.x, 0.0), yy = max(covariance.y, 0.0);
    float lim = sqrt(xx * yy);
    float xy = min(max(covariance.z, -lim), lim);
    float al = max(roughness * roughness, 1e-3);
    float v = 0.5 * al * al;
    float a = xx + v, b = yy + v, c = xy;
    float det = a * b - c * c;
    if (q.kind != SPC_QUERY_DIRECTION) {  // polygon and environment queries
        vec3 T, B, N;
        spc_frame(normal, tangent, T, B, N);
        vec3 lo = spc_to_local(q.wo, T, B, N);
        if (lo.z <= 0.0) return;
        // The equivalent GGX (BeckmannLeanLobe::polygonLtc, docs/ltc-tables.md): the frame tilted to the mean normal
        // n' = normalize(−μx, −μy, 1), roughness matrix α² = 1.5 Σ (measured best against this lobe).
        vec3 n = normalize(vec3(-slope.x, -slope.y, 1.0));
        vec3 t = normalize(vec3(1.0, 0.0, 0.0) - n * n.x);
        mat3 tilt = transpose(mat3(t, cross(n, t), n));  // rows t, b, n: lobe frame -> tilted frame
        mat3 invM;
        vec2 magFres;
        spc_ltc_ggx_matrix(ltc_matrix, ltc_amplitude, ltc_anisotropic, 1.5 * vec3(a, c, b), tilt * lo, invM, magFres);
        invM = invM * tilt;
        vec3 p[4];
        spc_ltc_local_polygon(q, T, B, N, p);
        float e = spc_ltc_integrate(invM, p, q.vertex_count, q.horizon, ltc_amplitude);
        bsdf.f = weight * (spc_ltc_fresnel_scale(spc_fresnel_f0(fresnel, f0, ior, eta, k), magFres) * e);
        if (q.kind == SPC_QUERY_ENVIRONMENT) bsdf.f *= spc_ltc_environment(invM, T, B, N);
        return;
    }
    vec3 o, i, h;
    if (!spc_reflection_local(q.wo, q.wi, normal, tangent, o, i, h)) return;
    if (h.z <= 0.0) return;
    float eo = o.z - (o.x * slope.x + o.y * slope.y);
    if (eo <= 0.0 || i.z - (i.x * slope.x + i.y * slope.y) <= 0.0) return;
    float z2 = h.z * h.z;
    float dx = -h.x / h.z - slope.x, dy = -h.y / h.z - slope.y;
    float qf = (b * dx * dx - 2.0 * c * dx * dy + a * dy * dy) / det;
    float d = exp(-0.5 * qf) / (2.0 * SPC_PI * sqrt(det)) / (z2 * z2);
    if (d == 0.0) return;
    float g = 1.0 / (1.0 + spc_lean_lambda(o, slope, a, b, c) + spc_lean_lambda(i, slope, a, b, c));
    float val = d * g / (4.0 * eo);
    float cw = dot(o, h);
    vec3 F = spc_fresnel_eval(fresnel, cw, f0, ior, eta, k);
    bsdf.f = weight * (F * val);
}
