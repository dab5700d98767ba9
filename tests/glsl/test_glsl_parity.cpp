// Drift guard (dynamic): for every registered node, run its GLSL on Mesa llvmpipe through headless
// EGL over a grid of 1024 random inputs (one RGBA32F row per sample) and compare with the CPU
// evaluator on the same float inputs: max relative error |gpu − cpu| / max(|cpu|, 1e-3) must stay within
// NodeSpec::parityTolerance (1e-4 unless documented in docs/nodes.md). Also checks an emitted
// material module end to end (uniform block, bindings, specula_eval) and dFdx-based derivatives.
#define GL_GLEXT_PROTOTYPES 1
#include "core/codegen/glsl_emitter.h"
#include "core/codegen/glsl_manifest.h"
#include "core/codegen/glsl_signature.h"
#include "tests/unit/test_support.h"
#include "core/codegen/glsl_sources.h"
#include "core/color/color_config.h"
#include "core/graph/graph_material.h"
#include "tests/unit/test_support.h"
#include "core/texture/lean_moments.h"
#include "core/texture/texture_store.h"
#include "glsl_harness.h"
#include "nodes/bsdf/glint/glint_dictionary.h"

#include <algorithm>
#include <GL/gl.h>
#include <GL/glext.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

using namespace specula;
using namespace specula::graph;
using nlohmann::json;

namespace {

constexpr int kSide = 32, kSamples = kSide * kSide;
constexpr float kRelFloor = 1e-3f;
constexpr int kGeom = 31;  // P3 N3 Ng3 T4 uv2 dPdx3 dPdy3 duvdx2 duvdy2 dNdx3 dNdy3
// Then wo3 wi3 dwodx3 dwody3 and the light distance (0: a direction, +inf).
constexpr int kQuery = kGeom + 13;

struct Fixture {
    std::string dir;
    std::shared_ptr<TextureStore> store;
};

Fixture& fixture() {
    static Fixture f;
    static bool init = false;
    if (init) return f;
    init = true;
    f.dir = (std::filesystem::temp_directory_path() / "specula-parity-tex").string();
    std::filesystem::create_directories(f.dir);
    // 16x12 RGBA float image with smooth + sharp content.
    const int w = 16, h = 12;
    std::vector<float> px(w * h * 4);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float* p = &px[(y * w + x) * 4];
            p[0] = float(x) / (w - 1);
            p[1] = float(y) / (h - 1);
            p[2] = ((x + y) % 3) * 0.4f;
            p[3] = 0.25f + 0.5f * ((x * 7 + y * 3) % 5) / 4.f;
        }
    std::string file = f.dir + "/grid.exr";
    auto out = OIIO::ImageOutput::create(file);
    OIIO::ImageSpec spec(w, h, 4, OIIO::TypeDesc::FLOAT);
    out->open(file, spec);
    out->write_image(OIIO::TypeDesc::FLOAT, px.data());
    out->close();
    f.store = std::make_shared<TextureStore>(ColorConfig::load("builtin"));
    return f;
}

Vec3 randUnit(std::mt19937& rng) {
    std::normal_distribution<float> n(0.f, 1.f);
    Vec3 v;
    do v = Vec3(n(rng), n(rng), n(rng));
    while (glm::dot(v, v) < 1e-4f);
    return glm::normalize(v);
}

// The string inputs of a node with resources: the fixture image for the inputs its resources read the file and colour
// space from (ResourceSpec::fileInput / colorspaceInput), the default of every other string (enums: their first value).
std::vector<std::string> resourceStrings(const NodeSpec& s) {
    std::vector<std::string> v(s.inputs.size());
    for (size_t k = 0; k < s.inputs.size(); ++k) v[k] = s.inputs[k].defString;
    for (const ResourceSpec& r : s.resources) {
        if (!r.fileInput.empty()) v[size_t(s.inputIndex(r.fileInput))] = "grid.exr";
        if (!r.colorspaceInput.empty()) v[size_t(s.inputIndex(r.colorspaceInput))] = "raw";
    }
    // A square power-of-two map (the fixture image is 16×12): a generated 16² flakes map, 4 stored MIP levels.
    if (s.id == "bsdf.ltc_normal_map") v[size_t(s.inputIndex("normal_map"))] = "generate:flakes:16:7";
    // bsdf.glint_pndf refuses maps that do not decode to unit normals (the RGBA fixture): a generated bump map.
    if (s.id == "bsdf.glint_pndf") v[size_t(s.inputIndex("normal_map"))] = "generate:bumps:16:7";
    return v;
}

// Sampling range of an input for the parity grid (documented in docs/nodes.md).
void parityRange(const NodeSpec& s, const PortSpec& p, float& lo, float& hi) {
    lo = std::isfinite(p.minValue) ? p.minValue : -2.f;
    hi = std::isfinite(p.maxValue) ? p.maxValue : 2.f;
    if (s.id == "bsdf.ggx" && p.name == "roughness") lo = 0.1f;  // α ≥ 0.01: below, D's float conditioning dominates
    if (s.id == "texture.image" && (p.name == "duvdx" || p.name == "duvdy")) lo = hi = 0.f;  // bilinear (see docs)
}

struct Layout {
    std::vector<int> inOffset;  // per input port, -1 if not in the data
    int floats = 0;
    int outFloats = 0;
};

Layout layoutFor(const NodeSpec& s) {
    Layout L;
    L.floats = kQuery;
    for (auto& p : s.inputs) {
        int w = p.type == TypeDesc::Closure ? 3 : p.type == TypeDesc::String ? (p.enumValues.empty() ? 0 : 1) : typeWidth(p.type);
        L.inOffset.push_back(w ? L.floats : -1);
        L.floats += w;
    }
    for (auto& o : s.outputs) L.outFloats += o.type == TypeDesc::Closure ? 6 : typeWidth(o.type);
    return L;
}

