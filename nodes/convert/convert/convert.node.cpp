// Explicit conversions (connections never convert implicitly): convert.<from>_to_<to> for
// float -> vec2/color3/vector3 (broadcast), color3 <-> vector3, vector3 <-> normal3 (no renormalisation),
// and convert.color3_to_float (one channel or Rec.709 luminance).
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {

template <int W>
struct Broadcast {
    static void run(EvalContext& c, const Instr& i) {
        for (int k = 0; k < W; ++k) c.r[i.out[0] + k] = c.r[i.in[0]];
    }
};
void copy3(EvalContext& c, const Instr& i) {
    for (int k = 0; k < 3; ++k) c.r[i.out[0] + k] = c.r[i.in[0] + k];
}
void channel(EvalContext& c, const Instr& i) {
    Vec3 v = inV3(c, i, 0);
    int ch = inEnum(i, 1);
    outF(c, i, 0, ch < 3 ? v[ch] : 0.2126f * v.x + 0.7152f * v.y + 0.0722f * v.z);
}

NodeSpec base(TypeDesc from, TypeDesc to, const std::string& doc) {
    NodeSpec s;
    s.id = std::string("convert.") + typeName(from) + "_to_" + typeName(to);
    s.category = "convert";
    s.doc = doc;
    s.flags = kPure;
    s.glslFile = "convert/convert/convert.glsl";
    s.inputs = {port("in", from, 0.f, "value to convert")};
    s.outputs = {PortSpec::out("out", to, "converted value")};
    return s;
}

void reg(NodeRegistry& r) {
    for (TypeDesc to : {TypeDesc::Vec2, TypeDesc::Color3, TypeDesc::Vector3}) {
        NodeSpec s = base(TypeDesc::Float, to, std::string("Broadcast a float into every component of a ") + typeName(to) + ".");
        s.cpu = to == TypeDesc::Vec2 ? &Broadcast<2>::run : &Broadcast<3>::run;
        s.glslFunction = "spc_convert_broadcast";
        r.add(std::move(s));
    }
    const std::pair<TypeDesc, TypeDesc> same[] = {{TypeDesc::Color3, TypeDesc::Vector3}, {TypeDesc::Vector3, TypeDesc::Color3},
                                                  {TypeDesc::Vector3, TypeDesc::Normal3}, {TypeDesc::Normal3, TypeDesc::Vector3}};
    for (auto [from, to] : same) {
        NodeSpec s = base(from, to, std::string("Reinterpret a ") + typeName(from) + " as a " + typeName(to) + " (values unchanged).");
        s.cpu = &copy3;
        s.glslFunction = "spc_convert_copy";
        r.add(std::move(s));
    }
    NodeSpec s = base(TypeDesc::Color3, TypeDesc::Float, "One channel of a color3, or its Rec.709 luminance.");
    s.inputs.push_back(PortSpec::choice("channel", {"r", "g", "b", "luminance"}, "which channel"));
    s.cpu = &channel;
    s.glslFunction = "spc_convert_channel";
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
