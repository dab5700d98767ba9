// Validation building blocks shared by the `specula` CLI (render --camera-shift-px, compare --mask/--frames) and
// the in-process validation tests (tests/unit/test_validation_filtered_ggx.cpp, test_lean_validation.cpp), so that
// the numbers of every validation page come from one implementation (docs/validation/README.md).
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace specula {

// ---- camera offsets ---------------------------------------------------------------------------------------------
// Translates camera.position and camera.look_at of a scene (JSON, format v1) by (dx, dy) pixels measured at the
// look-at distance: +dx along the image's right, +dy down the image (raster y). 'width' and 'height' are the image
// size the pixel is measured on (the scene's render size after overrides). Computed in double on the JSON numbers
// (defaults up = [0, 0, 1], fov = 39.6, fov_axis = "x", as the loader). Throws std::runtime_error on a degenerate
// camera.
void shiftCameraJson(nlohmann::json& scene, double dx, double dy, int width, int height);
// Parses "DX,DY" (two numbers); false on anything else.
bool parseCameraShift(const std::string& text, double& dx, double& dy);

// ---- image metrics ----------------------------------------------------------------------------------------------
// Over the pixels where mask is non-zero (every pixel when mask is empty) and every channel of interleaved images
// with 'channels' floats per pixel.
struct MaskedError {
    double rmse = 0, mae = 0;
    double meanRef = 0;  // mean of the reference inside the mask
    double relRmse = 0;  // rmse / meanRef (0 when meanRef is 0)
    size_t pixels = 0;
};
MaskedError maskedError(const std::vector<float>& test, const std::vector<float>& ref, int channels,
                        const std::vector<char>& mask = {});

// Flicker (shared/specs/validation.md §2): with E_t = test_t - ref_t per pixel and channel, the mean over the mask
// (and the channels) of the standard deviation over t of E_t. 'ref' may be empty: then E_t = test_t (the raw
// temporal variation of the test images).
double flickerMetric(const std::vector<std::vector<float>>& test, const std::vector<std::vector<float>>& ref,
                     int channels, const std::vector<char>& mask = {});

}  // namespace specula
