// Drift guard for the GLSL LTC path (nodes/shared/ltc.glsl): polygon queries of bsdf.diffuse, bsdf.ggx,
// bsdf.ggx_filtered and bsdf.beckmann_lean on Mesa llvmpipe against Closure::integratePolygon of the same node.
//
// Per node, 4096 samples with random frames, parameters (the parity ranges of docs/nodes.md), views and quads in three
// classes (fully above the geometric horizon, straddling it, seen from behind = clockwise; every fifth one cut to a
// triangle), each answered with both horizon modes (exact clip, clip-free sphere table). The error measure is
// |gpu − cpu| / max(|cpu|, kFloor) per channel; the limits are the measured maxima with margin (ltc-filtering.md §3;
// the CPU integrates in double, the GLSL in float). Also an emitted material module (closure.mix of bsdf.diffuse and an anisotropic bsdf.ggx) whose
// tables are bound from its manifest only, and the partial flag of a lobe without a closed form.
#define GL_GLEXT_PROTOTYPES 1
#include "core/codegen/glsl_emitter.h"
#include "core/codegen/glsl_manifest.h"
#include "core/codegen/glsl_signature.h"
#include "core/codegen/glsl_sources.h"
#include "core/graph/graph_material.h"
#include "core/ltc/ltc_ggx.h"
#include "nodes/shared/ltc_gpu.h"
#include "glsl_harness.h"
#include "tests/unit/test_support.h"

#include <GL/gl.h>
#include <GL/glext.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <set>

using namespace specula;
using namespace specula::graph;
using nlohmann::json;

