// Graph core: registry completeness (drift guard), compiler (folding, pruning, topological order),
// CPU evaluator and loadGraphMaterial against closed forms and direct lobe calls.
#include "core/graph/graph_material.h"
#include "tests/unit/render_support.h"
#include "tests/unit/test_support.h"
#include "core/graph/node_spec.h"
#include "core/render/lobes/fresnel.h"
#include "core/render/lobes/ggx.h"
#include "core/render/lobes/lambert.h"

#include <gtest/gtest.h>
#include <limits>
#include <nlohmann/json.hpp>

using namespace specula;
using namespace specula::graph;
using nlohmann::json;

namespace {

ShadingPoint makeSp() {
    return test::shadingPointWithDifferentials(glm::normalize(Vec3(0.3f, -0.2f, 0.9f)), 0.1f);
}

std::shared_ptr<Material> load(const json& j) { return loadGraphMaterial(j, "/materials/m", GraphLoadContext{}); }

// Evaluates a pattern graph and returns the floats of output 'ref' (node.port).
std::vector<float> evalPattern(const json& nodes, const std::string& node, const std::string& port, ShadingPoint sp = makeSp()) {
    json m = {{"nodes", nodes}, {"output", "@" + node + "." + port}};
    GraphDesc g = parseGraph(m, "/m", ParseOptions{false});
    Program p = Program::compile(g, {{g.outputNode, g.outputPort}}, nullptr);
    ScratchArena arena;
    const float* r = p.run(sp, arena, nullptr, nullptr);
    int w = typeWidth(g.nodes[g.outputNode].spec->outputs[g.outputPort].type);
    return std::vector<float>(r + p.rootRegister(0), r + p.rootRegister(0) + w);
}

}  // namespace

TEST(GraphRegistry, EveryNodeHasCpuEntryAndGlslFunction) {
    auto specs = NodeRegistry::instance().all();
    ASSERT_GE(specs.size(), 60u);
    for (const NodeSpec* s : specs) {
        SCOPED_TRACE(s->id);
        EXPECT_NE(s->cpu, nullptr);
        EXPECT_FALSE(s->glslFunction.empty());
        ASSERT_NE(s->glslSource(), nullptr) << "missing embedded " << s->glslFile;
        EXPECT_NE(s->glslSource()->find(s->glslFunction + "("), std::string::npos);
        EXPECT_FALSE(s->category.empty());
        EXPECT_FALSE(s->outputs.empty());
        EXPECT_EQ(s->id.rfind(s->category + ".", 0), 0u) << "id must start with its category";
    }
    for (const char* id : {"bsdf.ggx", "bsdf.diffuse", "bsdf.emission", "closure.add", "closure.mix", "texture.image",
                           "texture.normal_map", "fresnel.schlick", "fresnel.dielectric", "fresnel.conductor", "geometry.uv",
                           "geometry.position", "geometry.normal", "geometry.tangent", "geometry.geometric_normal",
                           "constant.float", "constant.vec2", "constant.color3", "constant.vector3", "math.add.float",
                           "math.sub.color3", "math.mul.vec2", "math.div.vector3", "math.mix.color3", "math.clamp.float",
                           "math.pow.float", "math.dot.vector3", "math.normalize.vector3", "math.length.vec2", "math.remap.float"})
        EXPECT_NE(NodeRegistry::instance().find(id), nullptr) << id;
}

