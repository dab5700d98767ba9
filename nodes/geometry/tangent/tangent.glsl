// geometry.tangent: Mesh tangent T (world) and the bitangent sign.
void spc_geometry_tangent(SpeculaShadingInputs s, out vec3 T, out float sgn) { T = s.tangent.xyz; sgn = s.tangent.w; }
