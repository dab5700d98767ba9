// fresnel.conductor: Exact conductor Fresnel reflectance for a complex IOR eta + i k per RGB channel (unpolarised average of r_s and r_p).
void spc_fresnel_conductor_node(vec3 eta, vec3 k, float cos_theta, out vec3 F) { F = vec3(spc_fresnel_conductor(cos_theta, eta.x, k.x), spc_fresnel_conductor(cos_theta, eta.y, k.y), spc_fresnel_conductor(cos_theta, eta.z, k.z)); }
