// math.mix.*: a * (1 - t) + b * t, written out (not mix()) to match the CPU operation order.
void spc_math_mix(float a, float b, float t, out float out_) { out_ = a * (1.0 - t) + b * t; }
void spc_math_mix(vec2 a, vec2 b, float t, out vec2 out_) { out_ = a * (1.0 - t) + b * t; }
void spc_math_mix(vec3 a, vec3 b, float t, out vec3 out_) { out_ = a * (1.0 - t) + b * t; }
