// geometry.geometric_normal: Geometric normal Ng (world).
void spc_geometry_geometric_normal(SpeculaShadingInputs s, out vec3 Ng) { Ng = s.geometric_normal; }
