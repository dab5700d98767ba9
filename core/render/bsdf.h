// BSDF interface of the renderer: lobes answer queries (BsdfQuery: wo, wi, the light, a lobe mask) with
// f·|cos θi| and pdf together, and the Closure, a weighted sum of lobes each in its own frame, that materials build.
#pragma once

#include "core/math/math.h"

#include <functional>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <utility>
#include <type_traits>
#include <vector>

namespace specula {

// Category of a lobe, used for the diffuse/specular AOV split and for path-space statistics.
enum class LobeKind : uint8_t { Diffuse = 0, Specular = 1 };

// f·|cos θi| split by lobe category. Everything the integrators accumulate goes through this.
struct BsdfEval {
    Color3 diffuse{0.f};
    Color3 specular{0.f};
    Color3 total() const { return diffuse + specular; }
    BsdfEval& operator+=(const BsdfEval& o) {
        diffuse += o.diffuse;
        specular += o.specular;
        return *this;
    }
};

// Bit i selects lobe i of a closure (Closure::kMaxLobes ≤ 32).
using LobeMask = uint32_t;
constexpr LobeMask kAllLobes = ~LobeMask(0);

// What a closure is asked, in world space (Mitsuba's BSDFContext, MaterialX's ClosureData): everything that
// depends on the light arrives here, so no lobe reads per-light state from the shading point.
struct BsdfQuery {
    Vec3 wo{0, 0, 1};  // towards the viewer / previous vertex (unit)
    Vec3 wi{0, 0, 1};  // towards the light (unit); ignored by sample()
    // Distance to a point light being sampled (lobes filtered by half-vector derivatives differentiate wi with
    // it, filtered-ggx.md §5.1); +inf for directions (directional, environment and area lights, BSDF samples).
    float lightDistance = std::numeric_limits<float>::infinity();
    LobeMask lobes = kAllLobes;  // which lobes answer (the others contribute nothing)
    // Polygon queries (integratePolygon): how LTC lobes treat the horizon; 0 = exact clipping, 1 = clip-free sphere
    // approximation (ltc::Horizon; render.ltc_horizon).
    uint8_t polygonHorizon = 0;
    // The geometric normal on wo's side, or 0 (tools, tests): when set, each lobe scatters only to its side of the
    // surface, reflecting lobes to wi above it and transmitting lobes (BsdfLobe::transmits) to wi below it, so that
    // shading normals leak no light through the surface either way (pbrt-v3's rule). The pdf is unchanged.
    Vec3 ng{0.f};
};

// The same query in one lobe's local frame (z = the lobe's normal).
struct LobeQuery {
    Vec3 wo{0, 0, 1};
    Vec3 wi{0, 0, 1};
    float lightDistance = std::numeric_limits<float>::infinity();
    uint8_t polygonHorizon = 0;
};

// A lobe's answer: f·|cos θi| and the solid-angle density with which sample() produces wi.
struct LobeValue {
    Color3 f{0.f};
    float pdf = 0.f;
};

// A closure's answer: f·|cos θi| by category and the mixture pdf of Closure::sample.
struct BsdfValue {
    BsdfEval f;
    float pdf = 0.f;
};

struct BsdfSample {
    Vec3 wi{0.f};          // sampled incident direction (world)
    BsdfEval f;            // f·|cos θi| of the whole closure for (wo, wi)
    float pdf = 0.f;       // solid-angle pdf of the whole closure (mixture), > 0 on success
    LobeKind kind = LobeKind::Diffuse;  // category of the lobe that generated wi
};

// Named parameter values a lobe reports (BsdfLobe::parameters).
using LobeParameters = std::vector<std::pair<std::string, std::vector<double>>>;

// One scattering lobe. All directions are unit vectors in the lobe's local frame.
class BsdfLobe {
public:
    virtual ~BsdfLobe() = default;
    virtual LobeKind kind() const = 0;
    // Whether the lobe scatters into the other hemisphere (wi below the surface: refraction) instead of its own.
    virtual bool transmits() const { return false; }
    // The one evaluation entry: f(wo, wi)·|cos θi| and pdf(wi | wo); zero where the lobe does not scatter.
    virtual LobeValue evalPdf(const LobeQuery& q) const = 0;
    // Draws wi from u in [0,1)^2 for q.wo (q.wi is ignored). Returns false if no direction could be produced.
    virtual bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const = 0;
    // Directional albedo estimate ∫ f cos dwi (used for lobe selection and the albedo AOV).
    virtual Color3 albedo(const Vec3& wo) const = 0;
    // For tools (specula bsdf) and tests: the lobe's model name and its parameters as evaluated for q, e.g. the
    // filtered roughness matrix of a filtered GGX lobe. Not used while rendering.
    virtual const char* modelName() const = 0;
    virtual void parameters(const LobeQuery& q, LobeParameters& out) const {}
    // Analytic integration over a polygonal emitter (LTC area lights, Heitz et al. 2016):
    // result = ∫_P f(wo, wi) |cos θi| dωi, the polygon's vertices given in the local frame relative to
    // the shading point (not normalised, counter-clockwise seen from the shading point). The light's
    // radiance is applied by the caller. Returns false when the lobe has no closed form.
    virtual bool integratePolygon(const LobeQuery& q, const Vec3* vertices, int count, Color3& result) const {
        return false;
    }
    // Split-sum environment lighting (the raster integrator and the GPU preview, docs/preview.md): where this lobe reads
    // the prefiltered environment, its lookup direction (local frame, unit) and GGX roughness α (PrefilteredEnvironment:
    // α < 0 reads the irradiance map). Lobes with integratePolygon and this get the environment as their hemisphere
    // integral times that radiance; false (the default) leaves the lobe to the caller's estimate.
    virtual bool environmentLookup(const LobeQuery& q, Vec3& dir, float& alpha) const { return false; }
    // The factor of that radiance: the lobe's integral over the hemisphere polygon (integratePolygon) unless the lobe
    // says otherwise (a transmitting lobe: its transmitted fraction, which no upper-hemisphere polygon holds).
    virtual bool environmentIntegral(const LobeQuery& q, const Vec3* hemisphere, int count, Color3& result) const {
        return integratePolygon(q, hemisphere, count, result);
    }
    // For lobes with integratePolygon: a direction wi distributed in proportion to the integrand integratePolygon
    // integrates, restricted to the polygon (u: the first random pair; seed: for further tries). The shadow ratio
    // of Heitz, Hill & McGuire 2018 then needs one visibility test: E[integral·V(wi)] = the shadowed integral.
    virtual bool samplePolygon(const LobeQuery& q, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                               Vec3& wi) const {
        return false;
    }

