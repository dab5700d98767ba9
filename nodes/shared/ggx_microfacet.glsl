// The anisotropic GGX microfacet distribution and its Smith Λ, shared by bsdf.ggx and bsdf.dielectric (CPU: ggx::ndf and
// ggx::lambda in core/render/lobes/ggx.h). D: Walter et al. 2007, Eq. 33; Λ: Heitz 2014, Eq. 86.
float spc_ggx_ndf(vec3 h, float ax, float ay) {
    if (h.z <= 0.0) return 0.0;
    float hx = h.x / ax, hy = h.y / ay;
    float e = hx * hx + hy * hy + h.z * h.z;
    return 1.0 / (SPC_PI * ax * ay * e * e);
}
float spc_ggx_lambda(vec3 w, float ax, float ay) {
    float z2 = w.z * w.z;
    if (z2 <= 0.0) return 1e30;
    float px = ax * w.x, py = ay * w.y;
    float a2tan2 = (px * px + py * py) / z2;
    return 0.5 * (-1.0 + sqrt(1.0 + a2tan2));
}
