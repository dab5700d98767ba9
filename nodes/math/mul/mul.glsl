// math.mul.*: component-wise a * b.
void spc_math_mul(float a, float b, out float o) { o = a * b; }
void spc_math_mul(vec2 a, vec2 b, out vec2 o) { o = a * b; }
void spc_math_mul(vec3 a, vec3 b, out vec3 o) { o = a * b; }
