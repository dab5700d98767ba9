// math.dot.*: dot product (summed left to right like the CPU).
void spc_math_dot(vec2 a, vec2 b, out float out_) { out_ = a.x * b.x + a.y * b.y; }
void spc_math_dot(vec3 a, vec3 b, out float out_) { out_ = a.x * b.x + a.y * b.y + a.z * b.z; }
