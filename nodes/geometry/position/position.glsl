// geometry.position: World-space position P and its screen-space derivatives.
void spc_geometry_position(SpeculaShadingInputs s, out vec3 P, out vec3 dPdx, out vec3 dPdy) { P = s.position; dPdx = s.dPdx; dPdy = s.dPdy; }
