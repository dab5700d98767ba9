// Parity of the shared GLSL formulas with their one CPU home, function by function, on Mesa llvmpipe (headless EGL):
// nodes/shared/ggx_microfacet.glsl (α from roughness, GGX D, Λ in its diagonal and matrix forms, G2) and
// nodes/shared/fresnel_f0.glsl (the Fresnel model switch) over grids of inputs. The node parity tests
// (test_glsl_parity.cpp) compare whole nodes; these pin each shared formula, so a drift shows where it is.
//
// Error measure: |gpu − cpu| / max(|cpu|, floor) per component, floor = kFloor = 1e-3 (the node parity test's) for α, D,
// G2 and F, and kLambdaFloor = 1 for Λ: Λ enters the BSDF only as 1 + Λ (G1, G2), and for small Λ the formula's own
// cancellation sqrt(1 + α²tan²θ) − 1 leaves an absolute error of a float ulp of 1 (6e-8) on either side. Limit: 1e-5
// for every comparison, float against float with the same operation order (α, Λ, D, G2, Fresnel) and float against the
// double CPU matrix form (fggx::lambda, fggx::g2); measured maxima on llvmpipe (Mesa 22.3) are below 1e-6.
#define GL_GLEXT_PROTOTYPES 1
#include "core/codegen/glsl_signature.h"
#include "core/codegen/glsl_sources.h"
#include "core/graph/node_spec.h"
#include "core/render/lobes/ggx.h"
#include "glsl_harness.h"
#include "nodes/bsdf/ggx_filtered/filtered_ggx.h"
#include "nodes/shared/bsdf_ports.h"

#include <GL/gl.h>
#include <GL/glext.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

using namespace specula;

namespace {

constexpr double kFloor = 1e-3;
constexpr double kLambdaFloor = 1.0;
constexpr double kTolerance = 1e-5;

using Sample = std::array<float, 16>;  // the inputs of one evaluation: spc_in(0..15) in the shader
using Result = std::array<float, 4>;   // its output vec4

// Runs 'body' (GLSL statements that read spc_in(i) and assign the vec4 spc_out) once per sample, one sample per row,
// after the prelude, the Fresnel enum constants and the two shared libraries. Empty on a failed compile (logged).
std::vector<Result> runGpu(const std::string& body, const std::vector<Sample>& samples) {
    const graph::NodeSpec* ggx = graph::NodeRegistry::instance().find("bsdf.ggx");  // declares the fresnel port
    std::string src = "#version 450\n" + codegen::glslPrelude() + codegen::glslEnumConstants(*ggx) +
                      codegen::glslNodeLibraries({"shared/ggx_microfacet.glsl", "shared/fresnel_f0.glsl"}) +
                      R"(
layout(binding = 0) uniform sampler2D spc_data;
layout(location = 0) out vec4 spc_out;
float spc_in(int i) { return texelFetch(spc_data, ivec2(i >> 2, int(gl_FragCoord.y)), 0)[i & 3]; }
vec3 spc_in3(int i) { return vec3(spc_in(i), spc_in(i + 1), spc_in(i + 2)); }
void main() {
    spc_out = vec4(0.0);
)" + body + "\n}\n";
    std::string log;
    unsigned prog = glsltest::glProgram(src, &log);
    if (!prog) {
        ADD_FAILURE() << "GL compile/link failed: " << log;
        return {};
    }
    const int n = int(samples.size());
    std::vector<float> packed;
    for (const Sample& s : samples) packed.insert(packed.end(), s.begin(), s.end());
    unsigned tex = glsltest::glDataTexture(4, n, packed);
    std::vector<float> px = glsltest::glRun(prog, 1, n, [&] {
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, tex);
    });
    glDeleteTextures(1, &tex);
    glDeleteProgram(prog);
    std::vector<Result> out(static_cast<size_t>(n));
    for (int j = 0; j < n; ++j) std::copy(px.begin() + 4 * j, px.begin() + 4 * j + 4, out[size_t(j)].begin());
    return out;
}

// The largest error of output component c against the CPU answers; prints it with the worst sample.
double maxError(const std::vector<Result>& gpu, const std::vector<std::array<double, 4>>& cpu, int c, double floor,
                const std::vector<Sample>& samples, const char* what) {
    double worst = 0;
    size_t at = 0;
    for (size_t j = 0; j < gpu.size(); ++j) {
        double ref = cpu[j][size_t(c)];
        double e = std::abs(double(gpu[j][size_t(c)]) - ref) / std::max(std::abs(ref), floor);
        if (!(e <= worst)) worst = e, at = j;  // also catches NaN
    }
    if (!gpu.empty()) {
        const Sample& s = samples[at];
        std::printf("%s: max relative error %.3g over %zu samples (worst: inputs %g %g %g %g %g %g %g, gpu %.9g cpu %.9g)\n",
                    what, worst, gpu.size(), s[0], s[1], s[2], s[3], s[4], s[5], s[6], double(gpu[at][size_t(c)]),
                    cpu[at][size_t(c)]);
    }
    return worst;
}

