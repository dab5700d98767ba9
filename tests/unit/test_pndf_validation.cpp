// P-NDF validation in CI (docs/validation/pndf.md, shared/specs/validation.md; issue 12 item 7): a normal-mapped
// mirror-like aluminium plate under a small quad light (sampled), specular AOV against a high-spp reference of
// plain normal mapping (texture.image -> texture.normal_map -> bsdf.ggx roughness 0.03). Asserts the measured
// error ratio P-NDF / normal mapping at 64 spp (W24 Fig. 18), and that P-NDF's 64-spp error is close to its own
// error at 4x the samples (its bias floor: the kernel convolved with the pixel filter).
//
// Scene parameters are those of tools/validate_pndf.py (keep in sync: camera, light, plate, Fresnel, roughness,
// map seed, seeds of reference and tests); this test is smaller: 64 x 48, 256² maps tiled twice (the page's texel
// density), 1024-spp reference, maps bumps and brushed.
#include "core/api/specula.h"
#include "render_support.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

using namespace specula;
using test::compareRmse;
using test::specularAov;

namespace {

constexpr int kW = 64, kH = 48;
constexpr int kMapSize = 256;  // the page: 1024
constexpr int kMapSeed = 3;
constexpr int kTiles = 2;      // 256² tiled twice: the page's texel density (1024² once over the plate at 112 x 84)
constexpr int kRefSpp = 1024;  // the page: 4096
constexpr int kSpp = 64;
constexpr int kHiSpp = 256;    // P-NDF at 4x the samples: close to its bias floor
constexpr int kRefSeed = 1, kTestSeed = 2;
// MEASURED (this renderer, 2026-12-02): RMSE ratio P-NDF / normal mapping at 64 spp 0.692 (bumps), 0.573 (brushed);
// bumps P-NDF 64 spp / 256 spp 1.039. Asserted with margins: <= 0.85, <= 0.75, <= 1.2. (Without the 2x tiling,
// 256² once over the plate = 4 texels per pixel, bumps measured 1.29: the claim needs several texels per pixel.)
constexpr double kMaxRatioBumps = 0.85;
constexpr double kMaxRatioBrushed = 0.75;
constexpr double kMaxToFloor = 1.2;
// Kernel centred on the pixel, box, k = 1 (footprint_centre "pixel"): measured ratio vs normal mapping 0.540 (bumps),
// 0.540 (brushed), and 0.780 / 0.943 of the default's error: the kernel is no longer convolved with the pixel filter.
constexpr double kMaxRatioPixelCentred = 0.65;
constexpr double kMaxPixelCentredVsDefaultBumps = 0.9;
constexpr const char* kAluminium = R"("fresnel": "conductor", "eta": [1.66, 0.88, 0.52], "k": [9.22, 6.27, 4.84])";

// pixelCentred: the P-NDF kernel centred on the pixel (footprint_centre "pixel"), box, k = 1: the box-filtered
// surface the reference converges to, instead of the default (k 2 Gaussian on each sample, convolved with the filter).
std::string material(bool pndf, const std::string& kind, bool pixelCentred = false) {
    const std::string gen = "generate:" + kind + ":" + std::to_string(kMapSize) + ":" + std::to_string(kMapSeed);
    std::ostringstream m;
    if (pndf) {
        m << R"({"nodes": {"g": {"type": "bsdf.glint_pndf", "inputs": {"normal_map": ")" << gen
          << R"(", "uv_scale": )" << kTiles
          << (pixelCentred ? R"(, "footprint_scale": 1, "kernel": "box", "footprint_centre": "pixel", )"
                           : R"(, "footprint_scale": 2, "kernel": "gaussian", )")
          << kAluminium << R"(}}}, "output": "@g.bsdf"})";
    } else {  // plain normal mapping of the full-resolution map (zero footprint: bilinear on MIP level 0)
        m << R"({"nodes": {"uvs": {"type": "geometry.uv"},
          "uv": {"type": "math.mul.vec2", "inputs": {"a": "@uvs.uv", "b": [)" << kTiles << "," << kTiles << R"(]}},
          "img": {"type": "texture.image", "inputs": {"file": ")" << gen
          << R"(", "colorspace": "raw", "uv": "@uv.out", "duvdx": [0, 0], "duvdy": [0, 0]}},
          "nm": {"type": "texture.normal_map", "inputs": {"color": "@img.color"}},
          "spec": {"type": "bsdf.ggx", "inputs": {"roughness": 0.03, "normal": "@nm.normal", )" << kAluminium
          << R"(}}}, "output": "@spec.bsdf"})";
    }
    return m.str();
}

std::string scene(bool pndf, const std::string& kind, int spp, int seed, bool pixelCentred = false) {
    std::ostringstream s;
    s << R"({"version": 1, "render": {"width": )" << kW << R"(, "height": )" << kH << R"(, "spp": )" << spp
      << R"(, "seed": )" << seed << R"(, "integrator": "direct", "max_depth": 1, "filter": "box",
        "area_lights": "sampled"},
      "camera": {"position": [0, -1.2, 0.75], "look_at": [0, 0.05, 0], "up": [0, 0, 1], "fov": 40},
      "materials": {"m": )" << material(pndf, kind, pixelCentred) << R"(},
      "shapes": [{"type": "quad", "size": [1, 1], "material": "m"}],
      "lights": [{"type": "quad", "position": [0, 1.2, 0.75], "look_at": [0, 0, 0], "size": [0.08, 0.08],
                  "power": 20}]})";
    return s.str();
}

}  // namespace

TEST(PndfValidation, SixtyFourSppAgainstNormalMapping) {
    const std::string dir = test::tempDir("pndf-validation");
    std::printf("  map      nm64       pndf64     pndf256    ratio pndf/nm  pndf64/pndf256  (RMSE, specular AOV)\n");
    for (const char* kind : {"bumps", "brushed"}) {
        const bool bumps = std::string(kind) == "bumps";
        std::vector<float> ref = specularAov(scene(false, kind, kRefSpp, kRefSeed), dir);
        double nm = compareRmse(specularAov(scene(false, kind, kSpp, kTestSeed), dir), ref);
        double p64 = compareRmse(specularAov(scene(true, kind, kSpp, kTestSeed), dir), ref);
        // The bias-floor check on bumps only: brushed P-NDF at 256 spp costs ~35 s on 2 cores.
        double p256 = bumps ? compareRmse(specularAov(scene(true, kind, kHiSpp, kTestSeed), dir), ref) : 0.0;
        double pPix = compareRmse(specularAov(scene(true, kind, kSpp, kTestSeed, true), dir), ref);
        std::printf("  %-8s %-10.4g %-10.4g %-10.4g %-14.3f %-10.3f\n", kind, nm, p64, p256, p64 / nm,
                    bumps ? p64 / p256 : 0.0);
        std::printf("  %-8s pixel-centred box k 1: RMSE %.4g, ratio vs normal mapping %.3f, vs the default %.3f\n", kind,
                    pPix, pPix / nm, pPix / p64);
        // Claims, with the margins above.
        EXPECT_LE(p64 / nm, bumps ? kMaxRatioBumps : kMaxRatioBrushed) << kind << ": W24 Fig. 18 claim";
        EXPECT_LE(pPix / nm, kMaxRatioPixelCentred) << kind << ": pixel-centred kernel";
        if (bumps) {
            EXPECT_LE(p64 / p256, kMaxToFloor) << kind << ": P-NDF at 64 spp must be near its own bias floor";
            EXPECT_LE(pPix / p64, kMaxPixelCentredVsDefaultBumps) << "the pixel-centred kernel lowers the bias";
        }
    }
}