namespace {

constexpr int kSamples = 4096;
// Relative-error floor: integrals below it (e.g. the zeros of back-facing quads, or a sliver of a straddling quad)
// are compared absolutely. The largest integrals are O(1) (a big quad in front of a diffuse or rough lobe).
constexpr float kFloor = 1e-3f;
// Data per sample: N3 T3 wo3 | polygon 4×3 | dwodx3 dwody3 | vertex count | the node's inputs.
constexpr int kPoly = 9, kDeriv = 21, kCount = 27, kInputs = 28;

Vec3 randUnit(std::mt19937& rng) {
    std::normal_distribution<float> n(0.f, 1.f);
    Vec3 v;
    do v = Vec3(n(rng), n(rng), n(rng));
    while (glm::dot(v, v) < 1e-4f);
    return glm::normalize(v);
}

// Quad classes of the test.
enum QuadClass { kAbove = 0, kStraddling = 1, kBehind = 2 };
const char* className(int c) { return c == kAbove ? "above" : c == kStraddling ? "straddling" : "behind"; }

// A random quad in the frame (t, b, n) of the shading point: centre at elevation 'elev' (radians) and distance d, its
// plane tilted up to ~40° from facing the shading point, counter-clockwise seen from it (clockwise for kBehind).
// Returns false if the drawn quad is not of its class (the caller draws again).
bool randomQuad(std::mt19937& rng, int cls, const Vec3& t, const Vec3& b, const Vec3& n, Vec3 out[4]) {
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    const float pi = 3.14159265f;
    float elev = cls == kStraddling ? (-0.15f + 0.4f * u01(rng)) : (0.2f + 1.3f * u01(rng));
    float az = 2.f * pi * u01(rng);
    Vec3 dir = std::cos(elev) * (std::cos(az) * t + std::sin(az) * b) + std::sin(elev) * n;
    float d = 1.f + 4.f * u01(rng);
    Vec3 C = d * dir;
    Vec3 facing = glm::normalize(-dir + 0.7f * randUnit(rng) * u01(rng));  // the quad's normal, towards the point
    if (glm::dot(facing, -dir) < 0.3f) facing = -dir;
    Vec3 u = glm::normalize(glm::cross(facing, randUnit(rng)));
    // cross(u, v) = −facing points away from the shading point: then (−−, +−, ++, −+) runs counter-clockwise seen
    // from it, the orientation with a positive edge sum (ltc.cpp facing()).
    Vec3 v = glm::cross(u, facing);
    float su = d * (0.05f + 0.6f * u01(rng)), sv = d * (0.05f + 0.6f * u01(rng));
    Vec3 q[4] = {C - su * u - sv * v, C + su * u - sv * v, C + su * u + sv * v, C - su * u + sv * v};
    int above = 0;
    for (auto& p : q) above += glm::dot(p, n) > 0.f;
    if (cls == kStraddling && (above == 0 || above == 4)) return false;
    if (cls != kStraddling && above != 4) return false;
    if (glm::dot(glm::cross(q[1] - q[0], q[2] - q[0]), C) <= 0.f) return false;  // wrong side (cannot happen)
    for (int k = 0; k < 4; ++k) out[k] = cls == kBehind ? q[3 - k] : q[k];
    return true;
}

// Sampling range of an input (as the direction parity test, docs/nodes.md).
void inputRange(const NodeSpec& s, const PortSpec& p, float& lo, float& hi) {
    lo = std::isfinite(p.minValue) ? p.minValue : -2.f;
    hi = std::isfinite(p.maxValue) ? p.maxValue : 2.f;
    if (s.id == "bsdf.ggx" && p.name == "roughness") lo = 0.1f;
}

// The string inputs of a node (port order): defaults, and bsdf.ltc_normal_map's map (a generated 16² flakes map,
// square and power-of-two, as the direction parity test uses).
std::vector<std::string> nodeStrings(const NodeSpec& s) {
    std::vector<std::string> v;
    for (auto& p : s.inputs) v.push_back(p.defString);
    if (s.id == "bsdf.ltc_normal_map") v[size_t(s.inputIndex("normal_map"))] = "generate:flakes:16:7";
    if (s.id == "bsdf.glint_pndf") v[size_t(s.inputIndex("normal_map"))] = "generate:bumps:16:7";
    return v;
}

struct Layout {
    std::vector<int> inOffset;
    int floats = kInputs;
};
Layout layoutFor(const NodeSpec& s) {
    Layout L;
    for (auto& p : s.inputs) {
        int w = p.type == TypeDesc::String ? (p.enumValues.empty() ? 0 : 1) : typeWidth(p.type);
        L.inOffset.push_back(w ? L.floats : -1);
        L.floats += w;
    }
    return L;
}

// Fragment shader: row = sample, column 0 = exact clip, 1 = clip-free; out = (f, partial).
std::string ltcShader(const NodeSpec& s, const Layout& L) {
    std::string src = "#version 450\n" + codegen::glslPrelude() + codegen::glslEnumConstants(s) +
                      codegen::glslNodeLibraries(s.glslLibraries) + *s.glslSource() + "\n";
    std::vector<std::string> res;
    for (size_t r = 0; r < s.resources.size(); ++r) {
        res.push_back("spc_res" + std::to_string(r));
        src += "layout(binding = " + std::to_string(r + 1) + ") uniform " + s.resources[r].glslType + " " + res.back() + ";\n";
    }
    src += R"(layout(binding = 0) uniform sampler2D spc_data;
layout(location = 0) out vec4 spc_out;
float spc_in(int i) { return texelFetch(spc_data, ivec2(i >> 2, int(gl_FragCoord.y)), 0)[i & 3]; }
vec2 spc_in2(int i) { return vec2(spc_in(i), spc_in(i + 1)); }
vec3 spc_in3(int i) { return vec3(spc_in(i), spc_in(i + 1), spc_in(i + 2)); }
void main() {
    SpeculaShadingInputs s;
    s.front_facing = true;
    s.position = vec3(0.0); s.normal = spc_in3(0); s.geometric_normal = s.normal; s.tangent = vec4(spc_in3(3), 1.0);
    s.uv = vec2(0.0); s.dPdx = vec3(0.0); s.dPdy = vec3(0.0); s.duvdx = vec2(0.0); s.duvdy = vec2(0.0);
    s.dNdx = vec3(0.0); s.dNdy = vec3(0.0); s.dwodx = spc_in3(21); s.dwody = spc_in3(24);
    SpeculaClosureQuery q = specula_polygon_query(spc_in3(6), spc_in3(9), spc_in3(12), spc_in3(15), spc_in3(18), int(spc_in(27)),
                                                  int(gl_FragCoord.x) == 0 ? SPC_HORIZON_CLIP : SPC_HORIZON_CLIPLESS);
)";
    auto expr = [&](int k) -> std::string {
        const PortSpec& p = s.inputs[size_t(k)];
        std::string off = std::to_string(L.inOffset[size_t(k)]);
        if (p.type == TypeDesc::String) return "int(spc_in(" + off + "))";
        switch (typeWidth(p.type)) {
            case 1: return "spc_in(" + off + ")";
            case 2: return "spc_in2(" + off + ")";
            default: return "spc_in3(" + off + ")";
        }
    };
    std::vector<std::string> outs;
    for (size_t k = 0; k < s.outputs.size(); ++k) {
        outs.push_back("o" + std::to_string(k));
        src += std::string("    ") + glslTypeName(s.outputs[k].type) + " " + outs.back() + ";\n";
    }
    src += "    " + glsltest::nodeCall(s, expr, outs, res) + ";\n";
    src += "    spc_out = vec4(o0.f, o0.partial ? 1.0 : 0.0);\n}\n";
    return src;
}

struct Stats {
    float maxErr[2][3] = {};  // [horizon][class]
    int worst[2] = {-1, -1};
    float worstCpu[2] = {}, worstGpu[2] = {};
    int nonZero = 0, partial = 0;
};

Stats runNode(const NodeSpec& s, std::string* failure) {
    Stats st;
    Layout L = layoutFor(s);
    std::mt19937 rng(4242u + uint32_t(std::hash<std::string>()(s.id) & 0xffff));
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<std::vector<float>> data(kSamples, std::vector<float>(size_t(L.floats), 0.f));
    const int nrm = s.inputIndex("normal"), tan = s.inputIndex("tangent");
    for (int j = 0; j < kSamples; ++j) {
        float* d = data[size_t(j)].data();
        auto put3 = [&](int o, Vec3 v) { d[o] = v.x, d[o + 1] = v.y, d[o + 2] = v.z; };
        for (size_t k = 0; k < s.inputs.size(); ++k) {
            const PortSpec& p = s.inputs[k];
            int o = L.inOffset[k];
            if (o < 0) continue;
            if (p.type == TypeDesc::String) {
                d[o] = p.uniform ? 0.f : float((j / 3) % int(p.enumValues.size()));  // derivative source: analytic
            } else if (int(k) == nrm || int(k) == tan) {
                put3(o, randUnit(rng));
            } else if (p.uniform) {  // one value per material, possibly baked into the resources: the default
                for (int c = 0; c < typeWidth(p.type); ++c) d[o + c] = p.def[size_t(c)];
            } else {
                float lo, hi;
                inputRange(s, p, lo, hi);
                for (int c = 0; c < typeWidth(p.type); ++c) d[o + c] = lo + (hi - lo) * u01(rng);
            }
        }
        const Vec3 N(d[L.inOffset[size_t(nrm)]], d[L.inOffset[size_t(nrm)] + 1], d[L.inOffset[size_t(nrm)] + 2]);
        const Vec3 T0(d[L.inOffset[size_t(tan)]], d[L.inOffset[size_t(tan)] + 1], d[L.inOffset[size_t(tan)] + 2]);
        put3(0, N);
        put3(3, T0);
        Vec3 wo = randUnit(rng);
        if (glm::dot(wo, N) < 0.f && u01(rng) < 0.9f) wo = -wo;  // a few views below the surface (answer 0)
        put3(6, wo);
        Frame f = Frame::fromNormalTangent(N, T0);
        Vec3 q[4];
        while (!randomQuad(rng, j % 3, f.t, f.b, f.n, q)) {
        }
        for (int k = 0; k < 4; ++k) put3(kPoly + 3 * k, q[k]);
        for (int k = kDeriv; k < kCount; ++k) d[k] = -0.05f + 0.1f * u01(rng);
        d[kCount] = j % 5 == 4 ? 3.f : 4.f;  // every fifth polygon a triangle (its first three vertices)
    }
    // GPU
    const int texW = (L.floats + 3) / 4;
    std::vector<float> packed(size_t(texW) * 4 * kSamples, 0.f);
    for (int j = 0; j < kSamples; ++j)
        std::copy(data[size_t(j)].begin(), data[size_t(j)].end(), packed.begin() + std::ptrdiff_t(size_t(j) * texW * 4));
    std::string log;
    unsigned prog = glsltest::glProgram(ltcShader(s, L), &log);
    if (!prog) {
        *failure = "GL compile/link failed: " + log;
        return st;
    }
    unsigned dataTex = glsltest::glDataTexture(texW, kSamples, packed);
    // The resources as the node prepares them (built-in tables ignore the prepared data).
    std::vector<glsltest::GlTexture> tex;
    const std::vector<std::string> strings = nodeStrings(s);
    const std::vector<graph::ResourceImage> images =
        codegen::nodeResourceImages(s, strings, std::vector<std::string>(s.inputs.size()), GraphLoadContext{});
    for (size_t r = 0; r < images.size(); ++r) tex.push_back(glsltest::glResourceTexture(images[r], s.resources[r].glslType));
    std::vector<float> gpu = glsltest::glRun(prog, 2, kSamples, [&] {
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, dataTex);
        for (size_t r = 0; r < tex.size(); ++r) {
            glActiveTexture(GLenum(GL_TEXTURE1 + r));
            glBindTexture(tex[r].target, tex[r].name);
        }
    });
    glDeleteTextures(1, &dataTex);
    for (auto& t : tex) glDeleteTextures(1, &t.name);
    glDeleteProgram(prog);