bool gl() {
    std::string why;
    if (!glsltest::glContext(&why)) {
        ADD_FAILURE() << "no GL context: " << why;
        return false;
    }
    return true;
}

// Unit directions over a (θ, φ) grid, θ up to just short of grazing, some of the lower hemisphere's mirror images, and
// the horizon itself (Λ = "fully masked": 1e30 in float, 1e300 in double).
std::vector<Vec3> directionGrid() {
    std::vector<Vec3> w{Vec3(1.f, 0.f, 0.f), Vec3(0.6f, -0.8f, 0.f)};
    for (int i = 0; i <= 16; ++i)
        for (int k = 0; k < 8; ++k) {
            float theta = 1.5707f * float(i) / 16.f, phi = 6.2831853f * (float(k) + 0.25f) / 8.f;
            Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
            w.push_back(d);
            if (i % 4 == 1) w.push_back(Vec3(d.x, d.y, -d.z));
        }
    return w;
}
const float kAlphas[] = {1e-4f, 1e-2f, 0.1f, 0.3f, 0.6f, 1.f};

TEST(GlslFormulas, AlphaFromRoughnessMatchesBsdfPorts) {
    if (!gl()) return;
    std::vector<Sample> in;
    std::vector<std::array<double, 4>> cpu;
    for (int i = 0; i <= 32; ++i)
        for (int k = 0; k <= 32; ++k) {
            float r = float(i) / 32.f, a = float(k) / 32.f;  // the ports' ranges (roughness, anisotropy ∈ [0, 1])
            in.push_back({r, a});
            Vec2 cpuAlpha = nodes::alphaFromRoughness(r, a);
            cpu.push_back({cpuAlpha.x, cpuAlpha.y, 0, 0});
        }
    auto gpu = runGpu("spc_out.xy = spc_alpha_from_roughness(spc_in(0), spc_in(1));", in);
    EXPECT_LE(maxError(gpu, cpu, 0, kFloor, in, "alphaFromRoughness x"), kTolerance);
    EXPECT_LE(maxError(gpu, cpu, 1, kFloor, in, "alphaFromRoughness y"), kTolerance);
}

TEST(GlslFormulas, LambdaOfTan2MatchesGgx) {
    if (!gl()) return;
    std::vector<Sample> in;
    std::vector<std::array<double, 4>> cpu;
    in.push_back({0.f});
    cpu.push_back({ggx::lambdaOfTan2(0.f), 0, 0, 0});
    // Heitz 2014, Eq. 86 itself, in double: Λ(0) = 0 and Λ(3) = 1/2.
    EXPECT_EQ(ggx::lambdaOfTan2(0.0), 0.0);
    EXPECT_EQ(ggx::lambdaOfTan2(3.0), 0.5);
    for (int e = -80; e <= 80; ++e) {  // α²tan²θ from 1e-8 to 1e8
        float x = std::pow(10.f, float(e) / 10.f);
        in.push_back({x});
        cpu.push_back({ggx::lambdaOfTan2(x), 0, 0, 0});
    }
    auto gpu = runGpu("spc_out.x = spc_ggx_lambda_of_tan2(spc_in(0));", in);
    EXPECT_LE(maxError(gpu, cpu, 0, kLambdaFloor, in, "lambdaOfTan2"), kTolerance);
}

// The diagonal forms: Λ(w), D(h) and G2(wo, wi) of ggx:: against spc_ggx_lambda / spc_ggx_ndf / spc_ggx_g2, and the
// matrix Λ at A = diag(αx², αy²) against the same ggx::lambda (the special case the header comments name).
TEST(GlslFormulas, GgxDiagonalFormsMatchGgx) {
    if (!gl()) return;
    std::vector<Vec3> dirs = directionGrid();
    std::vector<Sample> in;
    std::vector<std::array<double, 4>> cpu;
    size_t n = 0;
    for (float ax : kAlphas)
        for (float ay : kAlphas)
            for (size_t d = 0; d < dirs.size(); ++d) {
                Vec3 w = dirs[d], wi = dirs[(d * 7 + 3) % dirs.size()];
                Vec3 h = glm::normalize(Vec3(w.x + wi.x, w.y + wi.y, std::abs(w.z) + std::abs(wi.z) + 1e-3f));
                in.push_back({w.x, w.y, w.z, wi.x, wi.y, wi.z, h.x, h.y, h.z, ax, ay});
                cpu.push_back({ggx::lambda(w, ax, ay), ggx::ndf(h, ax, ay), ggx::g2(w, wi, ax, ay), ggx::lambda(w, ax, ay)});
                ++n;
            }
    auto gpu = runGpu(R"(
    vec3 w = spc_in3(0), wi = spc_in3(3), h = spc_in3(6);
    float ax = spc_in(9), ay = spc_in(10);
    spc_out = vec4(spc_ggx_lambda(w, ax, ay), spc_ggx_ndf(h, ax, ay), spc_ggx_g2(w, wi, ax, ay),
                   spc_ggx_lambda_matrix(w, vec3(ax * ax, 0.0, ay * ay)));)",
                      in);
    ASSERT_EQ(gpu.size(), n);
    EXPECT_LE(maxError(gpu, cpu, 0, kLambdaFloor, in, "ggx lambda"), kTolerance);
    EXPECT_LE(maxError(gpu, cpu, 1, kFloor, in, "ggx ndf"), kTolerance);
    EXPECT_LE(maxError(gpu, cpu, 2, kFloor, in, "ggx g2"), kTolerance);
    // The matrix form sums αx² wx² + αy² wy² where the diagonal one sums (αx wx)² + (αy wy)²: same value, other rounding.
    EXPECT_LE(maxError(gpu, cpu, 3, kLambdaFloor, in, "matrix lambda at diag(ax^2, ay^2)"), kTolerance);
}

