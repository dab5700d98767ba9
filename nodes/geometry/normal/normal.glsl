// geometry.normal: Shading normal N (world) and its screen-space derivatives.
void spc_geometry_normal(SpeculaShadingInputs s, out vec3 N, out vec3 dNdx, out vec3 dNdy) { N = s.normal; dNdx = s.dNdx; dNdy = s.dNdy; }
