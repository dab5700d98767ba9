// bsdf.dielectric: rough glass (Walter et al. 2007), the GLSL twin of the closure the CPU node builds: GgxLobe with the
// exact dielectric Fresnel (reflection) plus GgxTransmissionLobe (core/render/lobes/dielectric.h, refraction).
// Direction queries: f·cos of both; wi below the surface is the refraction (Walter 2007, Eqs. 16 and 21, radiance form).
// Polygon queries: the reflection's LTC (as bsdf.ggx); a polygon reaching below the surface sets partial (the
// refraction has no closed form). Environment queries: the reflection's split sum plus the environment along the
// refracted view direction times the transmitted fraction (1 − F).

// Refraction of the local direction o through the interface normal +z, eta = n_far / n_o (CPU: dielectric::refract);
// false on total internal reflection.
bool spc_dielectric_refract(vec3 o, float eta, out vec3 t) {
    float c = o.z;
    float sin2T = max(0.0, 1.0 - c * c) / (eta * eta);
    t = vec3(0.0, 0.0, -1.0);
    if (sin2T >= 1.0) return false;
    float cosT = sqrt(1.0 - sin2T);
    t = -o / eta + (c / eta - cosT) * vec3(0.0, 0.0, 1.0);
    return true;
}

void spc_bsdf_dielectric(SpeculaClosureQuery q, vec3 weight, vec3 reflection_tint, vec3 transmission_tint, float roughness,
                         float anisotropy, float ior, float front_facing, vec3 normal, vec3 tangent, sampler2D ltc_matrix,
                         sampler2D ltc_amplitude, sampler2D ltc_anisotropic, out SpeculaClosure bsdf) {
    bsdf = spc_closure_none();
    vec2 alpha = spc_alpha_from_roughness(roughness, anisotropy);
    float ax = max(alpha.x, 1e-4), ay = max(alpha.y, 1e-4);  // ggx::kMinAlpha
    float eta = front_facing >= 0.5 ? ior : 1.0 / ior;  // the far side's index over the viewer's
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    vec3 o = spc_to_local(q.wo, T, B, N);
    if (q.kind != SPC_QUERY_DIRECTION) {  // polygon and environment queries
        if (q.kind == SPC_QUERY_POLYGON)
            for (int k = 0; k < q.vertex_count; ++k)
                if (dot(q.polygon[k], N) < 0.0) bsdf.partial = true;  // light below the surface: sampled by the host
        if (o.z <= 0.0) return;
        mat3 invM;
        vec2 magFres;
        float e = spc_ltc_ggx_polygon(q, ltc_matrix, ltc_amplitude, ltc_anisotropic, ax, ay, o, T, B, N, invM, magFres);
        vec3 r = reflection_tint * (spc_ltc_fresnel_scale(vec3(spc_fresnel_dielectric(1.0, eta)), magFres) * e);
        if (q.kind == SPC_QUERY_ENVIRONMENT) {
            r *= spc_ltc_environment(invM, T, B, N);
            vec3 t;
            spc_dielectric_refract(o, eta, t);
            float alphaT = sqrt(ax * ay) * abs(1.0 - 1.0 / eta) * 0.5;
            r += transmission_tint * ((1.0 - spc_fresnel_dielectric(o.z, eta)) *
                                      spc_host_environment(T * t.x + B * t.y + N * t.z, alphaT));
        }
        bsdf.f = weight * r;
        return;
    }
    vec3 i = spc_to_local(q.wi, T, B, N);
    vec3 f = vec3(0.0);
    if (o.z > 0.0 && i.z > 0.0) {  // reflection: F(wo·h) D(h) G2 / (4 wo.z)
        vec3 h = o + i;
        float len = sqrt(dot(h, h));
        if (len > 0.0) {
            h /= len;
            float d = spc_ggx_ndf(h, ax, ay);
            float g = spc_ggx_g2(o, i, ax, ay);
            f += reflection_tint * (spc_fresnel_dielectric(dot(o, h), eta) * (d * g / (4.0 * o.z)));
        }
    }
    if (o.z * i.z < 0.0) {  // refraction (Walter 2007, Eq. 21 with the radiance factor 1/η'²)
        float etaP = o.z > 0.0 ? eta : 1.0 / eta;  // n_wi / n_wo
        vec3 h = o + etaP * i;
        float len = sqrt(dot(h, h));
        if (len > 0.0) {
            h /= len;
            if (h.z < 0.0) h = -h;
            float oh = dot(o, h), ih = dot(i, h);
            float denom = (ih + oh / etaP) * (ih + oh / etaP);
            if (oh * o.z > 0.0 && ih * i.z > 0.0 && denom > 0.0) {
                float d = spc_ggx_ndf(h, ax, ay);
                float g = spc_ggx_g2(o, i, ax, ay);
                float fr = spc_fresnel_dielectric(etaP >= 1.0 ? oh : ih, eta);  // from the less dense side
                f += transmission_tint * ((1.0 - fr) * d * g * abs(ih * oh) / (abs(o.z) * denom * etaP * etaP));
            }
        }
    }
    bsdf.f = weight * f;
}