std::string parityShader(const NodeSpec& s, const Layout& L) {
    bool closures = false;
    for (auto& p : s.inputs) closures |= p.type == TypeDesc::Closure;
    const NodeSpec* diffuse = NodeRegistry::instance().find("bsdf.diffuse");
    // Libraries are guarded, so the node's and the closure source's may overlap.
    std::string src = "#version 450\n" + codegen::glslPrelude() + codegen::glslEnumConstants(s) +
                      codegen::glslNodeLibraries(s.glslLibraries) +
                      (closures ? codegen::glslNodeLibraries(diffuse->glslLibraries) : std::string()) + *s.glslSource() + "\n";
    if (closures && s.glslFile != diffuse->glslFile) src += *diffuse->glslSource() + "\n";
    // The node's resources at bindings 1, 2, ... (binding 0 holds the data), bound from their ResourceImages; then
    // those of the bsdf.diffuse closure sources (parityClosureResources).
    std::vector<std::string> resources, diffuseResources;
    for (size_t r = 0; r < s.resources.size(); ++r) {
        resources.push_back("spc_res" + std::to_string(r));
        src += "layout(binding = " + std::to_string(r + 1) + ") uniform " + s.resources[r].glslType + " " + resources.back() + ";\n";
    }
    if (closures)
        for (size_t r = 0; r < diffuse->resources.size(); ++r) {
            diffuseResources.push_back("spc_dres" + std::to_string(r));
            src += "layout(binding = " + std::to_string(s.resources.size() + r + 1) + ") uniform " +
                   diffuse->resources[r].glslType + " " + diffuseResources.back() + ";\n";
        }
    src += R"(layout(binding = 0) uniform sampler2D spc_data;
layout(location = 0) out vec4 spc_out;
float spc_in(int i) { return texelFetch(spc_data, ivec2(i >> 2, int(gl_FragCoord.y)), 0)[i & 3]; }
vec2 spc_in2(int i) { return vec2(spc_in(i), spc_in(i + 1)); }
vec3 spc_in3(int i) { return vec3(spc_in(i), spc_in(i + 1), spc_in(i + 2)); }
void main() {
    SpeculaShadingInputs s;
    s.front_facing = true;
    s.position = spc_in3(0); s.normal = spc_in3(3); s.geometric_normal = spc_in3(6);
    s.tangent = vec4(spc_in3(9), spc_in(12)); s.uv = spc_in2(13);
    s.dPdx = spc_in3(15); s.dPdy = spc_in3(18); s.duvdx = spc_in2(21); s.duvdy = spc_in2(23);
    s.dNdx = spc_in3(25); s.dNdy = spc_in3(28);
    s.dwodx = spc_in3(37); s.dwody = spc_in3(40);
    float light_distance = spc_in(43) > 0.0 ? spc_in(43) : 1.0 / 0.0;
    SpeculaClosureQuery q = specula_direction_query(spc_in3(31), spc_in3(34), light_distance);
)";
    auto expr = [&](int k) -> std::string {
        const PortSpec& p = s.inputs[k];
        std::string off = std::to_string(L.inOffset[k]);
        if (p.type == TypeDesc::Closure) return "spc_cin" + std::to_string(k);
        if (p.type == TypeDesc::String) return "int(spc_in(" + off + "))";
        switch (typeWidth(p.type)) {
            case 1: return "spc_in(" + off + ")";
            case 2: return "spc_in2(" + off + ")";
            default: return "spc_in3(" + off + ")";
        }
    };
    for (size_t k = 0; k < s.inputs.size(); ++k)
        if (s.inputs[k].type == TypeDesc::Closure)
        {
            const std::string v = "spc_cin" + std::to_string(k), color = "spc_in3(" + std::to_string(L.inOffset[k]) + ")";
            src += "    SpeculaClosure " + v + ";\n    " +
                   glsltest::nodeCall(*diffuse, [&](int p) { return diffuse->inputs[size_t(p)].name == "color" ? color
                                                             : diffuse->inputs[size_t(p)].name == "normal" ? std::string("s.normal")
                                                                                                           : std::string("s.tangent.xyz"); },
                                      {v}, diffuseResources) + ";\n";
        }
    std::vector<std::string> outs;
    for (size_t k = 0; k < s.outputs.size(); ++k) {
        outs.push_back("o" + std::to_string(k));
        src += std::string("    ") + glslTypeName(s.outputs[k].type) + " " + outs.back() + ";\n";
    }
    src += "    " + glsltest::nodeCall(s, expr, outs, resources) + ";\n";
    src += "    float r[" + std::to_string(L.outFloats + 4) + "];\n";
    int m = 0;
    for (size_t k = 0; k < s.outputs.size(); ++k) {
        const std::string& o = outs[k];
        auto put = [&](const std::string& e) { src += "    r[" + std::to_string(m++) + "] = " + e + ";\n"; };
        if (s.outputs[k].type == TypeDesc::Closure) {
            for (const char* c : {".f.x", ".f.y", ".f.z", ".emission.x", ".emission.y", ".emission.z"}) put(o + c);
        } else if (typeWidth(s.outputs[k].type) == 1) {
            put(o);
        } else {
            for (int c = 0; c < typeWidth(s.outputs[k].type); ++c) put(o + "[" + std::to_string(c) + "]");
        }
    }
    for (int pad = 0; pad < 4; ++pad) src += "    r[" + std::to_string(m + pad) + "] = 0.0;\n";
    src += "    int c = int(gl_FragCoord.x) * 4;\n    spc_out = vec4(r[c], r[c + 1], r[c + 2], r[c + 3]);\n}\n";
    return src;
}

