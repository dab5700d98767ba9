// The GPU preview's fragment main (plugin/preview/preview.cpp embeds this file): the shading point from the
// interpolated attributes (two-sided as on the CPU: the frame faces the viewer), then every light by its closed form,
// as Integrator::rasterLighting (core/render/integrator.cpp) computes render.integrator "raster": keep the two alike.
// The host puts before it: a material's module (with SPECULA_HOST_ENVIRONMENT), the SPC_PREVIEW_* defines, the frame
// block (frameBlockGlsl, plugin/preview/preview_frame.h: SpcPreviewLight), the shadow lookup (shadowLookupGlsl), the
// interpolated attributes v_position, v_normal, v_tangent, v_uv and the AOV outputs o_beauty … o_aux.

vec3 spc_preview_diffuse, spc_preview_specular;
void spc_preview_add(SpeculaClosure c, vec3 L) {
    spc_preview_diffuse += c.f_diffuse * L;
    spc_preview_specular += (c.f - c.f_diffuse) * L;
}
// The split sum's environment (core/render/environment_prefilter.h): the light being lit, then its prefiltered chain
// (mip level α·(levels−1)) or irradiance map, row 0 = +z, read as PrefilteredEnvironment::lookup reads them.
layout(binding = SPC_PREVIEW_ENV_BINDING) uniform sampler2D spc_env_specular;
layout(binding = SPC_PREVIEW_ENV_BINDING + 1) uniform sampler2D spc_env_irradiance;
vec3 spc_preview_env_value;
bool spc_preview_env_map;
float spc_preview_env_rotation;
vec3 spc_host_environment(vec3 dir, float alpha) {
    if (!spc_preview_env_map) return spc_preview_env_value;
    float c = cos(spc_preview_env_rotation), s = sin(spc_preview_env_rotation);
    vec3 r = vec3(c * dir.x + s * dir.y, -s * dir.x + c * dir.y, dir.z);  // environmentUv
    // GLSL leaves atan(0, 0) undefined; C++'s atan2(±0, −0) = ±π puts the exact poles at u = 0 (a plane facing +z reads
    // there, and row 0 varies with u)
    float u = (r.x == 0.0 && r.y == 0.0) ? 0.0 : 0.5 - atan(r.y, -r.x) * 0.15915494309189535;
    u -= floor(u);
    vec2 uv = vec2(u, acos(clamp(r.z, -1.0, 1.0)) * 0.31830988618379067);
    if (alpha < 0.0) return textureLod(spc_env_irradiance, uv, 0.0).rgb;
    return textureLod(spc_env_specular, uv, clamp(alpha, 0.0, 1.0) * float(SPC_PREVIEW_ENV_LEVELS - 1)).rgb;
}
// A light's shadow-map visibility at P (point, spot, directional, quad: core/render/shadow_maps.h).
float spc_preview_shadow(SpcPreviewLight l, vec3 P, vec3 Ng) {
    return spc_shadow(l.shadow, l.shadow_origin.xyz, l.shadow_axis.xyz, l.shadow_right.xyz, l.shadow_up.xyz, P, Ng);
}
// The environment's share that reaches P (environmentShadowVisibility): each shadow direction's map weighted by the
// irradiance from that direction (channel sum).
float spc_preview_environment_shadow(SpcPreviewLight l, vec3 P, vec3 Ng) {
    float E[14];
    for (int k = 0; k < 14; ++k) {
        vec3 e = spc_host_environment(spc_shadow_direction(k), -1.0);
        E[k] = e.x + e.y + e.z;
    }
    return spc_shadow_environment(l.shadow, l.shadow_origin.xyz, l.shadow_origin.w, E, P, Ng);
}
float spc_preview_spot(float c, float cos_outer, float cos_inner) {
    if (c >= cos_inner) return 1.0;
    if (c <= cos_outer) return 0.0;
    float t = (c - cos_outer) / max(cos_inner - cos_outer, 1e-6);
    return t * t * (3.0 - 2.0 * t);
}