    // CPU: the node alone in a graph, its closure's integratePolygon (world-space offsets, as the integrator asks).
    ScratchArena arena;
    for (int j = 0; j < kSamples; ++j) {
        const float* d = data[size_t(j)].data();
        auto v3 = [&](int o) { return Vec3(d[o], d[o + 1], d[o + 2]); };
        json inputs = json::object();
        for (size_t k = 0; k < s.inputs.size(); ++k) {
            const PortSpec& p = s.inputs[k];
            int o = L.inOffset[k];
            if (o < 0) {
                if (p.type == TypeDesc::String && !strings[k].empty()) inputs[p.name] = strings[k];
                continue;
            }
            if (p.type == TypeDesc::String) {
                inputs[p.name] = p.enumValues[size_t(d[o])];
                continue;
            }
            json arr = json::array();
            for (int c = 0; c < typeWidth(p.type); ++c) arr.push_back(d[o + c]);
            inputs[p.name] = typeWidth(p.type) == 1 ? arr[0] : arr;
        }
        json m = {{"nodes", {{"n", {{"type", s.id}, {"inputs", inputs}}}}}, {"output", "@n.bsdf"}};
        GraphDesc g = parseGraph(m, "/ltc", ParseOptions{false});
        Program program = Program::compile(g, {{g.findNode("n"), 0}}, nullptr);
        ShadingPoint sp;
        sp.n = sp.ng = v3(0);
        sp.tangent = Vec4(v3(3), 1.f);
        sp.frame = Frame::fromNormal(sp.n);
        sp.wo = v3(6);
        sp.dwodx = v3(kDeriv), sp.dwody = v3(kDeriv + 3);
        sp.hasDifferentials = true;
        Closure cl;
        Color3 em(0.f);
        program.run(sp, arena, &cl, &em);
        Vec3 poly[4] = {v3(kPoly), v3(kPoly + 3), v3(kPoly + 6), v3(kPoly + 9)};
        for (int h = 0; h < 2; ++h) {
            BsdfQuery bq;
            bq.wo = sp.wo;
            bq.polygonHorizon = uint8_t(h);
            BsdfEval e;
            LobeMask done = cl.integratePolygon(bq, poly, int(d[kCount]), e);
            if (done != cl.allLobes()) *failure = s.id + ": a lobe has no closed form on the CPU";
            Color3 c = e.total();
            const float* gp = &gpu[(size_t(j) * 2 + size_t(h)) * 4];
            st.partial += gp[3] != 0.f;
            for (int ch = 0; ch < 3; ++ch) {
                float err = std::abs(gp[ch] - c[ch]) / std::max(std::abs(c[ch]), kFloor);
                if (std::isnan(err)) err = 1e30f;
                st.nonZero += std::abs(c[ch]) > kFloor;
                float& mx = st.maxErr[h][j % 3];
                if (err > mx) {
                    mx = err;
                    if (err >= std::max(st.maxErr[h][0], std::max(st.maxErr[h][1], st.maxErr[h][2])))
                        st.worst[h] = j, st.worstCpu[h] = c[ch], st.worstGpu[h] = gp[ch];
                }
            }
        }
        arena.reset();
    }
    return st;
}

