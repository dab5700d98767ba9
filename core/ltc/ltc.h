// Linearly transformed cosines (Heitz, Dupuy, Hill & Neubelt 2016, "HDHN16", with the 2017 updates): the LTC
// distribution, its polygon integral (exact horizon clipping or the clip-free sphere approximation) and a lobe of one LTC.
#pragma once

#include "core/math/math.h"
#include "core/render/bsdf.h"

namespace specula::ltc {

struct LtcTables;

// How a polygon that crosses the horizon of the cosine space is handled (ltc-filtering.md §3 steps 4-5).
enum class Horizon : uint8_t {
    Clip,      // exact: Sutherland-Hodgman against z > 0, then the acos edge integral
    Clipless,  // rational edge factor, no clipping, the equivalent-cap horizon correction of the sphere table
};

// One LTC in a lobe's local frame (z = normal): D(w) = D_o(w_o) |det M⁻¹| / |M⁻¹ w|³ with w_o = M⁻¹w/|M⁻¹w| and
// D_o(w) = max(0, w_z)/π (HDHN16 Eq. 1), scaled by the lobe's directional albedo. invM may have any non-zero scale.
struct Ltc {
    Mat3 invM{1.f};         // lobe-frame direction -> cosine space (glm, column-major: invM[col][row])
    float magnitude = 1.f;  // ∫ f·cos dω with F = 1 (the table's "mag")
    float fresnel = 0.f;    // ∫ f·cos·(1 − wo·h)⁵ dω (the table's "fres"); Schlick: F0·mag + (1 − F0)·fres
    // D(w) for a unit w; integrates to 1 over the sphere (mass below the lobe frame's horizon is "leak").
    float density(const Vec3& w) const;
    // A direction distributed as D: a cosine sample w_o of u, mapped by M (HDHN16 §3.3).
    Vec3 sample(const Vec2& u) const;
};

// Where an LTC lobe reads the prefiltered environment (docs/preview.md): dir = M·ẑ normalised, the image of the
// cosine's peak, and the GGX roughness whose reflected lobe (N = V = R) has the LTC's peak density,
// D(dir) = |det M⁻¹| |M ẑ|³ / π = 1/(4π α²), i.e. α = 1 / (2 |det M⁻¹|^½ |M ẑ|^{3/2}), clamped to [0, 1]. Any scale of
// invM gives the same. GLSL twin: spc_ltc_environment_lookup (nodes/shared/ltc.glsl).
void environmentLookup(const Ltc& ltc, Vec3& dir, float& alpha);

// ---- Building blocks (ltc-filtering.md §3) ----------------------------------------------------------------------

// Exact edge term of Lambert's form factor for unit a, b: acos(a·b)·[(a×b)/|a×b|]_z / 2π (HDHN16 Eq. 11 per edge).
double edgeIntegralExact(const DVec3& a, const DVec3& b);
// θ/sin θ/2π for x = cos θ, the rational fit of ltc_code (§3 step 3); relative error ≈ 1.4e-6 in double.
double rationalEdgeFactor(double x);
// (a×b)·rationalEdgeFactor(a·b) for unit a, b: the edge's contribution to the form-factor vector.
DVec3 edgeVectorRational(const DVec3& a, const DVec3& b);
// Sutherland-Hodgman clip of a polygon against the half-space z > 0; 'out' needs room for n + 1 vertices.
int clipToUpperHemisphere(const DVec3* in, int n, DVec3* out);
// Form factor of a spherical cap (half-angle σ, axis elevation ω from the normal) clipped by the horizon
// (Snyder 1996, ltc-filtering.md §3 step 5); for σ -> 0 it tends to sin²σ·max(cos ω, 0).
double capFormFactor(double omega, double sigma);

// ∫_P D_o over a polygon in cosine space (vertices relative to the shading point, any length, counter-clockwise
// seen from the origin when the polygon faces it). One-sided: max(0, E); two-sided: |E|. Clipless needs the sphere
// table (tables may be null for Clip).
double clampedCosineIntegral(const DVec3* v, int n, bool twoSided, Horizon horizon, const LtcTables* tables);
// ∫_P D over a polygon given in the LTC's lobe frame (transforms by invM, then clampedCosineIntegral).
double integrate(const Ltc& ltc, const Vec3* vertices, int n, bool twoSided, Horizon horizon,
                 const LtcTables* tables);
// What the lobes use: one-sided (lights orient their polygons), and Clipless reads the shipped sphere table, so the
// CPU's clip-free path is the GPU's (Clip is exact and needs no table).
double integrateForLobe(const Ltc& ltc, const Vec3* vertices, int n, uint8_t horizon);

// Draws w ∝ D restricted to the polygon (vertices in the LTC's lobe frame, relative to the shading point, oriented as
// for clampedCosineIntegral): Malley's method in cosine space, i.e. a uniform point of the clipped polygon's
// projection onto the unit disk, by rejection from its exact bounding box. u is the first try; further tries hash
// 'seed'. The density (solid angle, lobe frame) is D(w)/∫_P D. False when the polygon is invisible or no try hit.
// This is the sampling the ratio estimator of Heitz, Hill & McGuire 2018 needs for an unbiased shadow ratio.
bool samplePolygon(const Ltc& ltc, const Vec3* vertices, int n, const Vec2& u, uint64_t seed, Vec3& w);

// A lobe made of one LTC: f·cos = tint·magnitude·D(wi) on the upper hemisphere, pdf = D(wi) (its own sampling;
// samples below the horizon are rejected, so the pdf is a sub-density), and the exact polygon integral.
// Used for prefiltered normal maps (Nahmias 2022), where the fitted LTC *is* the effective BRDF.
class LtcLobe final : public BsdfLobe {
public:
    LtcLobe(const Ltc& ltc, LobeKind kind, const Color3& tint) : ltc_(ltc), kind_(kind), tint_(tint) {}
    LobeKind kind() const override { return kind_; }
    using BsdfLobe::sample;
    LobeValue evalPdf(const LobeQuery& q) const override;
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override;
    Color3 albedo(const Vec3& wo) const override { return tint_ * ltc_.magnitude; }
    const char* modelName() const override { return "ltc"; }
    void parameters(const LobeQuery& q, LobeParameters& out) const override;
    bool integratePolygon(const LobeQuery& q, const Vec3* vertices, int count, Color3& result) const override;
    bool samplePolygon(const LobeQuery& q, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                       Vec3& wi) const override;
    bool environmentLookup(const LobeQuery&, Vec3& dir, float& alpha) const override {
        ltc::environmentLookup(ltc_, dir, alpha);
        return true;
    }
    const Ltc& ltc() const { return ltc_; }

private:
    Ltc ltc_;
    LobeKind kind_;
    Color3 tint_;
};

}  // namespace specula::ltc
