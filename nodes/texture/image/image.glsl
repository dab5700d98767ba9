// texture.image: filtered lookup with explicit gradients. The resource 'image' is the working-space, MIP-mapped image,
// rows bottom-up (v = 0 bottom), missing channels expanded like TextureStore (grey -> rgb, alpha = 1); the wrap mode
// is sampler state listed in the module's resource manifest (the 'wrap' argument documents it).
void spc_texture_image(sampler2D image, int wrap, vec2 uv, vec2 duvdx, vec2 duvdy, float uv_scale, out vec3 color,
                       out float alpha) {
    vec4 c = textureGrad(image, uv * uv_scale, duvdx * uv_scale, duvdy * uv_scale);
    color = c.rgb;
    alpha = c.a;
}