struct ParityResult {
    float maxErr = 0.f;
    int worstSample = -1, worstFloat = -1;
    float worstCpu = 0.f, worstGpu = 0.f;
    // bsdf.glint with flakes: samples with f > 0 whose flakes' weight (LobeParameters "flakes") is 1, between 0 and 1,
    // and 0 (explicit flakes, the hand-over, the counting at one microfacet per flake).
    int flakeRegimes[3] = {0, 0, 0};
};

ParityResult runParity(const NodeSpec& s, std::string* failure) {
    ParityResult res;
    Layout L = layoutFor(s);
    std::mt19937 rng(1234u + uint32_t(std::hash<std::string>()(s.id) & 0xffff));
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<std::vector<float>> data(kSamples, std::vector<float>(L.floats, 0.f));
    int nrm = s.inputIndex("normal");
    for (int j = 0; j < kSamples; ++j) {
        float* d = data[j].data();
        auto put3 = [&](int o, Vec3 v) { d[o] = v.x, d[o + 1] = v.y, d[o + 2] = v.z; };
        auto rnd = [&](float lo, float hi) { return lo + (hi - lo) * u01(rng); };
        for (int k = 0; k < 3; ++k) d[k] = rnd(-2.f, 2.f);
        Vec3 N = randUnit(rng);
        put3(3, N);
        put3(6, glm::normalize(N + 0.2f * randUnit(rng)));
        put3(9, randUnit(rng));
        d[12] = u01(rng) < 0.5f ? -1.f : 1.f;
        d[13] = rnd(0.f, 1.f), d[14] = rnd(0.f, 1.f);
        for (int k = 15; k < kGeom; ++k) d[k] = rnd(-0.05f, 0.05f);
        for (size_t k = 0; k < s.inputs.size(); ++k) {
            const PortSpec& p = s.inputs[k];
            int o = L.inOffset[k];
            if (o < 0) continue;
            if (p.type == TypeDesc::Closure) {
                for (int c = 0; c < 3; ++c) d[o + c] = rnd(0.f, 1.f);
            } else if (p.type == TypeDesc::String) {
                // Neighbouring pixels of the parity grid hold unrelated samples, so screen-space finite
                // differences are meaningless there: derivative sources are pinned to "analytic" where a port
                // offers it. Other uniform ports (sampler state) keep their first value for the whole grid.
                if (p.uniform) {
                    auto a = std::find(p.enumValues.begin(), p.enumValues.end(), "analytic");
                    d[o] = a == p.enumValues.end() ? 0.f : float(a - p.enumValues.begin());
                } else {
                    d[o] = float(j % int(p.enumValues.size()));
                }
            } else if (p.type == TypeDesc::Normal3 || (p.type == TypeDesc::Vector3 && p.binding == GeomBinding::T)) {
                put3(o, randUnit(rng));
            } else if (p.uniform) {
                // A uniform numeric port is one value per material, which a prepare step may have baked into the
                // node's resources (bsdf.ltc_normal_map's tables are fitted for its roughness): its default.
                for (int c = 0; c < typeWidth(p.type); ++c) d[o + c] = p.def[size_t(c)];
            } else {
                float lo, hi;
                parityRange(s, p, lo, hi);
                for (int c = 0; c < typeWidth(p.type); ++c) d[o + c] = rnd(lo, hi);
            }
        }
        // bsdf.ltc_normal_map: footprints spread over all its MIP regimes, not only the coarse levels the port
        // range gives on the 16² map (|duv| ~ 0.3: level ~2.3): scaled by 2^-(j mod 6), so the MIP-0 texels, the
        // MIP 0-1 blend and the stored levels' trilinear filter are all compared.
        // bsdf.glint: half the samples without flakes (the counted glints at their own log_density), the other half
        // with flakes of 0.002-0.01 and, in every other one of those, a footprint a tenth as large, so the grid holds the
        // explicit flakes, the hand-over and the counting at one microfacet per flake (flakeRegimes counts them).
        if (s.id == "bsdf.glint") {
            const int fs = L.inOffset[size_t(s.inputIndex("flake_size"))];
            if (j % 2 == 0) {
                d[fs] = 0.f;
            } else {
                d[fs] = rnd(0.002f, 0.01f);
                if (j % 4 == 1)
                    for (const char* name : {"duvdx", "duvdy"})
                        for (int c = 0; c < 2; ++c) d[L.inOffset[size_t(s.inputIndex(name))] + c] *= 0.1f;
            }
        }
        if (s.id == "bsdf.ltc_normal_map")
            for (const char* name : {"duvdx", "duvdy"})
                for (int c = 0; c < 2; ++c) d[L.inOffset[size_t(s.inputIndex(name))] + c] *= std::ldexp(1.f, -(j % 6));
        // Directions: mostly above the BSDF's normal (or the shading normal), some below.
        Vec3 ref = nrm >= 0 && L.inOffset[nrm] >= 0 ? Vec3(d[L.inOffset[nrm]], d[L.inOffset[nrm] + 1], d[L.inOffset[nrm] + 2]) : N;
        for (int o : {kGeom, kGeom + 3}) {
            Vec3 w = randUnit(rng);
            if (glm::dot(w, ref) < 0.f && u01(rng) < 0.85f) w = -w;
            put3(o, w);
        }
        for (int k = kGeom + 6; k < kGeom + 12; ++k) d[k] = rnd(-0.05f, 0.05f);  // dwo/dx, dwo/dy
        d[kGeom + 12] = j % 2 ? rnd(1.f, 5.f) : 0.f;                              // point light or direction
    }
    // GPU
    int texW = (L.floats + 3) / 4, outW = (L.outFloats + 3) / 4;
    std::vector<float> packed(size_t(texW) * 4 * kSamples, 0.f);
    for (int j = 0; j < kSamples; ++j)
        for (int i = 0; i < L.floats; ++i) packed[size_t(j) * texW * 4 + i] = data[j][i];
    std::string log;
    unsigned prog = glsltest::glProgram(parityShader(s, L), &log);
    if (!prog) {
        *failure = "GL compile/link failed: " + log;
        return res;
    }
    unsigned dataTex = glsltest::glDataTexture(texW, kSamples, packed);
    // The node's resources, produced from its prepared data exactly as the CPU program prepares it.
    GraphLoadContext load{s.resources.empty() ? nullptr : fixture().store.get(), fixture().dir};
    load.gpuSubstitutes = true;  // nodes the GPU cannot run are compared with the CPU twin of their GLSL substitute
    std::vector<glsltest::GlTexture> resourceTex;
    for (const graph::ResourceImage& img : codegen::nodeResourceImages(s, resourceStrings(s), std::vector<std::string>(s.inputs.size()), load))
        resourceTex.push_back(glsltest::glResourceTexture(img, s.resources[resourceTex.size()].glslType));
    // The closure sources' (bsdf.diffuse) built-in tables after them, as parityShader declares them.
    bool closureInputs = false;
    for (auto& p : s.inputs) closureInputs |= p.type == TypeDesc::Closure;
    if (closureInputs) {
        const NodeSpec* diffuse = NodeRegistry::instance().find("bsdf.diffuse");
        for (const graph::ResourceSpec& r : diffuse->resources) resourceTex.push_back(glsltest::glResourceTexture(r.produce(nullptr), r.glslType));
    }
    std::vector<float> gpu = glsltest::glRun(prog, outW, kSamples, [&] {
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, dataTex);
        for (size_t r = 0; r < resourceTex.size(); ++r) {
            glActiveTexture(GLenum(GL_TEXTURE1 + r));
            glBindTexture(resourceTex[r].target, resourceTex[r].name);
        }
    });
    glDeleteTextures(1, &dataTex);
    for (auto& t : resourceTex) glDeleteTextures(1, &t.name);
    glDeleteProgram(prog);

    // CPU
    ScratchArena arena;
    for (int j = 0; j < kSamples; ++j) {
        const float* d = data[j].data();
        auto v3 = [&](int o) { return Vec3(d[o], d[o + 1], d[o + 2]); };
        json nodes, inputs = json::object();
        for (size_t k = 0; k < s.inputs.size(); ++k) {
            const PortSpec& p = s.inputs[k];
            int o = L.inOffset[k];
            if (p.type == TypeDesc::String) {
                if (o >= 0) inputs[p.name] = p.enumValues[int(d[o])];
                else if (!resourceStrings(s)[k].empty()) inputs[p.name] = resourceStrings(s)[k];
                continue;
            }
            if (p.type == TypeDesc::Closure) {
                std::string id = "src" + std::to_string(k);
                nodes[id] = {{"type", "bsdf.diffuse"},
                             {"inputs", {{"color", {d[o], d[o + 1], d[o + 2]}}, {"normal", {d[3], d[4], d[5]}}, {"tangent", {d[9], d[10], d[11]}}}}};
                inputs[p.name] = "@" + id + ".bsdf";
                continue;
            }
            json arr = json::array();
            for (int c = 0; c < typeWidth(p.type); ++c) arr.push_back(d[o + c]);
            inputs[p.name] = typeWidth(p.type) == 1 ? arr[0] : arr;
        }
        nodes["n"] = {{"type", s.id}, {"inputs", inputs}};
        json m = {{"nodes", nodes}, {"output", "@n." + s.outputs[0].name}};
        GraphDesc g = parseGraph(m, "/parity", ParseOptions{false});
        std::vector<std::pair<int, int>> roots;
        for (size_t k = 0; k < s.outputs.size(); ++k) roots.push_back({g.findNode("n"), int(k)});
        Program prog = Program::compile(g, roots, &load);
        ShadingPoint sp;
        sp.p = v3(0), sp.n = v3(3), sp.ng = v3(6), sp.tangent = Vec4(v3(9), d[12]);
        sp.uv = Vec2(d[13], d[14]);
        sp.dpdx = v3(15), sp.dpdy = v3(18), sp.duvdx = Vec2(d[21], d[22]), sp.duvdy = Vec2(d[23], d[24]);
        sp.dndx = v3(25), sp.dndy = v3(28);
        sp.dwodx = v3(kGeom + 6), sp.dwody = v3(kGeom + 9);
        const float lightDistance = d[kGeom + 12] > 0.f ? d[kGeom + 12] : std::numeric_limits<float>::infinity();
        sp.hasDifferentials = true;
        sp.frame = Frame::fromNormal(sp.n);
        Vec3 wo = v3(kGeom), wi = v3(kGeom + 3);
        sp.wo = wo;
        Closure cl;
        Color3 em(0.f);
        const float* r = prog.run(sp, arena, s.outputs[0].type == TypeDesc::Closure ? &cl : nullptr, &em);
        std::vector<float> cpu;
        for (size_t k = 0; k < s.outputs.size(); ++k) {
            if (s.outputs[k].type == TypeDesc::Closure) {
                Color3 f = test::query(cl, wo, wi, lightDistance).f.total();
                cpu.insert(cpu.end(), {f.x, f.y, f.z, em.x, em.y, em.z});
                LobeParameters params;
                if (cl.size() == 1 && f.x + f.y + f.z > 0.f) cl.lobe(0)->parameters(LobeQuery{wo, wi}, params);
                for (const auto& [name, v] : params)
                    if (name == "flakes" && v.size() == 3) ++res.flakeRegimes[v[2] >= 1.0 ? 0 : v[2] > 0.0 ? 1 : 2];
            } else {
                for (int c = 0; c < typeWidth(s.outputs[k].type); ++c) cpu.push_back(r[prog.rootRegister(k) + c]);
            }
        }
        arena.reset();
        for (int i = 0; i < L.outFloats; ++i) {
            float gv = gpu[size_t(j) * outW * 4 + i], cv = cpu[i];
            float err = std::abs(gv - cv) / std::max(std::abs(cv), kRelFloor);
            if (!(err <= res.maxErr)) {  // also catches NaN
                res.maxErr = std::isnan(err) ? 1e30f : err;
                res.worstSample = j, res.worstFloat = i, res.worstCpu = cv, res.worstGpu = gv;
            }
        }
    }
    return res;
}

