// The directional albedo table of the Charlie sheen lobe (sheen_lobe.h): ∫ f cos θi dωi over a grid of cos θo and α,
// integrated once on first use, so that lobe selection and the albedo AOV cost one bilinear lookup.
#include "nodes/bsdf/sheen/sheen_lobe.h"

#include <array>

namespace specula::sheen {
namespace {

constexpr int kCosSteps = 32;    // cos θo at k / (kCosSteps − 1)
constexpr int kAlphaSteps = 16;  // α from kMinAlpha to 1, uniform
// Quadrature per entry: midpoint in cos θi (uniform in cos θi: dω = d(cos θ) dφ) and in φ over [0, π] (the lobe is
// symmetric about the plane of wo), doubled.
constexpr int kCosQuad = 64, kPhiQuad = 64;

float alphaAt(int j) { return kMinAlpha + (1.f - kMinAlpha) * float(j) / float(kAlphaSteps - 1); }

using Table = std::array<float, kCosSteps * kAlphaSteps>;

Table buildTable() {
    Table t{};
    for (int j = 0; j < kAlphaSteps; ++j) {
        const float alpha = alphaAt(j);
        for (int k = 0; k < kCosSteps; ++k) {
            // cos θo = 0 has no albedo (f·cos has 1/cos θo but G2 → 0 faster); take the first sample above it.
            const float co = std::max(float(k) / float(kCosSteps - 1), 1e-3f);
            const Vec3 wo(std::sqrt(1.f - co * co), 0.f, co);
            double sum = 0;
            for (int a = 0; a < kCosQuad; ++a) {
                const float ci = (float(a) + 0.5f) / float(kCosQuad), si = std::sqrt(1.f - ci * ci);
                for (int b = 0; b < kPhiQuad; ++b) {
                    const float phi = kPi * (float(b) + 0.5f) / float(kPhiQuad);
                    sum += reflectanceCos(wo, Vec3(si * std::cos(phi), si * std::sin(phi), ci), alpha);
                }
            }
            t[size_t(j * kCosSteps + k)] = float(sum * (2.0 * kPi) / (double(kCosQuad) * kPhiQuad));
        }
    }
    return t;
}

}  // namespace

float directionalAlbedo(float cosThetaO, float alpha) {
    static const Table table = buildTable();
    const float x = std::clamp(cosThetaO, 0.f, 1.f) * float(kCosSteps - 1);
    const float y = (std::clamp(alpha, kMinAlpha, 1.f) - kMinAlpha) / (1.f - kMinAlpha) * float(kAlphaSteps - 1);
    const int x0 = std::min(int(x), kCosSteps - 2), y0 = std::min(int(y), kAlphaSteps - 2);
    const float fx = x - float(x0), fy = y - float(y0);
    auto at = [&](int i, int j) { return table[size_t(j * kCosSteps + i)]; };
    return (1.f - fy) * ((1.f - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
           fy * ((1.f - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

}  // namespace specula::sheen
