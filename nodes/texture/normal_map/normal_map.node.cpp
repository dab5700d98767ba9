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
    Color3 dcolorDu, dcolorDv;
    Vec2 duvdx, duvdy;
    Vec3 surfaceDndx, surfaceDndy;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .c3("color", &Params::color, Vec3(0.5f, 0.5f, 1.f), "normal-map texel (connect texture.image with colorspace raw)").range(0.f, 1.f)
    .f("strength", &Params::strength, 1.f, "scales the tangent-space tilt").range(0.f, 2.f)
    .choice("convention", &Params::convention, "green channel: opengl = +Y up, directx = +Y down")
    .n3("normal", &Params::normal, Vec3(0, 0, 1), "surface normal to perturb").bind(GeomBinding::N)
    .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent").bind(GeomBinding::T)
    .f("sign", &Params::sign, 1.f, "bitangent sign").range(-1.f, 1.f).bind(GeomBinding::TSign)
    .c3("dcolor_du", &Params::dcolorDu, Vec3(0.f), "texture gradient d(color)/du (texture.image dcolor_du); 0: no map derivative").range(-4.f, 4.f)
    .c3("dcolor_dv", &Params::dcolorDv, Vec3(0.f), "texture gradient d(color)/dv").range(-4.f, 4.f)
    .v2("duvdx", &Params::duvdx, Vec2(0.f), "uv footprint d(uv)/dx of the map's uv input").range(-0.01f, 0.01f).bind(GeomBinding::DUVDX)
    .v2("duvdy", &Params::duvdy, Vec2(0.f), "uv footprint d(uv)/dy").range(-0.01f, 0.01f).bind(GeomBinding::DUVDY)
    .v3("surface_dndx", &Params::surfaceDndx, Vec3(0.f), "screen derivative of the surface normal").range(-0.05f, 0.05f).bind(GeomBinding::DNDX)
    .v3("surface_dndy", &Params::surfaceDndy, Vec3(0.f), "screen derivative of the surface normal").range(-0.05f, 0.05f).bind(GeomBinding::DNDY);
OutputList kOutputs;
const OutPort<Vec3> kNormal = kOutputs.add<Vec3>("normal", TypeDesc::Normal3, "perturbed unit normal (world)");
const OutPort<Vec3> kDndx = kOutputs.add<Vec3>(
    "dndx", TypeDesc::Vector3, "screen derivative of the perturbed normal: map gradient x footprint, plus the surface's dN/dx");
const OutPort<Vec3> kDndy = kOutputs.add<Vec3>("dndy", TypeDesc::Vector3, "screen derivative of the perturbed normal along y");

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
    const Vec3 nn = l2 > 0.f ? n / std::sqrt(l2) : f.n;
    set(c, i, kNormal, nn);
    if (wanted(i, kDndx) || wanted(i, kDndy)) {
        // dn = (I - n n^T) dm / |m| with dm = T dts.x + b dts.y + N dts.z + ts.z dN_surface, dts = 2 dcolor (tilt scaled,
        // green flipped like ts) and dcolor = dcolor/du duv.x + dcolor/dv duv.y: first order, the rotation of T and b
        // with the surface ignored.
        const float len = l2 > 0.f ? std::sqrt(l2) : 1.f;
        auto dnOf = [&](Vec2 duv, Vec3 dNs) {
            Vec3 dts = (p.dcolorDu * duv.x + p.dcolorDv * duv.y) * 2.f;
            if (p.convention == NormalMapConvention::DirectX) dts.y = -dts.y;
            dts.x *= p.strength;
            dts.y *= p.strength;
            Vec3 dm = dts.x * f.t + dts.y * b + dts.z * f.n + ts.z * dNs;
            return (dm - nn * glm::dot(nn, dm)) / len;
        };
        set(c, i, kDndx, dnOf(p.duvdx, p.surfaceDndx));
        set(c, i, kDndy, dnOf(p.duvdy, p.surfaceDndy));
    }
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("texture.normal_map",
                             "Tangent-space normal map to a world-space shading normal (feed it to a BSDF's normal).",
                             kParams, kOutputs, &cpu, kPure);
    s.notes = "`normal` = normalize(x·T + y·sign·(N×T) + z·N) with (x, y, z) = 2·color − 1, x and y scaled by "
              "`strength`, T Gram-Schmidt-orthogonalised to N.";
    s.parityTolerance = 2e-4f;
    s.parityNote = "frame construction + renormalisation (sqrt/divide, FMA contraction on llvmpipe), measured 9.0e-5";
    s.cpuBatch = &batchOf<&cpu>;  // Program::shadeBatch: one call per batch
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