class GlslParity : public ::testing::TestWithParam<std::string> {
protected:
    void SetUp() override {
        std::string why;
        // No silent skip: a missing EGL/llvmpipe context is a failure (CI installs Mesa, platform.md §3).
        ASSERT_TRUE(glsltest::glContext(&why)) << "headless EGL context unavailable: " << why;
    }
};

TEST_P(GlslParity, NodeMatchesCpu) {
    const NodeSpec* s = NodeRegistry::instance().find(GetParam());
    ASSERT_NE(s, nullptr);
    std::string failure;
    ParityResult r = runParity(*s, &failure);
    ASSERT_TRUE(failure.empty()) << failure;
    std::printf("PARITY %-28s max_rel_err %.3g  tolerance %.3g\n", s->id.c_str(), r.maxErr, s->parityTolerance);
    if (s->id == "bsdf.glint") {
        std::printf("  flakes (f > 0): %d explicit, %d in the hand-over, %d counted at one microfacet per flake\n",
                    r.flakeRegimes[0], r.flakeRegimes[1], r.flakeRegimes[2]);
        for (int k = 0; k < 3; ++k) EXPECT_GE(r.flakeRegimes[k], 20) << "flake regime " << k << " hardly sampled";
    }
    EXPECT_LE(r.maxErr, s->parityTolerance) << "sample " << r.worstSample << " output float " << r.worstFloat << ": cpu "
                                            << r.worstCpu << " gpu " << r.worstGpu;
}