// Limits per node and horizon mode over all three quad classes. Measured maxima on llvmpipe (Mesa, 4096 samples,
// floor 1e-3; docs/ltc-tables.md "GLSL"), clip / clip-free: diffuse 1.8e-5 / 1.9e-5, ggx 6.4e-5 / 4.0e-5,
// ggx_filtered 2.5e-5 / 2.5e-5, beckmann_lean 3.2e-5 / 2.6e-5. The residue is float rounding (vertex transform,
// normalisation, edge sums) against the CPU's double integration, largest for sharp lobes (α down to 0.01) whose
// peak a quad edge cuts.
struct Limits {
    const char* id;
    float clip, clipless;
};
const Limits kLimits[] = {
    {"bsdf.diffuse", 1e-4f, 1e-4f},
    {"bsdf.ggx", 1e-4f, 1e-4f},
    {"bsdf.ggx_filtered", 1e-4f, 1e-4f},
    {"bsdf.beckmann_lean", 1e-4f, 1e-4f},
    // 16² generated map (uniform ports at their defaults), footprints from the ports' ranges, quads and triangles:
    // measured 2.7e-5 / 2.4e-5.
    {"bsdf.ltc_normal_map", 1e-4f, 1e-4f},
};

class GlslLtcParity : public ::testing::TestWithParam<int> {
protected:
    void SetUp() override {
        std::string why;
        ASSERT_TRUE(glsltest::glContext(&why)) << "headless EGL context unavailable: " << why;
    }
};

