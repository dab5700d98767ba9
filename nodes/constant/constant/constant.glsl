// constant.*: pass the literal through (typed overloads).
void spc_constant(float value, out float out_) { out_ = value; }
void spc_constant(vec2 value, out vec2 out_) { out_ = value; }
void spc_constant(vec3 value, out vec3 out_) { out_ = value; }
