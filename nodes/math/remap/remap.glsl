// math.remap.*: out_min + (x - in_min) / (in_max - in_min) * (out_max - out_min); out_min if in_max == in_min.
float spc_remap1(float x, float a, float b, float p, float q) {
    float d = b - a;
    return d == 0.0 ? p : p + (x - a) / d * (q - p);
}
void spc_math_remap(float x, float in_min, float in_max, float out_min, float out_max, out float out_) {
    out_ = spc_remap1(x, in_min, in_max, out_min, out_max);
}
void spc_math_remap(vec2 x, vec2 in_min, vec2 in_max, vec2 out_min, vec2 out_max, out vec2 out_) {
    vec2 a = in_min, b = in_max, p = out_min, q = out_max;
    out_ = vec2(spc_remap1(x.x, a.x, b.x, p.x, q.x), spc_remap1(x.y, a.y, b.y, p.y, q.y));
}
void spc_math_remap(vec3 x, vec3 in_min, vec3 in_max, vec3 out_min, vec3 out_max, out vec3 out_) {
    vec3 a = in_min, b = in_max, p = out_min, q = out_max;
    out_ = vec3(spc_remap1(x.x, a.x, b.x, p.x, q.x), spc_remap1(x.y, a.y, b.y, p.y, q.y), spc_remap1(x.z, a.z, b.z, p.z, q.z));
}
