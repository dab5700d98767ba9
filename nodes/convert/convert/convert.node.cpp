// Explicit conversions (connections never convert implicitly): convert.<from>_to_<to> for
// float -> vec2/color3/vector3 (broadcast), vec2 -> color3/vector3 (x, y and a third component, e.g. to look at
// uvs or slopes), color3 <-> vector3, vector3 <-> normal3 (no renormalisation), and convert.color3_to_float (one
// channel or Rec.709 luminance).
#include "nodes/node_common.h"

namespace specula::nodes {
namespace {

struct FloatIn {
    float in;
};
struct Vec3In {
    Vec3 in;
};
struct Vec2In {
    Vec2 in;
    float z;
};
enum class Channel : int { R, G, B, Luminance };
struct ChannelIn {
    Vec3 in;
    Channel channel;
};

}  // namespace
}  // namespace specula::nodes

SPECULA_ENUM(specula::nodes::Channel, "SPC_CHANNEL", "r", "g", "b", "luminance");

namespace specula::nodes {
namespace {

// Every conversion has the input port "in" (and convert.color3_to_float the channel choice).
NodeParams<FloatIn> floatIn(TypeDesc) { return NodeParams<FloatIn>().f("in", &FloatIn::in, 0.f, "value to convert").range(-2.f, 2.f); }
NodeParams<Vec3In> vec3In(TypeDesc t) {
    NodeParams<Vec3In> l;
    if (t == TypeDesc::Color3) l.c3("in", &Vec3In::in, Vec3(0.f), "value to convert");
    else if (t == TypeDesc::Normal3) l.n3("in", &Vec3In::in, Vec3(0.f), "value to convert");
    else l.v3("in", &Vec3In::in, Vec3(0.f), "value to convert");
    return l.range(-2.f, 2.f);
}
const NodeParams<FloatIn> kFloatIn = floatIn(TypeDesc::Float);
const NodeParams<Vec3In> kVec3In = vec3In(TypeDesc::Vector3);
const NodeParams<Vec2In> kVec2In = NodeParams<Vec2In>()
    .v2("in", &Vec2In::in, Vec2(0.f), "value to convert: its x and y").range(-2.f, 2.f)
    .f("z", &Vec2In::z, 0.f, "the third component").range(-2.f, 2.f);
const NodeParams<ChannelIn> kChannelIn = NodeParams<ChannelIn>()
    .c3("in", &ChannelIn::in, Vec3(0.f), "value to convert").range(-2.f, 2.f)
    .choice("channel", &ChannelIn::channel, "which channel");

template <int W>
struct Broadcast {
    static void run(EvalContext& c, const Instr& i) {
        FloatN<W> o;
        o.fill(kFloatIn.read(c, i).in);
        setSingleOutput(c, i, o);
    }
};
void extend2(EvalContext& c, const Instr& i) {
    const Vec2In p = kVec2In.read(c, i);
    setSingleOutput(c, i, Vec3(p.in.x, p.in.y, p.z));
}
void copy3(EvalContext& c, const Instr& i) { setSingleOutput(c, i, kVec3In.read(c, i).in); }
void channel(EvalContext& c, const Instr& i) {
    const ChannelIn p = kChannelIn.read(c, i);
    const int ch = int(p.channel);
    setSingleOutput(c, i, p.channel != Channel::Luminance ? p.in[ch] : 0.2126f * p.in.x + 0.7152f * p.in.y + 0.0722f * p.in.z);
}

NodeSpec base(TypeDesc from, TypeDesc to, const std::string& doc) {
    NodeSpec s;
    s.id = std::string("convert.") + typeName(from) + "_to_" + typeName(to);
    s.category = "convert";
    s.doc = doc;
    s.flags = kPure;
    s.glslFile = "convert/convert/convert.glsl";
    s.inputs = from == TypeDesc::Float ? floatIn(from).ports() : vec3In(from).ports();
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
    for (TypeDesc to : {TypeDesc::Color3, TypeDesc::Vector3}) {
        NodeSpec e = base(TypeDesc::Vec2, to, std::string("A vec2's x and y as the first two components of a ") +
                                                  typeName(to) + ", z the third (e.g. uvs shown as red and green).");
        e.inputs = kVec2In.ports();
        e.cpu = &extend2;
        e.glslFunction = "spc_convert_extend";
        r.add(std::move(e));
    }
    NodeSpec s = base(TypeDesc::Color3, TypeDesc::Float, "One channel of a color3, or its Rec.709 luminance.");
    s.inputs = kChannelIn.ports();
    s.cpu = &channel;
    s.glslFunction = "spc_convert_channel";
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
