// texture.normal_map: tangent-space normal map (colour in [0,1]^3 -> [-1,1]^3, strength scales the
// xy tilt, DirectX maps flip green) to a world-space normal in the frame (T, sign·N×T, N).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"

namespace specula::nodes {
namespace {

void cpu(EvalContext& c, const Instr& i) {
    Vec3 ts = inV3(c, i, 0) * 2.f - Vec3(1.f);
    float strength = inF(c, i, 1);
    if (inEnum(i, 2) == 1) ts.y = -ts.y;  // DirectX: green points down
    ts.x *= strength;
    ts.y *= strength;
    Frame f = bsdfFrame(inV3(c, i, 3), inV3(c, i, 4));
    Vec3 b = inF(c, i, 5) < 0.f ? -f.b : f.b;
    Vec3 n = ts.x * f.t + ts.y * b + ts.z * f.n;
    float l2 = glm::dot(n, n);
    outV3(c, i, 0, l2 > 0.f ? n / std::sqrt(l2) : f.n);
}

void reg(NodeRegistry& r) {
    NodeSpec s;
    s.id = "texture.normal_map";
    s.category = "texture";
    s.doc = "Tangent-space normal map to a world-space shading normal (feed it to a BSDF's normal).";
    s.inputs = {std::move(PortSpec::c3("color", Vec3(0.5f, 0.5f, 1.f), "normal-map texel (connect texture.image with colorspace raw)")).range(0.f, 1.f),
                std::move(PortSpec::f("strength", 1.f, "scales the tangent-space tilt")).range(0.f, 2.f),
                PortSpec::choice("convention", {"opengl", "directx"}, "green channel: opengl = +Y up, directx = +Y down"),
                std::move(PortSpec::n3("normal", Vec3(0, 0, 1), "surface normal to perturb")).bind(GeomBinding::N),
                std::move(PortSpec::v3("tangent", Vec3(1, 0, 0), "tangent")).bind(GeomBinding::T),
                std::move(PortSpec::f("sign", 1.f, "bitangent sign")).range(-1.f, 1.f).bind(GeomBinding::TSign)};
    s.outputs = {PortSpec::out("normal", TypeDesc::Normal3, "perturbed unit normal (world)")};
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
