// ltc-report: the quad-light accuracy tables of docs/validation/ltc.md (LTC integral vs MIS Monte Carlo by view band
// and roughness, exact clipping and clip-free, for each lobe that integrates polygons), as Markdown on stdout.
#include "core/ltc/ltc_ggx.h"
#include "core/ltc/ltc_reference.h"
#include "core/render/lobes/ggx.h"
#include "core/render/lobes/lambert.h"
#include "nodes/bsdf/beckmann_lean/beckmann_lean.h"
#include "nodes/bsdf/ggx_filtered/filtered_ggx.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

using namespace specula;
using ltc::LobeUnderTest;

namespace {

void row(const std::string& lobe, const std::string& rough, const char* horizon, const ltc::BandErrors& e) {
    std::printf("| %s | %s | %s | %.4f | %.4f | %.4f | %.3f | %.3f | %.3f |\n", lobe.c_str(), rough.c_str(), horizon,
                e.meanAbs(0), e.meanAbs(1), e.meanAbs(2), e.medianRelative(0), e.medianRelative(1), e.medianRelative(2));
}

}  // namespace

int main(int argc, char** argv) {
    const int perBand = argc > 1 ? std::atoi(argv[1]) : 24;
    const int mc = argc > 2 ? std::atoi(argv[2]) : 100000;
    const auto& t = ltc::builtinTables();
    auto start = std::chrono::steady_clock::now();
    std::printf("Quads fully above the horizon, %d per view band, each against a %d+%d-sample MIS Monte Carlo of the "
                "lobe; error / albedo (mean) and relative error (median over quads capturing >= 10%% of the albedo).\n\n",
                perBand, mc, mc);
    std::printf("| lobe | roughness | horizon | mean \\|err\\|/albedo θ<30° | 30-60° | 60-88° | median rel θ<30° | 30-60° | 60-88° |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    for (uint8_t horizon : {uint8_t(0), uint8_t(1)}) {
        const char* hz = horizon ? "clipless" : "clip";
        for (float r : {0.1f, 0.25f, 0.5f, 0.75f, 1.0f}) {
            auto e = ltc::measureQuadErrors(
                [&](uint64_t&, const Vec3& wo) {
                    float a = r * r;
                    LobeUnderTest c{std::make_unique<GgxLobe>(a, a, Fresnel::one())};
                    c.albedo = ltc::ggxIsotropic(t, a, wo).magnitude;
                    return c;
                },
                perBand, mc, 11 + uint64_t(r * 100), horizon);
            char buf[32];
            std::snprintf(buf, sizeof buf, "%.2f", r);
            row("bsdf.ggx", buf, hz, e);
        }
        auto an = ltc::measureQuadErrors(
            [&](uint64_t& s, const Vec3& wo) {
                float ax = float(std::pow(0.3 + 0.7 * ltc::nextUniform(s), 2.0)), ay = float(std::pow(0.3 + 0.7 * ltc::nextUniform(s), 2.0));
                LobeUnderTest c{std::make_unique<GgxLobe>(ax, ay, Fresnel::one())};
                c.albedo = ltc::ggxRoughnessMatrix(t, ax * ax, 0, ay * ay, wo).magnitude;
                return c;
            },
            perBand, mc, 21, horizon);
        row("bsdf.ggx anisotropic", "0.3-1 per axis", hz, an);
        auto fg = ltc::measureQuadErrors(
            [&](uint64_t& s, const Vec3& wo) {
                double ax = std::pow(0.3 + 0.7 * ltc::nextUniform(s), 2.0), ay = std::pow(0.3 + 0.7 * ltc::nextUniform(s), 2.0);
                double phi = M_PI * ltc::nextUniform(s), cs = std::cos(phi), sn = std::sin(phi);
                fggx::LobeSetup setup;
                setup.A = {cs * cs * ax * ax + sn * sn * ay * ay, cs * sn * (ax * ax - ay * ay), sn * sn * ax * ax + cs * cs * ay * ay};
                setup.params.filter = fggx::Filter::None;
                LobeUnderTest c{std::make_unique<fggx::FilteredGgxLobe>(setup, Fresnel::one())};
                c.albedo = ltc::ggxRoughnessMatrix(t, setup.A.a, setup.A.c, setup.A.d, wo).magnitude;
                return c;
            },
            perBand, mc, 31, horizon);
        row("bsdf.ggx_filtered (rotated matrix)", "0.3-1 per axis", hz, fg);
        auto bl = ltc::measureQuadErrors(
            [&](uint64_t& s, const Vec3& wo) {
                Vec2 mean(float(0.3 * (ltc::nextUniform(s) - 0.5)), float(0.3 * (ltc::nextUniform(s) - 0.5)));
                Vec3 cov(float(0.02 * ltc::nextUniform(s)), float(0.02 * ltc::nextUniform(s)), 0.f);
                float alpha = float(0.2 + 0.6 * ltc::nextUniform(s));
                auto lobe = std::make_unique<BeckmannLeanLobe>(lean::makeSlopeGaussian(mean, cov, alpha), Fresnel::one());
                double albedo = lobe->polygonLtc(wo).magnitude;
                return LobeUnderTest{std::move(lobe), albedo};
            },
            perBand, mc, 41, horizon);
        row("bsdf.beckmann_lean (equivalent GGX)", "α 0.2-0.8", hz, bl);
        auto df = ltc::measureQuadErrors(
            [&](uint64_t&, const Vec3&) { return LobeUnderTest{std::make_unique<LambertLobe>(Color3(1.f)), 1.0}; },
            perBand, mc, 51, horizon);
        row("bsdf.diffuse", "-", hz, df);
    }
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("\n(%.1f s)\n", secs);
    return 0;
}
