// math.clamp.*: component-wise min(max(x, lo), hi).
void spc_math_clamp(float x, float lo, float hi, out float out_) { out_ = min(max(x, lo), hi); }
void spc_math_clamp(vec2 x, vec2 lo, vec2 hi, out vec2 out_) { out_ = min(max(x, lo), hi); }
void spc_math_clamp(vec3 x, vec3 lo, vec3 hi, out vec3 out_) { out_ = min(max(x, lo), hi); }
