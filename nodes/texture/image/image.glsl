// texture.image: filtered lookup with explicit gradients. Wrap is sampler state set by the host from
// the emitter's texture table; the sampler must hold the working-space, MIP-mapped image, rows
// bottom-up (v = 0 bottom) and missing channels expanded like TextureStore (grey -> rgb, alpha = 1).
void spc_texture_image(sampler2D tex, int wrap, vec2 uv, vec2 duvdx, vec2 duvdy, out vec3 color, out float alpha) {
    vec4 c = textureGrad(tex, uv, duvdx, duvdy);
    color = c.rgb;
    alpha = c.a;
}
