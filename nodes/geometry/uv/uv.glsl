// geometry.uv: Texture coordinates uv0 and their screen-space derivatives.
// GPU derivatives are per pixel: the sample footprint and the pixel footprint coincide.
void spc_geometry_uv(SpeculaShadingInputs s, out vec2 uv, out vec2 duvdx, out vec2 duvdy, out vec2 pixel_duvdx,
                     out vec2 pixel_duvdy) {
    uv = s.uv;
    duvdx = s.duvdx;
    duvdy = s.duvdy;
    pixel_duvdx = s.duvdx;
    pixel_duvdy = s.duvdy;
}
