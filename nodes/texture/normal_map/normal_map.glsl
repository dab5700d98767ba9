// texture.normal_map: tangent-space normal map -> world normal (same operations as the CPU).
void spc_texture_normal_map(vec3 color, float strength, int convention, vec3 normal, vec3 tangent, float sign_, out vec3 normal_out) {
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
}
