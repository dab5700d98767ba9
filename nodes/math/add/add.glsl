// math.add.*: component-wise a + b.
void spc_math_add(float a, float b, out float out_) { out_ = a + b; }
void spc_math_add(vec2 a, vec2 b, out vec2 out_) { out_ = a + b; }
void spc_math_add(vec3 a, vec3 b, out vec3 out_) { out_ = a + b; }