TEST(GraphCompiler, FoldsConstantsAndPrunesDeadNodes) {
    json m = {{"nodes",
               {{"a", {{"type", "constant.float"}, {"inputs", {{"value", 0.5}}}}},
                {"sq", {{"type", "math.mul.float"}, {"inputs", {{"a", "@a.out"}, {"b", "@a.out"}}}}},
                {"unused", {{"type", "math.add.float"}, {"inputs", {{"a", 1.0}}}}},
                {"ggx", {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", "@sq.out"}}}}}}},
              {"output", "@ggx.bsdf"}};
    GraphDesc g = parseGraph(m, "/materials/m");
    // topological order: sources before consumers
    auto pos = [&](const std::string& id) { return std::find(g.order.begin(), g.order.end(), g.findNode(id)) - g.order.begin(); };
    EXPECT_LT(pos("a"), pos("sq"));
    EXPECT_LT(pos("sq"), pos("ggx"));
    Program p = Program::compile(g, {{g.outputNode, g.outputPort}}, nullptr);
    EXPECT_EQ(p.instructionCount(), 1u);  // only the BSDF remains
    EXPECT_EQ(p.foldedCount(), 2u);       // constant + mul folded; 'unused' pruned
    EXPECT_EQ(g.liveOrder({{g.outputNode, g.outputPort}}).size(), 3u);
    // folded roughness 0.25 -> alpha 0.0625
    auto mat = std::make_shared<GraphMaterial>(g, p);
    ShadingPoint sp = makeSp();
    ScratchArena arena;
    Closure cl;
    mat->shade(sp, arena, cl);
    ASSERT_EQ(cl.size(), 1);
    auto* lobe = dynamic_cast<const GgxLobe*>(cl.lobe(0));
    ASSERT_NE(lobe, nullptr);
    EXPECT_FLOAT_EQ(lobe->alphaX(), 0.0625f);
    EXPECT_FLOAT_EQ(lobe->alphaY(), 0.0625f);
}

TEST(GraphMaterial, DiffuseMatchesClosedForm) {
    auto mat = load({{"nodes", {{"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", {0.2, 0.4, 0.6}}}}}}}}, {"output", "@d.bsdf"}});
    ShadingPoint sp = makeSp();
    ScratchArena arena;
    Closure cl;
    mat->shade(sp, arena, cl);
    Vec3 wo = glm::normalize(Vec3(0.1f, 0.2f, 0.9f)), wi = glm::normalize(Vec3(-0.4f, 0.1f, 0.7f));
    BsdfEval e = test::query(cl, wo, wi).f;
    EXPECT_NEAR(e.diffuse.x, 0.2f / kPi * wi.z, 1e-7f);
    EXPECT_NEAR(e.diffuse.z, 0.6f / kPi * wi.z, 1e-7f);
    EXPECT_NEAR(test::query(cl, wo, wi).pdf, wi.z / kPi, 1e-7f);
    EXPECT_FALSE(mat->isEmissive());
}

TEST(GraphMaterial, GgxMatchesDirectLobe) {
    auto mat = load({{"nodes",
                      {{"g",
                        {{"type", "bsdf.ggx"},
                         {"inputs", {{"roughness", 0.4}, {"anisotropy", 0.5}, {"f0", {0.9, 0.6, 0.5}}, {"weight", {1.0, 0.5, 1.0}}}}}}}},
                     {"output", "@g.bsdf"}});
    float alpha = 0.16f, aspect = std::sqrt(1.f - 0.45f);
    GgxLobe direct(alpha / aspect, alpha * aspect, Fresnel::schlick(Color3(0.9f, 0.6f, 0.5f)));
    ShadingPoint sp = makeSp();
    ScratchArena arena;
    Closure cl;
    mat->shade(sp, arena, cl);
    for (int k = 0; k < 20; ++k) {
        Vec3 wo = glm::normalize(Vec3(0.1f * k - 1.f, 0.3f, 1.f)), wi = glm::normalize(Vec3(0.5f, -0.05f * k, 0.8f));
        Color3 ref = direct.eval(wo, wi) * Color3(1.f, 0.5f, 1.f);
        Color3 got = test::query(cl, wo, wi).f.specular;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], ref[c], 1e-6f * std::max(1.f, ref[c]));
        EXPECT_NEAR(test::query(cl, wo, wi).pdf, direct.pdf(wo, wi), 1e-6f * std::max(1.f, direct.pdf(wo, wi)));
    }
}

