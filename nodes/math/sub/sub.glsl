// math.sub.*: component-wise a - b.
void spc_math_sub(float a, float b, out float out_) { out_ = a - b; }
void spc_math_sub(vec2 a, vec2 b, out vec2 out_) { out_ = a - b; }
void spc_math_sub(vec3 a, vec3 b, out vec3 out_) { out_ = a - b; }
