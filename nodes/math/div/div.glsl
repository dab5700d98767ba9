// math.div.*: component-wise a / b, 0 where b == 0.
float spc_div1(float a, float b) { return b == 0.0 ? 0.0 : a / b; }
void spc_math_div(float a, float b, out float out_) { out_ = spc_div1(a, b); }
void spc_math_div(vec2 a, vec2 b, out vec2 out_) { out_ = vec2(spc_div1(a.x, b.x), spc_div1(a.y, b.y)); }
void spc_math_div(vec3 a, vec3 b, out vec3 out_) { out_ = vec3(spc_div1(a.x, b.x), spc_div1(a.y, b.y), spc_div1(a.z, b.z)); }
