// convert.*: explicit type conversions.
void spc_convert_broadcast(float in_, out vec2 out_) { out_ = vec2(in_); }
void spc_convert_broadcast(float in_, out vec3 out_) { out_ = vec3(in_); }
void spc_convert_copy(vec3 in_, out vec3 out_) { out_ = in_; }
void spc_convert_extend(vec2 in_, float z, out vec3 out_) { out_ = vec3(in_, z); }
void spc_convert_channel(vec3 in_, int channel, out float out_) {
    out_ = channel != SPC_CHANNEL_LUMINANCE ? in_[channel] : 0.2126 * in_.x + 0.7152 * in_.y + 0.0722 * in_.z;
}