void main() {
    vec3 P = v_position;
    vec3 wo = normalize(spc_eye.xyz - P);
    vec3 Ng = normalize(cross(dFdx(P), dFdy(P)));  // faces the viewer (screen x cross screen y)
    if (dot(Ng, wo) < 0.0) Ng = -Ng;
    vec3 N = dot(v_normal, v_normal) > 0.0 ? normalize(gl_FrontFacing ? v_normal : -v_normal) : Ng;
    vec4 T = v_tangent;
    if (dot(T.xyz, T.xyz) <= 0.0) {
        vec3 t0, b0, n0;
        spc_frame(N, vec3(0.0), t0, b0, n0);
        T = vec4(t0, 1.0);
    }
    SpeculaShadingInputs s = specula_shading_inputs(P, N, Ng, T, v_uv, wo);
    SpeculaClosure c;
    specula_material(specula_direction_query(wo, wo, 1.0 / 0.0), s, c);
    vec3 emission = c.emission;
    spc_preview_diffuse = vec3(0.0);
    spc_preview_specular = vec3(0.0);
    const float inf = 1.0 / 0.0;
    // Every specula_material call is made in uniform control flow (the light count and kind and a material's
    // partial answers are uniform): nodes take dFdxFine/dFdyFine of their own values (glint footprints, filtered
    // lobes), which needs the whole 2x2 quad. A light that does not reach the point is dropped after the call.
    // Shadows are looked up after the call, where the light reaches the point, and multiply its light.
    for (int i = 0; i < spc_counts.x; ++i) {
        SpcPreviewLight l = spc_lights[i];
        vec4 h = l.header;
        vec3 a = l.position.xyz, b = l.direction.xyz, e = l.edge_v.xyz;
        vec3 value = l.value.xyz;
        int kind = int(h.x);
        if (kind <= 1) {  // point, spot
            vec3 d = a - P;
            float d2 = dot(d, d);
            float dist = sqrt(d2);
            vec3 wi = d2 > 0.0 ? d / dist : s.geometric_normal;
            float falloff = kind == 1 ? spc_preview_spot(dot(-wi, b), h.y, h.z) : 1.0;
            specula_material(specula_direction_query(wo, wi, dist), s, c);
            if (d2 > 0.0 && dot(wi, s.geometric_normal) > 0.0 && falloff > 0.0) {
                float vis = spc_preview_shadow(l, P, s.geometric_normal);
                if (vis > 0.0) spc_preview_add(c, value * (falloff / d2) * vis);
            }
        } else if (kind == 2) {  // directional: b = towards the light
            specula_material(specula_direction_query(wo, b, inf), s, c);
            if (dot(b, s.geometric_normal) > 0.0) {
                float vis = spc_preview_shadow(l, P, s.geometric_normal);
                if (vis > 0.0) spc_preview_add(c, value * vis);
            }
        } else if (kind == 3) {  // quad: corner a, edges b and e (QuadLight::polygon's winding)
            vec3 n = normalize(cross(b, e));
            float side = dot(P - a, n);
            bool lit = !(side == 0.0 || (h.w == 0.0 && side < 0.0));
            vec3 p[4];
            if (side > 0.0) p = vec3[4](a, a + e, a + b + e, a + b);
            else p = vec3[4](a, a + b, a + b + e, a + e);
            for (int k = 0; k < 4; ++k) p[k] -= P;
            specula_material(specula_polygon_query(wo, p, 4, spc_counts.y), s, c);
            float vis = lit ? spc_preview_shadow(l, P, s.geometric_normal) : 0.0;  // from the quad's centre
            if (!c.partial) {
                if (lit) spc_preview_add(c, value * vis);
                continue;
            }
            vec3 ctr = (p[0] + p[1] + p[2] + p[3]) * 0.25;
            float dist = length(ctr);
            vec3 wi = ctr / dist;
            vec3 nl = cross(b, e);
            float area = length(nl);
            float solid_angle = area * abs(dot(wi, nl / area)) / (dist * dist);
            specula_material(specula_direction_query(wo, wi, inf), s, c);
            if (lit && dot(wi, s.geometric_normal) > 0.0) spc_preview_add(c, value * solid_angle * vis);
        } else {  // environment: the split sum over the hemisphere of the shading normal (h.y: has a map, h.z: its turn)
            spc_preview_env_value = value;
            spc_preview_env_map = h.y != 0.0;
            spc_preview_env_rotation = h.z;
            vec3 tt, bb, nn;
            spc_frame(s.normal, s.tangent.xyz, tt, bb, nn);
            const float lift = SPC_PREVIEW_HEMISPHERE_LIFT;
            vec3 p[4] = vec3[4](normalize(tt + lift * nn), normalize(bb + lift * nn), normalize(-tt + lift * nn),
                                normalize(-bb + lift * nn));
            specula_material(specula_environment_query(wo, p, spc_counts.y), s, c);
            float vis = spc_preview_environment_shadow(l, P, s.geometric_normal);
            if (!c.partial) {
                spc_preview_add(c, vec3(vis));
            } else {
                specula_material(specula_direction_query(wo, nn, inf), s, c);
                spc_preview_add(c, spc_host_environment(nn, -1.0) * 3.14159265358979 * vis);
            }
        }
    }
    o_beauty = vec4(emission + spc_preview_diffuse + spc_preview_specular, 1.0);
    o_diffuse = vec4(spc_preview_diffuse, 1.0);
    o_specular = vec4(spc_preview_specular, 1.0);
    o_normal = vec4(s.normal, 1.0);
    o_aux = vec4(dot(P - spc_eye.xyz, spc_forward.xyz), v_uv, 1.0);
}
