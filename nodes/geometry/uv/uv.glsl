// geometry.uv: Texture coordinates uv0 and their screen-space derivatives.
void spc_geometry_uv(SpeculaShadingInputs s, out vec2 uv, out vec2 duvdx, out vec2 duvdy) { uv = s.uv; duvdx = s.duvdx; duvdy = s.duvdy; }