TEST(GraphMaterial, GgxFresnelModes) {
    // Normal incidence on a mirror-like lobe: F(1) must be the closed-form normal-incidence reflectance.
    Vec3 w(0, 0, 1);
    auto evalMode = [&](const json& inputs) {
        auto mat = load({{"nodes", {{"g", {{"type", "bsdf.ggx"}, {"inputs", inputs}}}}}, {"output", "@g.bsdf"}});
        ShadingPoint sp = makeSp();
        ScratchArena arena;
        Closure cl;
        mat->shade(sp, arena, cl);
        return test::query(cl, w, w).f.specular;
    };
    Color3 none = evalMode({{"roughness", 0.5}, {"fresnel", "none"}});
    Color3 diel = evalMode({{"roughness", 0.5}, {"fresnel", "dielectric"}, {"ior", 1.5}});
    Color3 cond = evalMode({{"roughness", 0.5}, {"fresnel", "conductor"}, {"eta", 1.5}, {"k", 2.0}});
    EXPECT_NEAR(diel.x / none.x, 0.04f, 1e-6f);                                 // ((n-1)/(n+1))^2
    EXPECT_NEAR(cond.y / none.y, (0.25f + 4.f) / (6.25f + 4.f), 1e-5f);         // ((n-1)^2+k^2)/((n+1)^2+k^2)
    // D(n) G2 / (4) at normal incidence: D = 1/(π α²), G2 = 1
    EXPECT_NEAR(none.x, 1.f / (kPi * 0.0625f) / 4.f, 1e-4f);
}

TEST(GraphMaterial, ClosureAddMixAndEmission) {
    json nodes = {{"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", 0.5}}}}},
                  {"e", {{"type", "bsdf.emission"}, {"inputs", {{"color", {1.0, 0.5, 0.25}}, {"strength", 4.0}}}}},
                  {"g", {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", 0.3}}}}},
                  {"mix", {{"type", "closure.mix"}, {"inputs", {{"a", "@d.bsdf"}, {"b", "@g.bsdf"}, {"t", 0.25}}}}},
                  {"sum", {{"type", "closure.add"}, {"inputs", {{"a", "@mix.bsdf"}, {"b", "@e.bsdf"}}}}}};
    auto mat = load({{"nodes", nodes}, {"output", "@sum.bsdf"}});
    EXPECT_TRUE(mat->isEmissive());
    ShadingPoint sp = makeSp();
    ScratchArena arena;
    Closure cl;
    mat->shade(sp, arena, cl);
    ASSERT_EQ(cl.size(), 2);
    Vec3 wo = glm::normalize(Vec3(0.2f, 0.1f, 1.f)), wi = glm::normalize(Vec3(-0.3f, 0.f, 1.f));
    GgxLobe g(0.09f, 0.09f, Fresnel::schlick(Color3(0.04f)));
    BsdfEval e = test::query(cl, wo, wi).f;
    EXPECT_NEAR(e.diffuse.x, 0.75f * 0.5f / kPi * wi.z, 1e-7f);
    EXPECT_NEAR(e.specular.x, 0.25f * g.eval(wo, wi).x, 1e-6f);
    Color3 em(0.f);
    Closure cl2;
    mat->shade(sp, arena, cl2, &em);
    EXPECT_FLOAT_EQ(em.x, 4.f);
    EXPECT_FLOAT_EQ(em.y, 2.f);
    EXPECT_FLOAT_EQ(em.z, 1.f);
}

