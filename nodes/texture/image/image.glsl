// texture.image: filtered lookup with explicit gradients. The resource 'image' is the working-space image's MIP chain
// as the host built it (GlMipChain, core/texture/gl_mip_chain.h: every level given), rows bottom-up (v = 0 bottom),
// missing channels expanded like TextureStore (grey -> rgb, alpha = 1); the wrap mode is sampler state listed in the
// module's resource manifest (the 'wrap' argument documents it).
// The footprint filter is GlMipChain::anisotropic step for step: EXT_texture_filter_anisotropic's probes with the LOD
// computed here and passed to textureLod, so every GL implementation blends the same texels by the same weights
// (textureGrad would leave the LOD and the anisotropy to the implementation: llvmpipe's differed from the CPU's).
vec4 spc_texture_image_filtered(sampler2D image, vec2 st, vec2 dx, vec2 dy) {
    vec2 size = vec2(textureSize(image, 0));
    vec2 j1 = dx * size, j2 = dy * size;
    float l1 = sqrt(dot(j1, j1)), l2 = sqrt(dot(j2, j2));
    float pmax = max(l1, l2), pmin = min(l1, l2);
    if (!(pmax > 0.0)) return textureLod(image, st, 0.0);
    // kGlAnisoRatioSlack = 1e-3, kGlMaxAnisotropy = 16
    int n = pmin > 0.0 ? int(min(ceil(pmax / pmin - 1e-3), 16.0)) : 16;
    n = max(n, 1);
    vec2 major = l1 >= l2 ? dx : dy;
    float lambda = max(log2(pmax / float(n)), 0.0);
    vec4 sum = vec4(0.0);
    for (int i = 0; i < n; ++i) {
        float t = (float(i) + 0.5) / float(n) - 0.5;
        sum += textureLod(image, st + major * t, lambda);
    }
    return sum / float(n);
}

void spc_texture_image(sampler2D image, int wrap, vec2 uv, vec2 duvdx, vec2 duvdy, float uv_scale, out vec3 color,
                       out float alpha, out vec3 dcolor_du, out vec3 dcolor_dv) {
    vec2 st = uv * uv_scale, dx = duvdx * uv_scale, dy = duvdy * uv_scale;
    vec4 c = spc_texture_image_filtered(image, st, dx, dy);
    color = c.rgb;
    alpha = c.a;
    // Texture gradient: central differences one level-0 texel apart with the same footprint (CPU twin).
    vec2 h = 1.0 / vec2(textureSize(image, 0));
    dcolor_du = (spc_texture_image_filtered(image, st + vec2(h.x, 0.0), dx, dy).rgb -
                 spc_texture_image_filtered(image, st - vec2(h.x, 0.0), dx, dy).rgb) * (uv_scale / (2.0 * h.x));
    dcolor_dv = (spc_texture_image_filtered(image, st + vec2(0.0, h.y), dx, dy).rgb -
                 spc_texture_image_filtered(image, st - vec2(0.0, h.y), dx, dy).rgb) * (uv_scale / (2.0 * h.y));
}
