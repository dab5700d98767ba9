// fresnel.schlick: Schlick's approximation F0 + (1 - F0)(1 - cos)^5 (Schlick 1994, Eq. 24).
void spc_fresnel_schlick_node(vec3 f0, float cos_theta, out vec3 F) { F = spc_fresnel_schlick(cos_theta, f0); }