    // Conveniences for tests and tools: a directional query (no light distance).
    Color3 eval(const Vec3& wo, const Vec3& wi) const { return evalPdf(LobeQuery{wo, wi}).f; }
    float pdf(const Vec3& wo, const Vec3& wi) const { return evalPdf(LobeQuery{wo, wi}).pdf; }
    bool sample(const Vec3& wo, const Vec2& u, Vec3& wi) const { return sample(LobeQuery{wo, wo}, u, wi); }
};

// Bump allocator for per-shading-point lobes; reset after each shading point (no heap in the hot path).
class ScratchArena {
public:
    // The buffer is left uninitialised (new T[] without value-initialisation): a tile makes one arena.
    explicit ScratchArena(size_t bytes = 64 * 1024) : buffer_(new std::byte[bytes]), size_(bytes) {}
    ScratchArena(const ScratchArena&) = delete;
    ScratchArena& operator=(const ScratchArena&) = delete;
    ~ScratchArena() { reset(); }

    template <typename T, typename... Args>
    T* make(Args&&... args) {
        void* mem = allocate(sizeof(T), alignof(T));
        T* obj = new (mem) T(std::forward<Args>(args)...);
        // Lobes are plain parameter records (they must not own resources), so they are discarded in
        // bulk without destructor calls; anything else gets its destructor run at reset().
        if constexpr (!std::is_trivially_destructible_v<T> && !std::is_base_of_v<BsdfLobe, T>)
            dtors_.push_back({[](void* p) { static_cast<T*>(p)->~T(); }, obj});
        return obj;
    }
    // The bump fast paths are inline (every lobe of every path vertex is allocated here, and the arena is reset at
    // each vertex); the rare overflow and the destructor calls are not.
    void* allocate(size_t size, size_t align) {
        const size_t start = (offset_ + align - 1) & ~(align - 1);
        if (start + size <= size_) {
            offset_ = start + size;
            return buffer_.get() + start;
        }
        return allocateOverflow(size, align);
    }
    void reset() {
        if (!dtors_.empty() || !overflow_.empty()) releaseAll();
        offset_ = 0;
    }

private:
    void* allocateOverflow(size_t size, size_t align);
    void releaseAll();  // runs the destructors (in reverse order of construction), frees the overflow blocks
    struct Dtor {
        void (*fn)(void*);
        void* obj;
    };
    std::unique_ptr<std::byte[]> buffer_;
    size_t size_;
    size_t offset_ = 0;
    std::vector<Dtor> dtors_;
    std::vector<std::unique_ptr<std::byte[]>> overflow_;
};

// A weighted sum of lobes, each with its own orthonormal frame (world space): what a material returns at a
// shading point. Queries and samples are in world space; the closure rotates them into each lobe's frame.
class Closure {
public:
    static constexpr int kMaxLobes = 8;

