// fresnel.dielectric: Exact unpolarised dielectric Fresnel reflectance for relative IOR (Walter et al. 2007, Eq. 22); 1 under total internal reflection.
void spc_fresnel_dielectric_node(float ior, float cos_theta, out float F) { F = spc_fresnel_dielectric(cos_theta, ior); }
