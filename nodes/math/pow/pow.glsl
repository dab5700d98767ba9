// math.pow.*: component-wise a^b, 0 where a <= 0.
float spc_pow1(float a, float b) { return a <= 0.0 ? 0.0 : pow(a, b); }
void spc_math_pow(float a, float b, out float o) { o = spc_pow1(a, b); }
void spc_math_pow(vec2 a, vec2 b, out vec2 o) { o = vec2(spc_pow1(a.x, b.x), spc_pow1(a.y, b.y)); }
void spc_math_pow(vec3 a, vec3 b, out vec3 o) { o = vec3(spc_pow1(a.x, b.x), spc_pow1(a.y, b.y), spc_pow1(a.z, b.z)); }
