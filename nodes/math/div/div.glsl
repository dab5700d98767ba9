// math.div.*: component-wise a / b, 0 where b == 0.
float spc_div1(float a, float b) { return b == 0.0 ? 0.0 : a / b; }
void spc_math_div(float a, float b, out float o) { o = spc_div1(a, b); }
void spc_math_div(vec2 a, vec2 b, out vec2 o) { o = vec2(spc_div1(a.x, b.x), spc_div1(a.y, b.y)); }
void spc_math_div(vec3 a, vec3 b, out vec3 o) { o = vec3(spc_div1(a.x, b.x), spc_div1(a.y, b.y), spc_div1(a.z, b.z)); }
