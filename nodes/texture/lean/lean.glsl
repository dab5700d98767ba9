// texture.lean: LEAN mapping (Olano & Baker 2010). The footprint-filtered slope moments of a tangent-space normal
// map and the Gaussian they define: mean slope / mean normal, (σx, σy, ρ) and Σ = E[xxᵀ] − E[x]E[x]ᵀ.
// Sampler layout (LeanPyramid::glslPackedLevel, core/texture/lean_moments.h): one mipmapped RGBA32F texture, level
// l interleaves rows: 2j = (x, y, x², y²), 2j+1 = (xy, h_l, levels, 0); level l has max(1, w0 >> l) x max(1, h0 >> l) moments. Filtering is done here with texelFetch,
// step for step as LeanPyramid::lookup (bilinear, trilinear at λ, EXT_texture_filter_anisotropic probes).
int spc_lean_wrap(int i, int n, int wrap) {
    if (wrap == SPC_LEAN_WRAP_CLAMP) return clamp(i, 0, n - 1);
    return i - n * int(floor(float(i) / float(n)));
}
void spc_lean_bilinear(sampler2D tex, int l, vec2 uv, int wrap, out vec4 a, out float b) {
    // Level sizes from level 0 (GL floor rule) rather than textureSize(tex, l): sizes queried at a per-pixel
    // varying LOD were unreliable on llvmpipe (Mesa 22.3) and the rule is exact by construction.
    int w = max(1, textureSize(tex, 0).x >> l);
    int h = max(1, int(texelFetch(tex, ivec2(0, 1), 0).g) >> l);
    float s = uv.x * float(w) - 0.5, t = uv.y * float(h) - 0.5;
    float fs = floor(s), ft = floor(t);
    int i0 = int(fs), j0 = int(ft);
    float fa = s - fs, fb = t - ft;
    int x0 = spc_lean_wrap(i0, w, wrap), x1 = spc_lean_wrap(i0 + 1, w, wrap);
    int y0 = spc_lean_wrap(j0, h, wrap), y1 = spc_lean_wrap(j0 + 1, h, wrap);
    float w00 = (1.0 - fa) * (1.0 - fb), w10 = fa * (1.0 - fb), w01 = (1.0 - fa) * fb, w11 = fa * fb;
    a = texelFetch(tex, ivec2(x0, 2 * y0), l) * w00;
    b = texelFetch(tex, ivec2(x0, 2 * y0 + 1), l).r * w00;
    a += texelFetch(tex, ivec2(x1, 2 * y0), l) * w10;
    b += texelFetch(tex, ivec2(x1, 2 * y0 + 1), l).r * w10;
    a += texelFetch(tex, ivec2(x0, 2 * y1), l) * w01;
    b += texelFetch(tex, ivec2(x0, 2 * y1 + 1), l).r * w01;
    a += texelFetch(tex, ivec2(x1, 2 * y1), l) * w11;
    b += texelFetch(tex, ivec2(x1, 2 * y1 + 1), l).r * w11;
}
void spc_lean_trilinear(sampler2D tex, int top, float lambda, vec2 uv, int wrap, out vec4 a, out float b) {
    if (!(lambda > 0.0)) {
        spc_lean_bilinear(tex, 0, uv, wrap, a, b);
        return;
    }
    if (lambda >= float(top)) {
        spc_lean_bilinear(tex, top, uv, wrap, a, b);
        return;
    }
    float fl = floor(lambda);
    int l0 = int(fl);
    float f = lambda - fl;
    vec4 a0;
    float b0;
    spc_lean_bilinear(tex, l0, uv, wrap, a0, b0);
    a = a0 * (1.0 - f);
    b = b0 * (1.0 - f);
    if (f > 0.0) {
        vec4 a1;
        float b1;
        spc_lean_bilinear(tex, l0 + 1, uv, wrap, a1, b1);
        a += a1 * f;
        b += b1 * f;
    }
}
// filt: SPC_LEAN_FILTER_* (none reads level 0). Returns the moments (x, y, x², y²) and xy.
void spc_lean_lookup(sampler2D tex, vec2 uv, vec2 duvdx, vec2 duvdy, int filt, int wrap, out vec4 a, out float b) {
    if (filt == SPC_LEAN_FILTER_NONE) {
        spc_lean_bilinear(tex, 0, uv, wrap, a, b);
        return;
    }
    int top = int(texelFetch(tex, ivec2(0, 1), 0).b) - 1;
    vec2 size = vec2(float(textureSize(tex, 0).x), texelFetch(tex, ivec2(0, 1), 0).g);
    vec2 j1 = duvdx * size, j2 = duvdy * size;
    float l1 = sqrt(dot(j1, j1)), l2 = sqrt(dot(j2, j2));
    if (filt == SPC_LEAN_FILTER_TRILINEAR) {
        float rho = max(l1, l2);
        if (rho > 0.0) spc_lean_trilinear(tex, top, log2(rho), uv, wrap, a, b);
        else spc_lean_bilinear(tex, 0, uv, wrap, a, b);
        return;
    }
    float pmax = max(l1, l2), pmin = min(l1, l2);
    if (!(pmax > 0.0)) {
        spc_lean_bilinear(tex, 0, uv, wrap, a, b);
        return;
    }
    const int maxAniso = 16;
    // anisotropicProbeCount (core/texture/gl_mip_chain.h): near-isotropic footprints take one probe on both sides.
    int na = pmin > 0.0 ? int(min(ceil(pmax / pmin - 1e-3), float(maxAniso))) : maxAniso;
    int n = max(1, na);
    vec2 major = l1 >= l2 ? duvdx : duvdy;
    float lambda = log2(pmax / float(n));
    float wgt = 1.0 / float(n);
    a = vec4(0.0);
    b = 0.0;
    for (int i = 0; i < n; ++i) {
        float t = (float(i) + 0.5) / float(n) - 0.5;
        vec4 pa;
        float pb;
        spc_lean_trilinear(tex, top, lambda, uv + major * t, wrap, pa, pb);
        a += pa * wgt;
        b += pb * wgt;
    }
}
void spc_texture_lean(sampler2D moments, int convention, int filter_, int correlation, int wrap, float strength, vec2 uv,
                      vec2 duvdx, vec2 duvdy, vec3 normal, vec3 tangent, float sign_, float uv_scale, out vec3 normal_out,
                      out vec2 slope, out vec3 sigma_rho, out vec3 covariance) {
    vec4 m;
    float mxy;
    spc_lean_lookup(moments, uv * uv_scale, duvdx * uv_scale, duvdy * uv_scale, filter_, wrap, m, mxy);
    // leanStats (core/texture/lean_moments.cpp): flip y for DirectX maps and for left-handed frames.
    bool flip = (convention == SPC_NORMAL_MAP_DIRECTX) != (sign_ < 0.0);
    float sy = flip ? -1.0 : 1.0;
    vec2 mean = vec2(m.x, m.y * sy) * strength;
    float s2 = strength * strength;
    float varX = max(m.z - m.x * m.x, 0.0) * s2;
    float varY = max(m.w - m.y * m.y, 0.0) * s2;
    float cov = correlation == SPC_LEAN_CORRELATION_IGNORE ? 0.0 : (mxy - m.x * m.y) * sy * s2;
    float sx = sqrt(varX), sY = sqrt(varY);
    float lim = sx * sY;
    cov = min(max(cov, -lim), lim);
    float rho = lim > 0.0 ? cov / lim : 0.0;
    vec3 nt = vec3(-mean.x, -mean.y, 1.0);
    nt = nt / sqrt(dot(nt, nt));
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    vec3 nw = nt.x * T + nt.y * B + nt.z * N;
    float l2 = dot(nw, nw);
    normal_out = l2 > 0.0 ? nw / sqrt(l2) : N;
    slope = mean;
    sigma_rho = vec3(sx, sY, rho);
    covariance = vec3(varX, varY, cov);
}
