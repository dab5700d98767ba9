// constant.*: pass the literal through (typed overloads).
void spc_constant(float value, out float o) { o = value; }
void spc_constant(vec2 value, out vec2 o) { o = value; }
void spc_constant(vec3 value, out vec3 o) { o = value; }
