// math.normalize.*: v / sqrt(v.v), 0 for the zero vector (explicit sqrt/divide like the CPU).
void spc_math_normalize(vec2 v, out vec2 out_) {
    float l2 = v.x * v.x + v.y * v.y;
    out_ = l2 > 0.0 ? v / sqrt(l2) : vec2(0.0);
}
void spc_math_normalize(vec3 v, out vec3 out_) {
    float l2 = v.x * v.x + v.y * v.y + v.z * v.z;
    out_ = l2 > 0.0 ? v / sqrt(l2) : vec3(0.0);
}