TEST(GraphMaterial, NormalMapPerturbsShadingFrame) {
    // A texel tilting the normal 45° towards +x (tangent-space (1,0,1)/√2): colour = n*0.5+0.5.
    float c = 0.5f + 0.5f / std::sqrt(2.f);
    json nodes = {{"nm", {{"type", "texture.normal_map"}, {"inputs", {{"color", {c, 0.5, c}}}}}},
                  {"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", 1.0}, {"normal", "@nm.normal"}}}}}};
    auto mat = load({{"nodes", nodes}, {"output", "@d.bsdf"}});
    ShadingPoint sp = makeSp();
    ScratchArena arena;
    Closure cl;
    mat->shade(sp, arena, cl);
    Vec3 nExp = glm::normalize(Vec3(1, 0, 1));
    ASSERT_EQ(cl.size(), 1);
    EXPECT_NEAR(cl.frame(0).n.x, nExp.x, 1e-6f);
    EXPECT_NEAR(cl.frame(0).n.z, nExp.z, 1e-6f);
    // wi along the perturbed normal in world space: f·cos = 1/π
    Vec3 wiW = nExp, woW = nExp;
    EXPECT_NEAR(test::query(cl, woW, wiW).f.diffuse.x, 1.f / kPi, 1e-6f);
    // DirectX convention flips green: a texel tilted towards +y in OpenGL tilts towards -y.
    json nodes2 = {{"nm", {{"type", "texture.normal_map"}, {"inputs", {{"color", {0.5, c, c}}, {"convention", "directx"}}}}},
                   {"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"normal", "@nm.normal"}}}}}};
    auto mat2 = load({{"nodes", nodes2}, {"output", "@d.bsdf"}});
    ShadingPoint sp2 = makeSp();
    mat2->shade(sp2, arena, cl);
    ASSERT_EQ(cl.size(), 1);
    EXPECT_NEAR(cl.frame(0).n.y, -1.f / std::sqrt(2.f), 1e-6f);
}

TEST(GraphMaterial, LobesInDifferentFramesAreRotated) {
    // Diffuse with the geometric normal, GGX with a tilted normal: each lobe keeps its own frame, so a world-space
    // query equals evaluating each lobe in its own frame.
    Vec3 tilted = glm::normalize(Vec3(0.3f, 0.f, 1.f));
    json nodes = {{"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", 0.5}}}}},
                  {"g", {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", 0.5}, {"normal", {tilted.x, tilted.y, tilted.z}}}}}},
                  {"sum", {{"type", "closure.add"}, {"inputs", {{"a", "@d.bsdf"}, {"b", "@g.bsdf"}}}}}};
    auto mat = load({{"nodes", nodes}, {"output", "@sum.bsdf"}});
    ShadingPoint sp = makeSp();
    ScratchArena arena;
    Closure cl;
    mat->shade(sp, arena, cl);
    Frame gf = Frame::fromNormalTangent(tilted, Vec3(1, 0, 0));
    GgxLobe g(0.25f, 0.25f, Fresnel::schlick(Color3(0.04f)));
    Vec3 woW = glm::normalize(Vec3(0.5f, 0.2f, 1.f)), wiW = glm::normalize(Vec3(-0.1f, -0.3f, 1.f));
    float ref = g.eval(gf.toLocal(woW), gf.toLocal(wiW)).x;
    EXPECT_NEAR(test::query(cl, woW, wiW).f.specular.x, ref, 1e-5f * std::max(1.f, ref));
    // Mixture pdf: selection weights luminance(weight·albedo) of each lobe in its own frame.
    LambertLobe d(Color3(0.5f));
    float wd = luminance(d.albedo(woW)), wg = luminance(g.albedo(gf.toLocal(woW)));
    float pdfRef = wd / (wd + wg) * d.pdf(woW, wiW) + wg / (wd + wg) * g.pdf(gf.toLocal(woW), gf.toLocal(wiW));
    EXPECT_NEAR(test::query(cl, woW, wiW).pdf, pdfRef, 1e-5f * pdfRef);
    // Sampling returns world directions whose f and pdf are those of a query.
    for (float uLobe : {0.1f, 0.97f}) {
        BsdfSample bs;
        ASSERT_TRUE(test::sample(cl, woW, uLobe, Vec2(0.3f, 0.6f), bs));
        BsdfValue v = test::query(cl, woW, bs.wi);
        EXPECT_NEAR(bs.pdf, v.pdf, 1e-5f * v.pdf);
        EXPECT_NEAR(bs.f.total().x, v.f.total().x, 1e-5f * std::max(1e-3f, v.f.total().x));
        EXPECT_EQ(bs.kind, uLobe < 0.5f ? LobeKind::Diffuse : LobeKind::Specular);
    }
    // A lobe mask selects which lobes answer; the pdf stays the whole mixture's.
    BsdfValue onlyD = test::query(cl, woW, wiW, std::numeric_limits<float>::infinity(), 1u);
    EXPECT_EQ(onlyD.f.specular.x, 0.f);
    EXPECT_GT(onlyD.f.diffuse.x, 0.f);
    EXPECT_FLOAT_EQ(onlyD.pdf, test::query(cl, woW, wiW).pdf);
}

