// texture.image: filtered lookup with explicit gradients. The resource 'image' is the working-space, MIP-mapped image,
// rows bottom-up (v = 0 bottom), missing channels expanded like TextureStore (grey -> rgb, alpha = 1); the wrap mode
// is sampler state listed in the module's resource manifest (the 'wrap' argument documents it).
void spc_texture_image(sampler2D image, int wrap, vec2 uv, vec2 duvdx, vec2 duvdy, float uv_scale, out vec3 color,
                       out float alpha, out vec3 dcolor_du, out vec3 dcolor_dv) {
    vec2 st = uv * uv_scale, dx = duvdx * uv_scale, dy = duvdy * uv_scale;
    vec4 c = textureGrad(image, st, dx, dy);
    color = c.rgb;
    alpha = c.a;
    // Texture gradient: central differences one level-0 texel apart with the same footprint (CPU twin).
    vec2 h = 1.0 / vec2(textureSize(image, 0));
    dcolor_du = (textureGrad(image, st + vec2(h.x, 0.0), dx, dy).rgb - textureGrad(image, st - vec2(h.x, 0.0), dx, dy).rgb) *
                (uv_scale / (2.0 * h.x));
    dcolor_dv = (textureGrad(image, st + vec2(0.0, h.y), dx, dy).rgb - textureGrad(image, st - vec2(0.0, h.y), dx, dy).rgb) *
                (uv_scale / (2.0 * h.y));
}