TEST_P(GlslLtcParity, PolygonQueryMatchesCpu) {
    const Limits& lim = kLimits[GetParam()];
    const NodeSpec* s = NodeRegistry::instance().find(lim.id);
    ASSERT_NE(s, nullptr);
    auto t0 = std::chrono::steady_clock::now();
    std::string failure;
    Stats st = runNode(*s, &failure);
    ASSERT_TRUE(failure.empty()) << failure;
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (int h = 0; h < 2; ++h)
        std::printf("LTC PARITY %-20s %-8s above %.3g  straddling %.3g  behind %.3g  (worst sample %d: cpu %.6g gpu %.6g)\n",
                    lim.id, h ? "clipless" : "clip", st.maxErr[h][0], st.maxErr[h][1], st.maxErr[h][2], st.worst[h],
                    st.worstCpu[h], st.worstGpu[h]);
    std::printf("LTC PARITY %-20s non-zero channels %d of %d, %.2f s\n", lim.id, st.nonZero, kSamples * 6, secs);
    EXPECT_EQ(st.partial, 0) << "the LTC lobes answer polygon queries themselves";
    EXPECT_GT(st.nonZero, kSamples);  // the comparison is not of zeros
    for (int c = 0; c < 3; ++c) {
        EXPECT_LE(st.maxErr[0][c], lim.clip) << className(c) << " quads, exact clip";
        EXPECT_LE(st.maxErr[1][c], lim.clipless) << className(c) << " quads, clip-free";
    }
}

INSTANTIATE_TEST_SUITE_P(LtcNodes, GlslLtcParity, ::testing::Range(0, int(std::size(kLimits))), [](const auto& info) {
    std::string n = kLimits[info.param].id;
    for (char& c : n)
        if (!std::isalnum((unsigned char)c)) c = '_';
    return n;
});