TEST(GraphNodes, GeometryAndBindings) {
    ShadingPoint sp = makeSp();
    EXPECT_EQ(evalPattern({{"g", {{"type", "geometry.uv"}}}}, "g", "uv", sp), (std::vector<float>{0.25f, 0.75f}));
    EXPECT_EQ(evalPattern({{"g", {{"type", "geometry.uv"}}}}, "g", "duvdy", sp), (std::vector<float>{0.f, 0.002f}));
    EXPECT_EQ(evalPattern({{"g", {{"type", "geometry.position"}}}}, "g", "dPdx", sp), (std::vector<float>{0.01f, 0.f, 0.f}));
    EXPECT_EQ(evalPattern({{"g", {{"type", "geometry.normal"}}}}, "g", "dNdy", sp), (std::vector<float>{0.f, 0.1f, 0.f}));
    EXPECT_EQ(evalPattern({{"g", {{"type", "geometry.tangent"}}}}, "g", "sign", sp), (std::vector<float>{1.f}));
    EXPECT_EQ(evalPattern({{"g", {{"type", "geometry.geometric_normal"}}}}, "g", "Ng", sp), (std::vector<float>{0.f, 0.f, 1.f}));
    // unconnected cos_theta binds to N·V
    auto f = evalPattern({{"f", {{"type", "fresnel.dielectric"}}}}, "f", "F", sp);
    EXPECT_NEAR(f[0], fresnelDielectric(sp.wo.z, 1.5f), 1e-7f);
}

TEST(GraphNodes, MathClosedForms) {
    auto one = [](const std::string& type, json inputs) {
        return evalPattern({{"n", {{"type", type}, {"inputs", inputs}}}}, "n", "out");
    };
    EXPECT_EQ(one("math.add.color3", {{"a", {1, 2, 3}}, {"b", 0.5}}), (std::vector<float>{1.5f, 2.5f, 3.5f}));
    EXPECT_EQ(one("math.sub.vec2", {{"a", {1, 2}}, {"b", {3, 1}}}), (std::vector<float>{-2.f, 1.f}));
    EXPECT_EQ(one("math.mul.vector3", {{"a", {1, 2, 3}}, {"b", 2}}), (std::vector<float>{2.f, 4.f, 6.f}));
    EXPECT_EQ(one("math.div.float", {{"a", 1}, {"b", 0}}), (std::vector<float>{0.f}));
    EXPECT_EQ(one("math.div.float", {{"a", 1}, {"b", 4}}), (std::vector<float>{0.25f}));
    EXPECT_EQ(one("math.mix.float", {{"a", 2}, {"b", 4}, {"t", 0.25}}), (std::vector<float>{2.5f}));
    EXPECT_EQ(one("math.clamp.vec2", {{"x", {-1, 3}}, {"lo", 0}, {"hi", 1}}), (std::vector<float>{0.f, 1.f}));
    EXPECT_EQ(one("math.pow.float", {{"a", 4}, {"b", 0.5}}), (std::vector<float>{2.f}));
    EXPECT_EQ(one("math.pow.float", {{"a", -4}, {"b", 0.5}}), (std::vector<float>{0.f}));
    EXPECT_EQ(one("math.dot.vector3", {{"a", {1, 2, 3}}, {"b", {4, 5, 6}}}), (std::vector<float>{32.f}));
    EXPECT_EQ(one("math.normalize.vector3", {{"v", {3, 0, 4}}}), (std::vector<float>{0.6f, 0.f, 0.8f}));
    EXPECT_EQ(one("math.length.vec2", {{"v", {3, 4}}}), (std::vector<float>{5.f}));
    EXPECT_EQ(one("math.remap.float", {{"x", 0.5}, {"in_min", 0}, {"in_max", 1}, {"out_min", 10}, {"out_max", 20}}),
              (std::vector<float>{15.f}));
    EXPECT_EQ(one("convert.color3_to_float", {{"in", {0.1, 0.2, 0.3}}, {"channel", "g"}}), (std::vector<float>{0.2f}));
    EXPECT_EQ(one("convert.float_to_color3", {{"in", 0.7}}), (std::vector<float>{0.7f, 0.7f, 0.7f}));
    auto s = evalPattern({{"f", {{"type", "fresnel.schlick"}, {"inputs", {{"f0", 0.04}, {"cos_theta", 0.0}}}}}}, "f", "F");
    EXPECT_FLOAT_EQ(s[0], 1.f);
    auto c = evalPattern({{"f", {{"type", "fresnel.conductor"}, {"inputs", {{"eta", 1.5}, {"k", 2.0}, {"cos_theta", 1.0}}}}}}, "f", "F");
    EXPECT_NEAR(c[0], (0.25f + 4.f) / (6.25f + 4.f), 1e-6f);
}