    void clear() {
        count_ = 0;
        transmitting_ = 0;
        sel_.valid = false;
    }
    // Adds weight·lobe whose local frame is 'frame'; lobes beyond kMaxLobes or with zero weight are dropped.
    void add(const Color3& weight, const BsdfLobe* lobe, const Frame& frame);
    // Multiplies every lobe weight (closure.mix / scaling).
    void scale(const Color3& s);
    void append(const Closure& other, const Color3& weight = Color3(1.f));

    int size() const { return count_; }
    bool empty() const { return count_ == 0; }
    const BsdfLobe* lobe(int i) const { return lobes_[i]; }
    const Color3& weight(int i) const { return weights_[i]; }
    const Frame& frame(int i) const { return frames_[i]; }
    LobeMask allLobes() const { return count_ >= 32 ? kAllLobes : (LobeMask(1) << count_) - 1; }
    // Whether some lobe transmits (BsdfLobe::transmits): paths and light samples then continue below the surface.
    bool transmits() const { return transmitting_ != 0; }

    // f·cos by category and the mixture pdf of sample() over the lobes in q.lobes (the selection
    // probabilities always count every lobe, so the pdf is that of sample() whatever the mask).
    BsdfValue evalPdf(const BsdfQuery& q) const;
    // Chooses a lobe with probability ∝ luminance(weight·albedo), samples it, returns the mixture
    // f·cos and pdf of the whole closure (so MIS with light sampling stays unbiased).
    bool sample(const BsdfQuery& q, float uLobe, const Vec2& u, BsdfSample& out) const;
    Color3 albedo(const Vec3& wo) const;
    // Σ weight · lobe.integratePolygon over the lobes in q.lobes that have a closed form, split by category,
    // added to 'out'. The vertices are world-space offsets from the shading point. Returns the mask of the lobes
    // integrated analytically; the caller estimates the others (e.g. sampled next-event estimation with MIS).
    // perLobe (optional, kMaxLobes entries): each integrated lobe's weighted integral, for the shadow ratio.
    LobeMask integratePolygon(const BsdfQuery& q, const Vec3* vertices, int count, BsdfEval& out,
                              Color3* perLobe = nullptr) const;
    // The split sum of an environment (docs/preview.md): Σ weight · lobe.integratePolygon(hemisphere) ·
    // radiance(lobe's environmentLookup, in world space) over the lobes in q.lobes that have both, split by category,
    // added to 'out' (radiance: PrefilteredEnvironment::lookup, the GLSL host's spc_host_environment). hemisphere:
    // world-space directions of the polygon standing for the hemisphere of the shading normal. Returns the mask of the
    // lobes so answered; the caller estimates the others.
    LobeMask integrateEnvironment(const BsdfQuery& q, const Vec3* hemisphere, int count,
                                  const std::function<Color3(const Vec3& dir, float alpha)>& radiance,
                                  BsdfEval& out) const;
    // Lobe i's BsdfLobe::samplePolygon in world space (vertices: world offsets from the shading point).
    bool samplePolygon(const BsdfQuery& q, int i, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                       Vec3& wi) const;
    // The frame of the lobe that scatters most towards wo (largest selection weight; the first on ties), or
    // 'fallback' for an empty closure: the normal AOV and the quad-derivative partner frames. It depends on the
    // closure's structure only, never on node ids.
    const Frame& dominantFrame(const Vec3& wo, const Frame& fallback) const;

private:
    // wo in every lobe's frame and the lobe selection weights for wo, computed once per wo: a path vertex asks many
    // queries (one per light, the BSDF sample) with the same wo. A closure belongs to one thread's path vertex.
    struct Selection {
        Vec3 wo{0.f};
        bool valid = false;
        Vec3 woLocal[kMaxLobes];
        float w[kMaxLobes];
        float sum = 0.f;
    };
    const Selection& selection(const Vec3& wo) const;
    LobeMask sidedLobes(const BsdfQuery& q, const Vec3& wi) const;
    std::array<const BsdfLobe*, kMaxLobes> lobes_{};
    std::array<Color3, kMaxLobes> weights_{};
    std::array<Frame, kMaxLobes> frames_{};
    int count_ = 0;
    LobeMask transmitting_ = 0;  // the lobes that transmit
    mutable Selection sel_;
};

}  // namespace specula
