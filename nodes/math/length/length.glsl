// math.length.*: sqrt(v.v).
void spc_math_length(vec2 v, out float out_) { out_ = sqrt(v.x * v.x + v.y * v.y); }
void spc_math_length(vec3 v, out float out_) { out_ = sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