// Program::compile pre-reads the ports that are constant in a program into the node's parameter struct
// (Instr::constParams) and reads only the varying ones per shade: a port fed by a literal, by a folded constant chain
// and by a node that varies per shading point (here the normal's length times 0.4, exactly 0.4 at a unit normal) must
// shade the same lobe; the varying one must follow the shading point.
TEST(GraphMaterial, PreReadConstantPortsMatchPortsReadPerShade) {
    auto ggx = [](const json& roughness, json extra) {
        extra["g"] = {{"type", "bsdf.ggx"},
                      {"inputs", {{"roughness", roughness}, {"anisotropy", 0.5}, {"f0", {0.9, 0.6, 0.5}}, {"fresnel", "schlick"}}}};
        return load({{"nodes", extra}, {"output", "@g.bsdf"}});
    };
    auto literal = ggx(0.4, json::object());
    auto folded = ggx("@k.out", {{"k", {{"type", "math.mul.float"}, {"inputs", {{"a", 0.8}, {"b", 0.5}}}}}});
    json varying = {{"n", {{"type", "geometry.normal"}}},
                    {"v", {{"type", "convert.normal3_to_vector3"}, {"inputs", {{"in", "@n.N"}}}}},
                    {"len", {{"type", "math.length.vector3"}, {"inputs", {{"v", "@v.out"}}}}},
                    {"k", {{"type", "math.mul.float"}, {"inputs", {{"a", "@len.out"}, {"b", 0.4}}}}}};
    auto dynamic = ggx("@k.out", varying);
    ShadingPoint sp = makeSp();
    Vec3 wo = glm::normalize(Vec3(0.2f, 0.1f, 1.f)), wi = glm::normalize(Vec3(-0.3f, 0.2f, 0.9f));
    auto value = [&](const std::shared_ptr<Material>& m, const ShadingPoint& at) {
        ScratchArena arena;
        Closure cl;
        m->shade(at, arena, cl);
        return test::query(cl, wo, wi).f.specular;
    };
    Color3 ref = value(literal, sp);
    EXPECT_GT(ref.x, 0.f);
    EXPECT_EQ(value(folded, sp), ref);
    EXPECT_EQ(value(dynamic, sp), ref);
    // A normal of length 2 (the node normalises it for its frame, the length graph reads it raw): roughness 0.8.
    ShadingPoint longer = sp;
    longer.n = Vec3(0, 0, 2);
    EXPECT_EQ(value(literal, longer), ref);
    EXPECT_EQ(value(dynamic, longer), value(ggx(0.8, json::object()), sp));
}

namespace {
// Fills the stack below the caller with NaN, so a shade that read a register it had not written (the template copy
// Program::shade skips when no node needs it) would see garbage rather than a lucky zero.
[[gnu::noinline]] void dirtyStack() {
    volatile float junk[8192];  // volatile: the stores are not dead code although nothing reads them
    for (int i = 0; i < 8192; ++i) junk[i] = std::numeric_limits<float>::quiet_NaN();
}
}  // namespace

