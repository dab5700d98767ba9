// convert.*: explicit type conversions.
void spc_convert_broadcast(float v, out vec2 o) { o = vec2(v); }
void spc_convert_broadcast(float v, out vec3 o) { o = vec3(v); }
void spc_convert_copy(vec3 v, out vec3 o) { o = v; }
void spc_convert_channel(vec3 v, int channel, out float o) {
    o = channel < 3 ? v[channel] : 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z;
}