// The matrix form (TK21 A.3): spc_ggx_lambda_matrix / spc_ggx_g2_matrix in float against fggx::lambda / fggx::g2 in
// double, over random positive semi-definite roughness matrices (αs 1e-3..1, correlation −0.99..0.99).
TEST(GlslFormulas, GgxMatrixFormsMatchFilteredGgx) {
    if (!gl()) return;
    std::vector<Vec3> dirs = directionGrid();
    std::mt19937 rng(36u);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<Sample> in;
    std::vector<std::array<double, 4>> cpu;
    for (int m = 0; m < 24; ++m) {
        float sx = std::pow(10.f, -3.f * u01(rng)), sy = std::pow(10.f, -3.f * u01(rng)), rho = 1.98f * u01(rng) - 0.99f;
        float a = sx * sx, d = sy * sy, c = rho * sx * sy;
        fggx::Sym2 A{a, c, d};
        for (size_t k = 0; k < dirs.size(); ++k) {
            Vec3 w = dirs[k], wi = dirs[(k * 5 + 1) % dirs.size()];
            in.push_back({w.x, w.y, w.z, wi.x, wi.y, wi.z, a, c, d});
            cpu.push_back({fggx::lambda(fggx::D3(w), A), fggx::g2(fggx::D3(w), fggx::D3(wi), A), 0, 0});
        }
    }
    for (auto& c : cpu)
        if (c[0] == 1e300) c[0] = 1e30;  // the same "fully masked" answer at the horizon
    auto gpu = runGpu(R"(
    vec3 w = spc_in3(0), wi = spc_in3(3), A = spc_in3(6);
    spc_out.xy = vec2(spc_ggx_lambda_matrix(w, A), spc_ggx_g2_matrix(w, wi, A));)",
                      in);
    EXPECT_LE(maxError(gpu, cpu, 0, kLambdaFloor, in, "fggx lambda"), kTolerance);
    EXPECT_LE(maxError(gpu, cpu, 1, kFloor, in, "fggx g2"), kTolerance);
}

// The Fresnel switch: spc_fresnel_eval(model, cos, ...) against fresnelOf(ports).eval(cos) for all four models, cos
// over [−1, 1] (the dielectric's other side and total internal reflection included), parameters over the ports' ranges;
// spc_fresnel_f0 against eval(1).
TEST(GlslFormulas, FresnelSwitchMatchesFresnelOf) {
    if (!gl()) return;
    struct Ports {
        nodes::FresnelModel fresnel;
        Color3 f0;
        float ior;
        Color3 eta, k;
    };
    std::mt19937 rng(3636u);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<Sample> in;
    std::vector<std::array<double, 4>> cpu;
    for (int model = 0; model < 4; ++model)
        for (int p = 0; p < 16; ++p) {
            Ports ports{nodes::FresnelModel(model), Color3(u01(rng), u01(rng), u01(rng)), 1.f + 2.f * u01(rng),
                        Color3(0.1f + 2.9f * u01(rng), 0.1f + 2.9f * u01(rng), 0.1f + 2.9f * u01(rng)),
                        Color3(10.f * u01(rng), 10.f * u01(rng), 10.f * u01(rng))};
            Fresnel F = nodes::fresnelOf(ports);
            for (int i = -32; i <= 33; ++i) {
                bool f0 = i == 33;  // the last sample of each set asks spc_fresnel_f0
                float c = f0 ? 1.f : float(i) / 32.f;
                in.push_back({float(model), c, f0 ? 1.f : 0.f, ports.ior, ports.f0.x, ports.f0.y, ports.f0.z, ports.eta.x,
                              ports.eta.y, ports.eta.z, ports.k.x, ports.k.y, ports.k.z});
                Color3 v = F.eval(c);
                cpu.push_back({v.x, v.y, v.z, 0});
            }
        }
    auto gpu = runGpu(R"(
    int model = int(spc_in(0));
    float c = spc_in(1), ior = spc_in(3);
    vec3 f0 = spc_in3(4), eta = spc_in3(7), k = spc_in3(10);
    spc_out.xyz = spc_in(2) > 0.5 ? spc_fresnel_f0(model, f0, ior, eta, k) : spc_fresnel_eval(model, c, f0, ior, eta, k);)",
                      in);
    const char* channel[] = {"fresnel switch r", "fresnel switch g", "fresnel switch b"};
    for (int c = 0; c < 3; ++c) EXPECT_LE(maxError(gpu, cpu, c, kFloor, in, channel[c]), kTolerance);
}

}  // namespace