TEST(GraphMaterial, BindingsAreReadFromTheShadingPointAndTheTemplateCopiedOnlyWhenRead) {
    // Two BSDFs on their own normal and tangent, summed: every port is constant, a closure or a binding.
    json direct = {{"g", {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", 0.5}, {"anisotropy", 0.6}, {"f0", {0.9, 0.6, 0.5}}}}}},
                   {"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", 0.5}}}}},
                   {"sum", {{"type", "closure.add"}, {"inputs", {{"a", "@g.bsdf"}, {"b", "@d.bsdf"}}}}}};
    // The same with the diffuse normal through a node without a parameter struct: the template is copied.
    json viaNode = direct;
    viaNode["n"] = {{"type", "geometry.normal"}};
    viaNode["d"]["inputs"]["normal"] = "@n.N";
    auto a = load({{"nodes", direct}, {"output", "@sum.bsdf"}});
    auto b = load({{"nodes", viaNode}, {"output", "@sum.bsdf"}});
    const Program& pa = std::dynamic_pointer_cast<GraphMaterial>(a)->program();
    const Program& pb = std::dynamic_pointer_cast<GraphMaterial>(b)->program();
    EXPECT_EQ(pa.prologueLoads(), 0u);
    EXPECT_FALSE(pa.readsTemplate());
    EXPECT_EQ(pb.prologueLoads(), 0u);  // every registered binding port is a member of its node's struct
    EXPECT_TRUE(pb.readsTemplate());

    ShadingPoint sp = makeSp();
    sp.n = Vec3(0.3f, -0.2f, 1.1f);  // not unit: the nodes normalise it
    sp.tangent = Vec4(0.9f, 0.4f, 0.1f, -1.f);
    const Frame frame = Frame::fromNormalTangent(glm::normalize(sp.n), Vec3(sp.tangent));
    float alpha = 0.25f, aspect = std::sqrt(1.f - 0.54f);
    GgxLobe ggx(alpha / aspect, alpha * aspect, Fresnel::schlick(Color3(0.9f, 0.6f, 0.5f)));
    for (const auto& mat : {a, b}) {
        ScratchArena arena;
        Closure shaded, ran;
        dirtyStack();
        mat->shade(sp, arena, shaded);
        std::dynamic_pointer_cast<GraphMaterial>(mat)->program().run(sp, arena, &ran, nullptr);
        ASSERT_EQ(shaded.size(), 2);
        for (int k = 0; k < 12; ++k) {
            Vec3 wo = glm::normalize(Vec3(0.1f * k - 0.6f, 0.3f, 1.f)), wi = glm::normalize(Vec3(0.5f, -0.05f * k, 0.8f));
            BsdfEval got = test::query(shaded, wo, wi).f, again = test::query(ran, wo, wi).f;
            Vec3 woL = frame.toLocal(wo), wiL = frame.toLocal(wi);
            Color3 spec = ggx.eval(woL, wiL);
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(got.specular[c], again.specular[c]);
                EXPECT_EQ(got.diffuse[c], again.diffuse[c]);
                EXPECT_NEAR(got.specular[c], spec[c], 1e-6f * std::max(1.f, spec[c]));
                EXPECT_NEAR(got.diffuse[c], 0.5f / kPi * std::max(wiL.z, 0.f), 1e-6f);
            }
        }
    }
}