std::vector<std::string> allNodeIds() {
    // Registration happens in static initialisers of the node objects linked into this binary.
    return NodeRegistry::instance().ids();
}

INSTANTIATE_TEST_SUITE_P(AllNodes, GlslParity, ::testing::ValuesIn(allNodeIds()), [](const auto& info) {
    std::string n = info.param;
    for (char& c : n)
        if (!std::isalnum((unsigned char)c)) c = '_';
    return n;
});

}  // namespace

namespace {

// The main() of the emitted-module parity tests: 5 data texels per sample (P N T uv | wo wi) from the sampler at
// 'binding', shading inputs without derivatives, then 'body' writes spc_out.
std::string emittedMain(int binding, const std::string& body) {
    return "\nlayout(binding = " + std::to_string(binding) + R"() uniform sampler2D spc_data_;
layout(location = 0) out vec4 spc_out;
vec4 spc_px(int i) { return texelFetch(spc_data_, ivec2(i, int(gl_FragCoord.y)), 0); }
void main() {
    vec4 a = spc_px(0), b = spc_px(1), c = spc_px(2), d = spc_px(3), e = spc_px(4);
    SpeculaShadingInputs s;
    s.front_facing = true;
    s.position = a.xyz; s.normal = vec3(a.w, b.xy); s.tangent = vec4(b.zw, c.x, 1.0);
    s.geometric_normal = s.normal; s.uv = c.yz;
    s.dPdx = vec3(0.0); s.dPdy = vec3(0.0); s.duvdx = vec2(0.0); s.duvdy = vec2(0.0); s.dNdx = vec3(0.0); s.dNdy = vec3(0.0);
    s.dwodx = vec3(0.0); s.dwody = vec3(0.0);
    vec3 wo = d.xyz, wi = vec3(d.w, e.xy);
    )" + body + "\n}\n";
}

// The CPU shading point of one sample of the emitted-module tests (emittedMain's layout), without derivatives.
ShadingPoint emittedShadingPoint(const float* d) {
    ShadingPoint sp;
    sp.p = Vec3(d[0], d[1], d[2]);
    sp.n = sp.ng = Vec3(d[3], d[4], d[5]);
    sp.tangent = Vec4(d[6], d[7], d[8], 1.f);
    sp.uv = Vec2(d[9], d[10]);
    sp.wo = Vec3(d[12], d[13], d[14]);
    return sp;
}

// Emitted modules end to end: uniform block uploaded from GlslModule::uniforms (std140 offsets),
// geometric bindings, specula_eval/specula_emission vs GraphMaterial::shade + Closure::eval.
class GlslEmittedParity : public ::testing::TestWithParam<std::string> {
protected:
    void SetUp() override {
        std::string why;
        ASSERT_TRUE(glsltest::glContext(&why)) << "headless EGL context unavailable: " << why;
    }
};

