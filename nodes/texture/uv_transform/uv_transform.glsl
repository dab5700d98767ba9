// texture.uv_transform: uv' = R(rotation) (uv * scale) + offset; the footprint is rotated and scaled alike (CPU twin).
void spc_texture_uv_transform(vec2 uv, vec2 duvdx, vec2 duvdy, vec2 scale, float rotation, vec2 offset, out vec2 uv_out,
                              out vec2 duvdx_out, out vec2 duvdy_out) {
    float a = rotation * (SPC_PI / 180.0), cs = cos(a), sn = sin(a);
    vec2 p = uv * scale, dx = duvdx * scale, dy = duvdy * scale;
    uv_out = vec2(cs * p.x - sn * p.y, sn * p.x + cs * p.y) + offset;
    duvdx_out = vec2(cs * dx.x - sn * dx.y, sn * dx.x + cs * dx.y);
    duvdy_out = vec2(cs * dy.x - sn * dy.y, sn * dy.x + cs * dy.y);
}
