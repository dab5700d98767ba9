// math.pow.*: component-wise a^b, 0 where a <= 0.
float spc_pow1(float a, float b) { return a <= 0.0 ? 0.0 : pow(a, b); }
void spc_math_pow(float a, float b, out float out_) { out_ = spc_pow1(a, b); }
void spc_math_pow(vec2 a, vec2 b, out vec2 out_) { out_ = vec2(spc_pow1(a.x, b.x), spc_pow1(a.y, b.y)); }
void spc_math_pow(vec3 a, vec3 b, out vec3 out_) { out_ = vec3(spc_pow1(a.x, b.x), spc_pow1(a.y, b.y), spc_pow1(a.z, b.z)); }