TEST_P(GlslEmittedParity, MaterialMatchesCpu) {
    json scene;
    std::ifstream(std::string(SPECULA_SOURCE_DIR) + "/tests/glsl/data/materials.json") >> scene;
    const json& mj = scene["materials"][GetParam()];
    GraphDesc g = parseGraph(mj, "/materials/" + GetParam());
    codegen::GlslModule mod = codegen::emitGlsl(g);
    auto mat = loadGraphMaterial(mj, "/materials/" + GetParam(), GraphLoadContext{});

    std::mt19937 rng(99);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    const int F = 12;  // P3 N3 T3 uv2 pad | wo3 wi3 (3 texels)
    std::vector<float> data(size_t(kSamples) * F, 0.f);
    for (int j = 0; j < kSamples; ++j) {
        float* d = &data[size_t(j) * F];
        Vec3 N = randUnit(rng), T = randUnit(rng);
        Vec3 P(u01(rng), u01(rng), u01(rng));
        float v[] = {P.x, P.y, P.z, N.x, N.y, N.z, T.x, T.y, T.z, u01(rng), u01(rng), 0.f};
        std::copy(v, v + 12, d);
    }
    std::vector<float> dirs(size_t(kSamples) * 8, 0.f);
    for (int j = 0; j < kSamples; ++j) {
        Vec3 N(data[size_t(j) * F + 3], data[size_t(j) * F + 4], data[size_t(j) * F + 5]);
        Vec3 wo = randUnit(rng), wi = randUnit(rng);
        if (glm::dot(wo, N) < 0.f) wo = -wo;
        if (glm::dot(wi, N) < 0.f && u01(rng) < 0.9f) wi = -wi;
        float v[] = {wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, 0.f, 0.f};
        std::copy(v, v + 8, &dirs[size_t(j) * 8]);
    }
    std::vector<float> packed(size_t(kSamples) * 20, 0.f);
    for (int j = 0; j < kSamples; ++j) {
        std::copy(&data[size_t(j) * F], &data[size_t(j) * F] + 12, &packed[size_t(j) * 20]);
        std::copy(&dirs[size_t(j) * 8], &dirs[size_t(j) * 8] + 8, &packed[size_t(j) * 20 + 12]);
    }
    std::string fs = mod.source + emittedMain(0, "spc_out = int(gl_FragCoord.x) == 0 ? vec4(specula_eval(s, wo, wi), 0.0) : "
                                                  "vec4(specula_emission(s, wo), 0.0);");
    std::string log;
    unsigned prog = glsltest::glProgram(fs, &log);
    ASSERT_NE(prog, 0u) << log;
    unsigned tex = glsltest::glDataTexture(5, kSamples, packed);
    std::vector<char> ubo(std::max<uint32_t>(mod.uniformBlockSize, 16), 0);
    for (auto& u : mod.uniforms) std::memcpy(&ubo[u.offset], u.value.data(), 4 * typeWidth(u.type));
    GLuint buf;
    glGenBuffers(1, &buf);
    glBindBuffer(GL_UNIFORM_BUFFER, buf);
    glBufferData(GL_UNIFORM_BUFFER, GLsizeiptr(ubo.size()), ubo.data(), GL_STATIC_DRAW);
    std::vector<float> gpu = glsltest::glRun(prog, 2, kSamples, [&] {
        glBindBufferBase(GL_UNIFORM_BUFFER, 0, buf);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, tex);
    });
    glDeleteBuffers(1, &buf);
    glDeleteTextures(1, &tex);
    glDeleteProgram(prog);

    float maxErr = 0.f;
    ScratchArena arena;
    for (int j = 0; j < kSamples; ++j) {
        const float* d = &packed[size_t(j) * 20];
        ShadingPoint sp = emittedShadingPoint(d);
        const Vec3 wo = sp.wo, wi(d[15], d[16], d[17]);
        Closure cl;
        Color3 em(0.f);
        mat->shade(sp, arena, cl, &em);
        Color3 f = test::query(cl, wo, wi).f.total();
        arena.reset();
        for (int c = 0; c < 3; ++c) {
            float e1 = std::abs(gpu[size_t(j) * 8 + c] - f[c]) / std::max(std::abs(f[c]), kRelFloor);
            float e2 = std::abs(gpu[size_t(j) * 8 + 4 + c] - em[c]) / std::max(std::abs(em[c]), kRelFloor);
            maxErr = std::max({maxErr, e1, e2});
            if (!(e1 <= 2e-4f)) ADD_FAILURE() << "sample " << j << " ch " << c << " cpu " << f[c] << " gpu " << gpu[size_t(j) * 8 + c];
            if (j > 8 && HasFailure()) return;
        }
    }
    std::printf("PARITY material %-20s max_rel_err %.3g  tolerance 2e-4\n", GetParam().c_str(), maxErr);
    EXPECT_LE(maxErr, 2e-4f);
}

INSTANTIATE_TEST_SUITE_P(TestMaterials, GlslEmittedParity,
                         ::testing::Values("gold_mirror", "brushed_steel", "plastic", "bumpy_copper"));

