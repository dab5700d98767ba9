// texture.normal_map: tangent-space normal map -> world normal (same operations as the CPU).
void spc_texture_normal_map(vec3 color, float strength, int convention, vec3 normal, vec3 tangent, float sign_, vec3 dcolor_du,
                            vec3 dcolor_dv, vec2 duvdx, vec2 duvdy, vec3 surface_dndx, vec3 surface_dndy,
                            out vec3 normal_out, out vec3 dndx, out vec3 dndy) {
    vec3 ts = color * 2.0 - vec3(1.0);
    if (convention == SPC_NORMAL_MAP_DIRECTX) ts.y = -ts.y;
    ts.x *= strength;
    ts.y *= strength;
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    vec3 b = sign_ < 0.0 ? -B : B;
    vec3 n = ts.x * T + ts.y * b + ts.z * N;
    float l2 = dot(n, n);
    normal_out = l2 > 0.0 ? n / sqrt(l2) : N;
    // dn = (I - n n^T) dm / |m| (CPU twin: first order, the rotation of T and B with the surface ignored).
    float len = l2 > 0.0 ? sqrt(l2) : 1.0;
    vec3 dts = (dcolor_du * duvdx.x + dcolor_dv * duvdx.y) * 2.0;
    if (convention == SPC_NORMAL_MAP_DIRECTX) dts.y = -dts.y;
    dts.x *= strength;
    dts.y *= strength;
    vec3 dm = dts.x * T + dts.y * b + dts.z * N + ts.z * surface_dndx;
    dndx = (dm - normal_out * dot(normal_out, dm)) / len;
    dts = (dcolor_du * duvdy.x + dcolor_dv * duvdy.y) * 2.0;
    if (convention == SPC_NORMAL_MAP_DIRECTX) dts.y = -dts.y;
    dts.x *= strength;
    dts.y *= strength;
    dm = dts.x * T + dts.y * b + dts.z * N + ts.z * surface_dndy;
    dndy = (dm - normal_out * dot(normal_out, dm)) / len;
}