// The table lookups alone (shared/ltc.glsl vs core/ltc): spc_ltc_ggx_matrix against ltc::ggxRoughnessMatrix for
// isotropic, axis-aligned and rotated roughness matrices and any view azimuth (mirror symmetries), and
// spc_ltc_sphere_scale against ltc::sphereScale, with the tables as the resources produce them.
TEST(GlslLtcLookups, MatchTheCpuTables) {
    std::string why;
    ASSERT_TRUE(glsltest::glContext(&why)) << why;
    std::string fs = "#version 450\n" + codegen::glslPrelude() + codegen::glslLibraryText("shared/ltc.glsl") + R"(
layout(binding = 0) uniform sampler2D spc_data;
layout(binding = 1) uniform sampler2D ltc_matrix;
layout(binding = 2) uniform sampler2D ltc_amplitude;
layout(binding = 3) uniform sampler2D ltc_anisotropic;
layout(location = 0) out vec4 spc_out;
void main() {
    vec4 a = texelFetch(spc_data, ivec2(0, int(gl_FragCoord.y)), 0), b = texelFetch(spc_data, ivec2(1, int(gl_FragCoord.y)), 0);
    mat3 invM;
    vec2 mf;
    spc_ltc_ggx_matrix(ltc_matrix, ltc_amplitude, ltc_anisotropic, a.xyz, b.xyz, invM, mf);
    int c = int(gl_FragCoord.x);
    spc_out = c < 3 ? vec4(invM[c], 0.0) : vec4(mf, spc_ltc_sphere_scale(ltc_amplitude, a.w, b.w), 0.0);
}
)";
    std::string log;
    unsigned prog = glsltest::glProgram(fs, &log);
    ASSERT_NE(prog, 0u) << log;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    const int n = 4096;
    std::vector<float> data(size_t(n) * 8, 0.f);
    for (int j = 0; j < n; ++j) {
        float* d = &data[size_t(j) * 8];
        float ax = 0.01f + 0.99f * u01(rng), ay = 0.01f + 0.99f * u01(rng);
        float a = ax * ax, dd = ay * ay, c = 0.f;
        if (j % 3 == 0) dd = a;                                                  // isotropic
        if (j % 3 == 2) c = (2.f * u01(rng) - 1.f) * 0.95f * std::sqrt(a * dd);  // rotated principal axes
        Vec3 wo = randUnit(rng);
        wo.z = std::abs(wo.z);
        if (j % 17 == 0) wo = Vec3(0.f, 0.f, 1.f);
        float v[8] = {a, c, dd, 2.f * u01(rng) - 1.f, wo.x, wo.y, wo.z, u01(rng)};
        std::copy(v, v + 8, d);
    }
    unsigned dataTex = glsltest::glDataTexture(2, n, data);
    std::vector<glsltest::GlTexture> tex;
    for (const ResourceSpec& r : {ltc::matrixResource(), ltc::amplitudeResource(), ltc::anisotropicResource()})
        tex.push_back(glsltest::glResourceTexture(r.produce(nullptr), r.glslType));
    std::vector<float> gpu = glsltest::glRun(prog, 4, n, [&] {
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, dataTex);
        for (size_t r = 0; r < tex.size(); ++r) {
            glActiveTexture(GLenum(GL_TEXTURE1 + r));
            glBindTexture(GL_TEXTURE_2D, tex[r].name);
        }
    });
    glDeleteTextures(1, &dataTex);
    for (auto& t : tex) glDeleteTextures(1, &t.name);
    glDeleteProgram(prog);
    float matErr[3] = {}, ampErr = 0.f, sphereErr = 0.f;
    for (int j = 0; j < n; ++j) {
        const float* d = &data[size_t(j) * 8];
        const float* g = &gpu[size_t(j) * 16];
        ltc::Ltc l = ltc::ggxRoughnessMatrix(ltc::builtinTables(), d[0], d[1], d[2], Vec3(d[4], d[5], d[6]));
        float scale = 0.f, err = 0.f;
        for (int col = 0; col < 3; ++col)
            for (int row = 0; row < 3; ++row) {
                scale = std::max(scale, std::abs(l.invM[col][row]));
                err = std::max(err, std::abs(g[col * 4 + row] - l.invM[col][row]));
            }
        matErr[j % 3] = std::max(matErr[j % 3], err / scale);  // relative to the matrix's largest entry
        ampErr = std::max({ampErr, std::abs(g[12] - l.magnitude) / std::max(l.magnitude, 1e-3f),
                           std::abs(g[13] - l.fresnel) / std::max(l.fresnel, 1e-3f)});
        float sc = ltc::sphereScale(ltc::builtinTables(), d[3], d[7]);
        sphereErr = std::max(sphereErr, std::abs(g[14] - sc) / std::max(sc, 1e-3f));
    }
    std::printf("LTC LOOKUPS invM (rel. to max entry) iso %.3g axis-aligned %.3g rotated %.3g; mag/fres %.3g; sphere %.3g\n",
                matErr[0], matErr[1], matErr[2], ampErr, sphereErr);
    // Measured: 2.1e-7, 5.3e-7, 5.7e-7 (rotated: float eigen-axes against the CPU's double ones), 7.1e-7, 1.2e-7.
    EXPECT_LE(matErr[0], 5e-6f);
    EXPECT_LE(matErr[1], 5e-6f);
    EXPECT_LE(matErr[2], 5e-6f);
    EXPECT_LE(ampErr, 5e-6f);
    EXPECT_LE(sphereErr, 5e-6f);
}

// The main() of the emitted-module tests: per sample 6 texels (N T | wo | 4 vertices) at binding 15.
std::string moduleMain(const std::string& prefix) {
    return R"(
layout(binding = 15) uniform sampler2D spc_data_;
layout(location = 0) out vec4 spc_out;
float spc_in(int i) { return texelFetch(spc_data_, ivec2(i >> 2, int(gl_FragCoord.y)), 0)[i & 3]; }
vec3 spc_in3(int i) { return vec3(spc_in(i), spc_in(i + 1), spc_in(i + 2)); }
void main() {
    SpeculaShadingInputs s;
    s.front_facing = true;
    s.position = vec3(0.0); s.normal = spc_in3(0); s.geometric_normal = s.normal; s.tangent = vec4(spc_in3(3), 1.0);
    s.uv = vec2(0.0); s.dPdx = vec3(0.0); s.dPdy = vec3(0.0); s.duvdx = vec2(0.0); s.duvdy = vec2(0.0);
    s.dNdx = vec3(0.0); s.dNdy = vec3(0.0); s.dwodx = vec3(0.0); s.dwody = vec3(0.0);
    vec3 poly[4] = vec3[4](spc_in3(9), spc_in3(12), spc_in3(15), spc_in3(18));
    SpeculaClosureQuery q = specula_polygon_query(spc_in3(6), poly, 4, int(gl_FragCoord.x) == 0 ? SPC_HORIZON_CLIP
                                                                                               : SPC_HORIZON_CLIPLESS);
    SpeculaClosure c;
    )" + prefix + R"(material(q, s, c);
    spc_out = vec4(c.f, c.partial ? 1.0 : 0.0);
}
)";
}

