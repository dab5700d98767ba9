// geometry.tangent: Mesh tangent T (world) and the bitangent sign.
void spc_geometry_tangent(SpeculaShadingInputs s, out vec3 T, out float sign_) { T = s.tangent.xyz; sign_ = s.tangent.w; }
