// math.remap.*: out_min + (x - in_min) / (in_max - in_min) * (out_max - out_min); out_min if in_max == in_min.
float spc_remap1(float x, float a, float b, float p, float q) {
    float d = b - a;
    return d == 0.0 ? p : p + (x - a) / d * (q - p);
}
void spc_math_remap(float x, float a, float b, float p, float q, out float o) { o = spc_remap1(x, a, b, p, q); }
void spc_math_remap(vec2 x, vec2 a, vec2 b, vec2 p, vec2 q, out vec2 o) {
    o = vec2(spc_remap1(x.x, a.x, b.x, p.x, q.x), spc_remap1(x.y, a.y, b.y, p.y, q.y));
}
void spc_math_remap(vec3 x, vec3 a, vec3 b, vec3 p, vec3 q, out vec3 o) {
    o = vec3(spc_remap1(x.x, a.x, b.x, p.x, q.x), spc_remap1(x.y, a.y, b.y, p.y, q.y), spc_remap1(x.z, a.z, b.z, p.z, q.z));
}
