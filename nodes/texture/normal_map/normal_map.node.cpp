// texture.normal_map: tangent-space normal map (colour in [0,1]^3 -> [-1,1]^3, strength scales the
// xy tilt, DirectX maps flip green) to a world-space normal in the frame (T, sign·N×T, N).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "nodes/shared/texture_ports.h"

namespace specula::nodes {
namespace {

struct Params {
    Color3 color;
    float strength;
    NormalMapConvention convention;
    Vec3 normal, tangent;
    float sign;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .c3("color", &Params::color, Vec3(0.5f, 0.5f, 1.f), "normal-map texel (connect texture.image with colorspace raw)").range(0.f, 1.f)
    .f("strength", &Params::strength, 1.f, "scales the tangent-space tilt").range(0.f, 2.f)
    .choice("convention", &Params::convention, "green channel: opengl = +Y up, directx = +Y down")
    .n3("normal", &Params::normal, Vec3(0, 0, 1), "surface normal to perturb").bind(GeomBinding::N)
    .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent").bind(GeomBinding::T)
    .f("sign", &Params::sign, 1.f, "bitangent sign").range(-1.f, 1.f).bind(GeomBinding::TSign);
OutputList kOutputs;
const OutPort<Vec3> kNormal = kOutputs.add<Vec3>("normal", TypeDesc::Normal3, "perturbed unit normal (world)");

void cpu(EvalContext& c, const Instr& i) {
    const Params p = kParams.read(c, i);
    Vec3 ts = p.color * 2.f - Vec3(1.f);
    if (p.convention == NormalMapConvention::DirectX) ts.y = -ts.y;  // DirectX: green points down
    ts.x *= p.strength;
    ts.y *= p.strength;
    Frame f = bsdfFrame(p.normal, p.tangent);
    Vec3 b = p.sign < 0.f ? -f.b : f.b;
    Vec3 n = ts.x * f.t + ts.y * b + ts.z * f.n;
    float l2 = glm::dot(n, n);
    set(c, i, kNormal, l2 > 0.f ? n / std::sqrt(l2) : f.n);
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "texture.normal_map";
    s.category = "texture";
    s.doc = "Tangent-space normal map to a world-space shading normal (feed it to a BSDF's normal).";
    s.inputs = kParams.ports();
    s.outputs = kOutputs.ports();
    s.flags = kPure;
    s.cpu = &cpu;
    s.parityTolerance = 2e-4f;
    s.parityNote = "frame construction + renormalisation (sqrt/divide, FMA contraction on llvmpipe), measured 9.0e-5";
    s.glslFunction = "spc_texture_normal_map";
    s.glslFile = "texture/normal_map/normal_map.glsl";
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