// Two materials with resources in one shader, bound only from their manifests (codegen::glslManifest): a textured
// diffuse + glint closure and a LEAN-mapped glint, against GraphMaterial on the CPU. Names come from the manifest.
TEST(GlslManifestParity, TwoMaterialsWithResourcesInOneShader) {
    std::string why;
    ASSERT_TRUE(glsltest::glContext(&why)) << why;
    const std::string dir = fixture().dir;
    const json matA = json::parse(R"({"nodes": {
        "img": {"type": "texture.image", "inputs": {"file": "grid.exr", "colorspace": "raw"}},
        "d": {"type": "bsdf.diffuse", "inputs": {"color": "@img.color"}},
        "g": {"type": "bsdf.glint", "inputs": {"ggaa": "off", "log_density": 12, "weight": 0.5}},
        "sum": {"type": "closure.add", "inputs": {"a": "@d.bsdf", "b": "@g.bsdf"}}}, "output": "@sum.bsdf"})");
    const json matB = json::parse(R"({"nodes": {
        "lean": {"type": "texture.lean", "inputs": {"file": "grid.exr", "filter": "none"}},
        "g": {"type": "bsdf.glint", "inputs": {"ggaa": "off", "lean_cov": "@lean.covariance", "lean_mean": "@lean.slope",
                                               "log_density": 14}}}, "output": "@g.bsdf"})");
    GraphLoadContext load{fixture().store.get(), dir};
    std::vector<json> manifests;
    std::string shader;
    int base = 0;
    std::vector<GraphDesc> graphs;
    std::vector<std::shared_ptr<Material>> mats;
    std::vector<std::vector<ResourceImage>> images;
    for (auto [name, mj] : {std::pair<std::string, json>{"a", matA}, {"b", matB}}) {
        GraphDesc g = parseGraph(mj, "/materials/" + name);
        codegen::GlslOptions opt;
        opt.prefix = name;
        opt.bindingBase = base;
        codegen::GlslModule mod = codegen::emitGlsl(g, opt);
        images.push_back(codegen::exportGlslResources(g, mod, load));
        manifests.push_back(codegen::glslManifest(mod, images.back(), {}));
        base += 1 + int(mod.resources.size());
        std::string src = mod.source;
        if (!shader.empty()) src = src.substr(src.find('\n') + 1);  // one #version per shader
        shader += src;
        mats.push_back(loadGraphMaterial(mj, "/materials/" + name, load));
    }
    ASSERT_EQ(manifests[0]["resources"].size(), 3u);  // the image, the diffuse's LTC amplitude table, the glint dictionary
    ASSERT_EQ(manifests[1]["resources"].size(), 2u);  // the LEAN moments and the dictionary
    shader += emittedMain(15, "spc_out = int(gl_FragCoord.x) == 0 ? vec4(specula_a_eval(s, wo, wi), 0.0) : "
                              "vec4(specula_b_eval(s, wo, wi), 0.0);");
    std::string log;
    unsigned prog = glsltest::glProgram(shader, &log);
    ASSERT_NE(prog, 0u) << log;

    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<float> packed(size_t(kSamples) * 20, 0.f);
    for (int j = 0; j < kSamples; ++j) {
        float* d = &packed[size_t(j) * 20];
        Vec3 N = glm::normalize(Vec3(0.2f * (u01(rng) - 0.5f), 0.2f * (u01(rng) - 0.5f), 1.f));
        Vec3 T = glm::normalize(glm::cross(Vec3(0, 1, 0), N));
        Vec3 wo = randUnit(rng), wi = randUnit(rng);
        if (glm::dot(wo, N) < 0.f) wo = -wo;
        if (glm::dot(wi, N) < 0.f) wi = -wi;
        float v[] = {u01(rng), u01(rng), u01(rng), N.x, N.y, N.z, T.x, T.y, T.z, u01(rng), u01(rng), 0.f,
                     wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, 0.f, 0.f};
        std::copy(v, v + 20, d);
    }
    unsigned dataTex = glsltest::glDataTexture(5, kSamples, packed);
    // Everything below is bound from the manifests alone: uniform blocks and resources at their listed bindings.
    std::vector<float> gpu;
    {
        glsltest::ManifestBindings host;
        for (size_t m = 0; m < manifests.size(); ++m) host.add(manifests[m], images[m]);
        gpu = glsltest::glRun(prog, 2, kSamples, [&] {
            host.bind();
            glActiveTexture(GL_TEXTURE15);
            glBindTexture(GL_TEXTURE_2D, dataTex);
        });
    }
    glDeleteTextures(1, &dataTex);
    glDeleteProgram(prog);

    float maxErr = 0.f;
    int nonZero = 0;
    ScratchArena arena;
    for (int j = 0; j < kSamples; ++j) {
        const float* d = &packed[size_t(j) * 20];
        ShadingPoint sp = emittedShadingPoint(d);
        const Vec3 wo = sp.wo, wi(d[15], d[16], d[17]);
        for (size_t m = 0; m < mats.size(); ++m) {
            Closure cl;
            mats[m]->shade(sp, arena, cl);
            Color3 f = test::query(cl, wo, wi).f.total();
            arena.reset();
            for (int c = 0; c < 3; ++c) {
                float g = gpu[(size_t(j) * 2 + m) * 4 + size_t(c)];
                float err = std::abs(g - f[c]) / std::max(std::abs(f[c]), kRelFloor);
                maxErr = std::max(maxErr, err);
                nonZero += f[c] > 1e-4f;
            }
        }
    }
    std::printf("PARITY two materials via manifests  max_rel_err %.3g  (non-zero channels %d)\n", maxErr, nonZero);
    EXPECT_GT(nonZero, kSamples);  // the comparison is not of zeros
    EXPECT_LE(maxErr, 2e-4f);
}

