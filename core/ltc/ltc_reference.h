// Independent references for LTC accuracy claims (tests, tools/ltc-report, docs/validation/ltc.md): the MIS Monte
// Carlo integral of a lobe over a quad, random quads above the horizon, and the T6 error statistics by view band.
#pragma once

#include "core/render/bsdf.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace specula::ltc {

// A parallelogram light seen from the origin: centre and half-edges; vertices counter-clockwise seen from the origin.
struct RefQuad {
    Vec3 c, a, b;
    std::array<Vec3, 4> polygon() const;
};

// ∫_P f·cos dω by multiple importance sampling: n uniform area samples of the quad and n samples of the lobe, balance
// heuristic (Veach 1997), green channel. Independent of every LTC code path (it calls only evalPdf and sample).
double monteCarloPolygonIntegral(const BsdfLobe& lobe, const Vec3& wo, const RefQuad& quad, int n, uint64_t seed);

// A random quad fully above the horizon (vertex z > 0.02), centre at elevation 5-85°, distance 0.6-2.2, half-edges
// 0.15-1.15, facing the origin within a random tilt. 'state' is advanced.
RefQuad randomRefQuad(uint64_t& state);

// T6 statistics (ltc-filtering.md §6) over view bands θ < 30°, 30-60°, 60-88°.
struct BandErrors {
    std::vector<double> absOverAlbedo[3];  // |LTC − MC| / albedo
    std::vector<double> relative[3];       // |LTC − MC| / MC, quads capturing >= 10% of the albedo
    double meanAbs(int band) const;
    double medianRelative(int band) const;
};

// A lobe for a view and the albedo its errors are divided by (the LTC magnitude, Fresnel included).
struct LobeUnderTest {
    std::unique_ptr<BsdfLobe> lobe;
    double albedo = 1;
};
using LobeFactory = std::function<LobeUnderTest(uint64_t& state, const Vec3& wo)>;

// perBand random (view, lobe, quad) triples per band; mcSamples per MC integral; horizon: BsdfQuery::polygonHorizon.
BandErrors measureQuadErrors(const LobeFactory& make, int perBand, int mcSamples, uint64_t seed, uint8_t horizon = 0);

// Uniform double in [0, 1) from a counter state (deterministic).
double nextUniform(uint64_t& state);

}  // namespace specula::ltc