struct ModuleResult {
    float maxErr = 0.f;
    int nonZero = 0, partial = 0, resources = 0;
};

// Emits 'mj', binds its uniform block and every resource from its manifest alone, answers kSamples polygon queries
// in both horizon modes and compares with GraphMaterial::shade + Closure::integratePolygon (lobes with a closed form;
// 'partial' counts GPU answers flagged partial).
ModuleResult runModule(const json& mj, std::string* failure) {
    ModuleResult res;
    GraphDesc g = parseGraph(mj, "/materials/m");
    codegen::GlslModule mod = codegen::emitGlsl(g);
    // The library once, and each built-in table once however many nodes read it.
    size_t libs = 0;
    for (size_t p = mod.source.find("#define SPC_FILE_SHARED_LTC_GLSL"); p != std::string::npos;
         p = mod.source.find("#define SPC_FILE_SHARED_LTC_GLSL", p + 1))
        ++libs;
    if (libs != 1) *failure = "shared/ltc.glsl emitted " + std::to_string(libs) + " times";
    std::set<std::string> tables;
    for (const codegen::GlslResource& r : mod.resources)
        if (r.kind == ResourceSpec::Kind::BuiltinTable && !tables.insert(r.resource).second)
            *failure = "built-in table '" + r.resource + "' bound twice";
    GraphLoadContext load{};
    std::vector<ResourceImage> images = codegen::exportGlslResources(g, mod, load);
    json manifest = codegen::glslManifest(mod, images, {});
    res.resources = int(manifest["resources"].size());
    auto mat = loadGraphMaterial(mj, "/materials/m", load);
    std::string log;
    unsigned prog = glsltest::glProgram(mod.source + moduleMain(mod.entryPrefix), &log);
    if (!prog) {
        *failure = "GL compile/link failed: " + log;
        return res;
    }
    std::mt19937 rng(77);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    const int F = 24;  // N3 T3 wo3 poly12, padded to 6 texels
    std::vector<float> data(size_t(kSamples) * F, 0.f);
    for (int j = 0; j < kSamples; ++j) {
        float* d = &data[size_t(j) * F];
        Vec3 N = randUnit(rng), T = randUnit(rng), wo = randUnit(rng);
        if (glm::dot(wo, N) < 0.f) wo = -wo;
        Frame f = Frame::fromNormalTangent(N, T);
        Vec3 q[4];
        while (!randomQuad(rng, j % 3, f.t, f.b, f.n, q)) {
        }
        Vec3 all[7] = {N, T, wo, q[0], q[1], q[2], q[3]};
        for (int k = 0; k < 7; ++k) d[3 * k] = all[k].x, d[3 * k + 1] = all[k].y, d[3 * k + 2] = all[k].z;
    }
    unsigned dataTex = glsltest::glDataTexture(F / 4, kSamples, data);
    std::vector<float> gpu;
    {
        glsltest::ManifestBindings host;  // bound from the manifest alone
        host.add(manifest, images);
        gpu = glsltest::glRun(prog, 2, kSamples, [&] {
            host.bind();
            glActiveTexture(GL_TEXTURE15);
            glBindTexture(GL_TEXTURE_2D, dataTex);
        });
    }
    glDeleteTextures(1, &dataTex);
    glDeleteProgram(prog);

    ScratchArena arena;
    for (int j = 0; j < kSamples; ++j) {
        const float* d = &data[size_t(j) * F];
        auto v3 = [&](int o) { return Vec3(d[o], d[o + 1], d[o + 2]); };
        ShadingPoint sp;
        sp.n = sp.ng = v3(0);
        sp.tangent = Vec4(v3(3), 1.f);
        sp.frame = Frame::fromNormal(sp.n);
        sp.wo = v3(6);
        Closure cl;
        mat->shade(sp, arena, cl);
        Vec3 poly[4] = {v3(9), v3(12), v3(15), v3(18)};
        for (int h = 0; h < 2; ++h) {
            BsdfQuery bq;
            bq.wo = sp.wo;
            bq.polygonHorizon = uint8_t(h);
            BsdfEval e;
            cl.integratePolygon(bq, poly, 4, e);
            Color3 c = e.total();
            const float* gp = &gpu[(size_t(j) * 2 + size_t(h)) * 4];
            res.partial += gp[3] != 0.f;
            for (int ch = 0; ch < 3; ++ch) {
                float err = std::abs(gp[ch] - c[ch]) / std::max(std::abs(c[ch]), kFloor);
                res.maxErr = std::max(res.maxErr, std::isnan(err) ? 1e30f : err);
                res.nonZero += std::abs(c[ch]) > kFloor;
            }
        }
        arena.reset();
    }
    return res;
}