// bsdf.ltc_normal_map in an emitted module bound from its manifest alone: non-default uniform literals (roughness,
// strength, convention) reach both the uniform block and the prepared tables (PrepareContext::number), the tables are a
// layered 2D array (ResourceImage::Level::layers), and a footprint of ~1.5 texels blends the MIP-0 texels with level 1.
TEST(GlslManifestParity, LtcNormalMapModuleBoundFromItsManifest) {
    std::string why;
    ASSERT_TRUE(glsltest::glContext(&why)) << why;
    const json mj = json::parse(R"({"nodes": {"n": {"type": "bsdf.ltc_normal_map", "inputs": {
        "normal_map": "generate:flakes:16:3", "convention": "directx", "roughness": 0.45, "strength": 0.8,
        "specular_color": [0.9, 0.7, 0.5], "diffuse_color": [0.2, 0.4, 0.3],
        "duvdx": [0.09, 0.02], "duvdy": [-0.01, 0.06]}}}, "output": "@n.bsdf"})");
    GraphLoadContext load{nullptr, ""};
    GraphDesc g = parseGraph(mj, "/materials/nm");
    codegen::GlslModule mod = codegen::emitGlsl(g);
    const std::vector<ResourceImage> images = codegen::exportGlslResources(g, mod, load);
    const json manifest = codegen::glslManifest(mod, images, {});
    ASSERT_EQ(manifest["resources"].size(), 4u);
    ASSERT_EQ(manifest["resources"][0]["glsl_type"], "sampler2DArray");
    auto mat = loadGraphMaterial(mj, "/materials/nm", load);
    std::string log;
    unsigned prog = glsltest::glProgram(mod.source + emittedMain(15, "spc_out = vec4(specula_eval(s, wo, wi), 0.0);"), &log);
    ASSERT_NE(prog, 0u) << log;

    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<float> packed(size_t(kSamples) * 20, 0.f);
    for (int j = 0; j < kSamples; ++j) {
        Vec3 N = glm::normalize(Vec3(0.3f * (u01(rng) - 0.5f), 0.3f * (u01(rng) - 0.5f), 1.f));
        Vec3 T = glm::normalize(glm::cross(Vec3(0, 1, 0), N));
        Vec3 wo = randUnit(rng), wi = randUnit(rng);
        if (glm::dot(wo, N) < 0.f) wo = -wo;
        if (glm::dot(wi, N) < 0.f) wi = -wi;
        float v[] = {0.f, 0.f, 0.f, N.x, N.y, N.z, T.x, T.y, T.z, 2.f * u01(rng) - 0.5f, 2.f * u01(rng) - 0.5f, 0.f,
                     wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, 0.f, 0.f};
        std::copy(v, v + 20, &packed[size_t(j) * 20]);
    }
    unsigned dataTex = glsltest::glDataTexture(5, kSamples, packed);
    std::vector<float> gpu;
    {
        glsltest::ManifestBindings host;
        host.add(manifest, images);
        gpu = glsltest::glRun(prog, 1, kSamples, [&] {
            host.bind();
            glActiveTexture(GL_TEXTURE15);
            glBindTexture(GL_TEXTURE_2D, dataTex);
        });
    }
    glDeleteTextures(1, &dataTex);
    glDeleteProgram(prog);

    float maxErr = 0.f;
    int nonZero = 0;
    ScratchArena arena;
    for (int j = 0; j < kSamples; ++j) {
        const float* d = &packed[size_t(j) * 20];
        ShadingPoint sp = emittedShadingPoint(d);
        const Vec3 wi(d[15], d[16], d[17]);
        Closure cl;
        mat->shade(sp, arena, cl);
        Color3 f = test::query(cl, sp.wo, wi).f.total();
        arena.reset();
        for (int c = 0; c < 3; ++c) {
            float err = std::abs(gpu[size_t(j) * 4 + size_t(c)] - f[c]) / std::max(std::abs(f[c]), kRelFloor);
            maxErr = std::max(maxErr, std::isnan(err) ? 1e30f : err);
            nonZero += f[c] > 1e-4f;
        }
    }
    std::printf("PARITY ltc_normal_map module via manifest  max_rel_err %.3g  (non-zero channels %d)\n", maxErr, nonZero);
    EXPECT_GT(nonZero, kSamples);
    EXPECT_LE(maxErr, NodeRegistry::instance().find("bsdf.ltc_normal_map")->parityTolerance);
}

// specula_shading_inputs() derives the screen-space derivatives with dFdx/dFdy: for attributes
// linear in the pixel position they equal the per-pixel step exactly.
TEST(GlslDerivatives, ShadingInputsFromFragmentUseScreenDerivatives) {
    std::string why;
    ASSERT_TRUE(glsltest::glContext(&why)) << why;
    const NodeSpec* uv = NodeRegistry::instance().find("geometry.uv");
    const NodeSpec* pos = NodeRegistry::instance().find("geometry.position");
    std::string fs = "#version 450\n" + codegen::glslPrelude() + *uv->glslSource() + *pos->glslSource() + R"(
layout(location = 0) out vec4 spc_out;
void main() {
    vec2 uv0 = gl_FragCoord.xy * vec2(0.125, 0.0625);
    vec3 P = vec3(gl_FragCoord.x * 0.5, gl_FragCoord.y * 0.25, 1.0);
    SpeculaShadingInputs s = specula_shading_inputs(P, vec3(0, 0, 1), vec3(0, 0, 1), vec4(1, 0, 0, 1), uv0);
    vec2 uv, dx, dy, pdx, pdy; vec3 p, dpx, dpy;
    spc_geometry_uv(s, uv, dx, dy, pdx, pdy);
    spc_geometry_position(s, p, dpx, dpy);
    spc_out = vec4(dx.x, dy.y, dpx.x, dpy.y);
}
)";
    std::string log;
    unsigned prog = glsltest::glProgram(fs, &log);
    ASSERT_NE(prog, 0u) << log;
    std::vector<float> px = glsltest::glRun(prog, 8, 8);
    for (int i = 0; i < 64; ++i) {
        EXPECT_FLOAT_EQ(px[i * 4 + 0], 0.125f);
        EXPECT_FLOAT_EQ(px[i * 4 + 1], 0.0625f);
        EXPECT_FLOAT_EQ(px[i * 4 + 2], 0.5f);
        EXPECT_FLOAT_EQ(px[i * 4 + 3], 0.25f);
    }
    glDeleteProgram(prog);
}

}  // namespace