// Material::needsDerivatives: true when a live node reads differentials (kNeedsDerivatives) or a port is bound to one
// (texture.normal_map's duvdx and surface_dndx), so the renderer builds them only for such materials (issue 15).
TEST(GraphMaterial, NeedsDerivativesOnlyWhenANodeOrABindingReadsThem) {
    json ggx = {{"g", {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", 0.3}}}}},
                {"d", {{"type", "bsdf.diffuse"}}},
                {"sum", {{"type", "closure.add"}, {"inputs", {{"a", "@g.bsdf"}, {"b", "@d.bsdf"}}}}}};
    EXPECT_FALSE(load({{"nodes", ggx}, {"output", "@sum.bsdf"}})->needsDerivatives());
    json filtered = {{"g", {{"type", "bsdf.ggx_filtered"}}}};
    EXPECT_TRUE(load({{"nodes", filtered}, {"output", "@g.bsdf"}})->needsDerivatives());
    json mapped = {{"nm", {{"type", "texture.normal_map"}, {"inputs", {{"color", {0.6, 0.5, 0.9}}}}}},
                   {"g", {{"type", "bsdf.ggx"}, {"inputs", {{"normal", "@nm.normal"}}}}}};
    EXPECT_TRUE(load({{"nodes", mapped}, {"output", "@g.bsdf"}})->needsDerivatives());
    // A node that is not live does not count.
    json unused = ggx;
    unused["f"] = {{"type", "bsdf.ggx_filtered"}};
    EXPECT_FALSE(load({{"nodes", unused}, {"output", "@sum.bsdf"}})->needsDerivatives());
}

// Program::shadeBatch (issue 37: the renderer's batched camera stage) computes what shade() computes point by point:
// the same closure bits and emission, for a program of nodes with a batch entry (batch of up to 64), one whose
// register file allows only sub-batches (a 300-node chain: 600+ registers), and one too large to batch at all (a
// 2,100-node chain, shaded point by point inside shadeBatch).
TEST(GraphMaterial, ShadeBatchEqualsShadePerPointForEveryBatchShape) {
    auto chained = [](int length) {
        json nodes = {{"uv", {{"type", "geometry.uv"}}}};
        std::string prev = "@uv.uv";
        for (int i = 0; i < length; ++i) {
            const std::string id = "c" + std::to_string(i);
            nodes[id] = {{"type", "math.add.vec2"}, {"inputs", {{"a", prev}, {"b", {0.001, -0.0005}}}}};
            prev = "@" + id + ".out";
        }
        nodes["len"] = {{"type", "math.length.vec2"}, {"inputs", {{"v", prev}}}};
        nodes["rough"] = {{"type", "math.clamp.float"}, {"inputs", {{"x", "@len.out"}, {"lo", 0.05}, {"hi", 1.0}}}};
        nodes["g"] = {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", "@rough.out"}, {"anisotropy", 0.3}}}};
        nodes["e"] = {{"type", "bsdf.emission"}, {"inputs", {{"color", {0.5, 0.25, 1.0}}, {"strength", "@len.out"}}}};
        nodes["sum"] = {{"type", "closure.add"}, {"inputs", {{"a", "@g.bsdf"}, {"b", "@e.bsdf"}}}};
        return json{{"nodes", nodes}, {"output", "@sum.bsdf"}};
    };
    json direct = {{"nodes",
                    {{"g", {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", 0.4}, {"anisotropy", 0.6}, {"f0", {0.9, 0.6, 0.5}}}}}},
                     {"d", {{"type", "bsdf.diffuse"}, {"inputs", {{"color", 0.5}}}}},
                     {"sum", {{"type", "closure.add"}, {"inputs", {{"a", "@g.bsdf"}, {"b", "@d.bsdf"}}}}}}},
                   {"output", "@sum.bsdf"}};
    struct Case {
        const char* name;
        json graph;
        size_t minRegisters;
    };
    const Case cases[] = {{"batch-entry nodes", direct, 0}, {"sub-batches", chained(300), 600}, {"too large", chained(2100), 4096}};
    constexpr size_t kPoints = 75;  // more than one batch of 64, and a remainder
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        auto mat = load(c.graph);
        const Program& prog = std::dynamic_pointer_cast<GraphMaterial>(mat)->program();
        EXPECT_GE(prog.registerCount(), c.minRegisters);
        std::vector<ShadingPoint> sps(kPoints, makeSp());
        std::vector<const ShadingPoint*> ptrs;
        std::vector<Closure> batched(kPoints);
        std::vector<Closure*> outs;
        for (size_t k = 0; k < kPoints; ++k) {
            sps[k].n = glm::normalize(Vec3(0.02f * float(k) - 0.7f, 0.3f - 0.01f * float(k), 1.f));
            sps[k].uv = Vec2(0.013f * float(k), 0.5f - 0.004f * float(k));
            sps[k].tangent = Vec4(1.f, 0.05f * float(k % 7), 0.f, 1.f);
            ptrs.push_back(&sps[k]);
            outs.push_back(&batched[k]);
        }
        ScratchArena batchArena;
        std::vector<Color3> batchedLe(kPoints, Color3(-1.f));
        dirtyStack();
        mat->shadeBatch(ptrs.data(), kPoints, batchArena, outs.data(), batchedLe.data());
        for (size_t k = 0; k < kPoints; ++k) {
            ScratchArena arena;
            Closure single;
            Color3 Le(-1.f);
            mat->shade(sps[k], arena, single, &Le);
            ASSERT_EQ(single.size(), batched[k].size()) << k;
            ASSERT_GT(single.size(), 0) << k;
            for (int c3 = 0; c3 < 3; ++c3) EXPECT_EQ(Le[c3], batchedLe[k][c3]) << k;
            for (int q = 0; q < 6; ++q) {
                const Vec3 wo = glm::normalize(Vec3(0.2f * q - 0.5f, 0.3f, 1.f)), wi = glm::normalize(Vec3(0.4f, -0.1f * q, 0.9f));
                const BsdfEval a = test::query(single, wo, wi).f, b = test::query(batched[k], wo, wi).f;
                for (int c3 = 0; c3 < 3; ++c3) {
                    EXPECT_EQ(a.specular[c3], b.specular[c3]) << k;
                    EXPECT_EQ(a.diffuse[c3], b.diffuse[c3]) << k;
                }
            }
        }
        // The chain's emission strength varies with uv, so a point shaded with another point's registers would show.
        if (c.minRegisters > 0) EXPECT_NE(batchedLe[0][0], batchedLe[kPoints - 1][0]);
    }
}