TEST(GlslLtcModule, MixOfDiffuseAndGgxAnswersPolygonQueries) {
    std::string why;
    ASSERT_TRUE(glsltest::glContext(&why)) << why;
    const json mj = json::parse(R"({"nodes": {
        "d": {"type": "bsdf.diffuse", "inputs": {"color": [0.7, 0.5, 0.3]}},
        "g": {"type": "bsdf.ggx", "inputs": {"roughness": 0.45, "anisotropy": 0.6, "fresnel": "conductor"}},
        "m": {"type": "closure.mix", "inputs": {"a": "@d.bsdf", "b": "@g.bsdf", "t": 0.35}}}, "output": "@m.bsdf"})");
    auto t0 = std::chrono::steady_clock::now();
    std::string failure;
    ModuleResult r = runModule(mj, &failure);
    ASSERT_TRUE(failure.empty()) << failure;
    EXPECT_EQ(r.resources, 3);  // ltc_matrix, ltc_amplitude (diffuse and ggx), ltc_anisotropic
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("LTC PARITY module diffuse+ggx mix  max_rel_err %.3g  (non-zero channels %d, %.2f s)\n", r.maxErr, r.nonZero, secs);
    EXPECT_EQ(r.partial, 0);
    EXPECT_GT(r.nonZero, kSamples * 2);
    EXPECT_LE(r.maxErr, 1e-4f);
}

// closure.coat over a diffuse + GGX mix: the coat lobe answers polygon queries with its GGX LTC, the base's answers are
// scaled by lerp(1, tint·(1 − E(μo)), weight) as on the CPU (coat.glsl against Closure::integratePolygon).
TEST(GlslLtcModule, CoatOverMixAnswersPolygonQueries) {
    std::string why;
    ASSERT_TRUE(glsltest::glContext(&why)) << why;
    const json mj = json::parse(R"({"nodes": {
        "d": {"type": "bsdf.diffuse", "inputs": {"color": [0.7, 0.5, 0.3]}},
        "g": {"type": "bsdf.ggx", "inputs": {"roughness": 0.45, "fresnel": "conductor"}},
        "m": {"type": "closure.mix", "inputs": {"a": "@d.bsdf", "b": "@g.bsdf", "t": 0.35}},
        "c": {"type": "closure.coat", "inputs": {"base": "@m.bsdf", "weight": 0.8, "roughness": 0.2, "ior": 1.6,
                                                 "tint": [0.9, 0.8, 0.6]}}}, "output": "@c.bsdf"})");
    std::string failure;
    ModuleResult r = runModule(mj, &failure);
    ASSERT_TRUE(failure.empty()) << failure;
    std::printf("LTC PARITY module coat over diffuse+ggx  max_rel_err %.3g  (non-zero channels %d)\n", r.maxErr, r.nonZero);
    EXPECT_EQ(r.partial, 0);
    EXPECT_GT(r.nonZero, kSamples * 2);
    EXPECT_LE(r.maxErr, 1e-4f);
}

// A lobe without a closed form (bsdf.glint) makes the whole answer partial; the LTC lobes beside it still answer.
TEST(GlslLtcModule, LobeWithoutClosedFormFlagsPartial) {
    std::string why;
    ASSERT_TRUE(glsltest::glContext(&why)) << why;
    const json mj = json::parse(R"({"nodes": {
        "d": {"type": "bsdf.diffuse", "inputs": {"color": [0.5, 0.5, 0.5]}},
        "g": {"type": "bsdf.glint", "inputs": {"ggaa": "off"}},
        "a": {"type": "closure.add", "inputs": {"a": "@d.bsdf", "b": "@g.bsdf"}}}, "output": "@a.bsdf"})");
    std::string failure;
    ModuleResult r = runModule(mj, &failure);
    ASSERT_TRUE(failure.empty()) << failure;
    EXPECT_EQ(r.partial, 2 * kSamples);
    EXPECT_LE(r.maxErr, 1e-4f);  // the diffuse part, which the CPU integrates alone as well
}

}  // namespace
