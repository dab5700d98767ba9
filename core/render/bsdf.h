// BSDF interface of the renderer: lobes in the local shading frame (z = shading normal) offering
// eval (f·|cos θi|), pdf and sample, and the Closure, a weighted sum of lobes that materials build.
#pragma once

#include "core/math/math.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
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

struct BsdfSample {
    Vec3 wi{0.f};          // sampled incident direction (local frame)
    BsdfEval f;            // f·|cos θi| of the whole closure for (wo, wi)
    float pdf = 0.f;       // solid-angle pdf of the whole closure (mixture), > 0 on success
    LobeKind kind = LobeKind::Diffuse;  // category of the lobe that generated wi
};

// One scattering lobe. All directions are unit vectors in the local shading frame.
class BsdfLobe {
public:
    virtual ~BsdfLobe() = default;
    virtual LobeKind kind() const = 0;
    // f(wo, wi)·|cos θi|; zero where the lobe does not scatter (e.g. wi below the surface for reflection).
    virtual Color3 eval(const Vec3& wo, const Vec3& wi) const = 0;
    // Solid-angle density with which sample() produces wi.
    virtual float pdf(const Vec3& wo, const Vec3& wi) const = 0;
    // Draws wi from u in [0,1)^2. Returns false if no direction could be produced.
    virtual bool sample(const Vec3& wo, const Vec2& u, Vec3& wi) const = 0;
    // Directional albedo estimate ∫ f cos dwi (used for lobe selection and the albedo AOV).
    virtual Color3 albedo(const Vec3& wo) const = 0;
    // Hook for analytic integration over a polygonal emitter (LTC area lights, Heitz et al. 2016):
    // result = ∫_P f(wo, wi) |cos θi| dωi, the polygon's vertices given in the local frame relative to
    // the shading point (not normalised, counter-clockwise seen from the shading point). The light's
    // radiance is applied by the caller. Returns false when the lobe has no closed form.
    virtual bool integratePolygon(const Vec3& wo, const Vec3* vertices, int count, Color3& result) const {
        return false;
    }
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
    void* allocate(size_t size, size_t align);
    void reset();

private:
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

// A weighted sum of lobes: what a material returns at a shading point.
class Closure {
public:
    static constexpr int kMaxLobes = 8;

    void clear() { count_ = 0; }
    // Adds weight·lobe; lobes beyond kMaxLobes or with zero weight are dropped.
    void add(const Color3& weight, const BsdfLobe* lobe);
    // Multiplies every lobe weight (closure.mix / scaling).
    void scale(const Color3& s);
    void append(const Closure& other, const Color3& weight = Color3(1.f));

    int size() const { return count_; }
    bool empty() const { return count_ == 0; }
    const BsdfLobe* lobe(int i) const { return lobes_[i]; }
    const Color3& weight(int i) const { return weights_[i]; }

    BsdfEval eval(const Vec3& wo, const Vec3& wi) const;
    float pdf(const Vec3& wo, const Vec3& wi) const;
    // Chooses a lobe with probability ∝ luminance(weight·albedo), samples it, returns the mixture
    // f·cos and pdf of the whole closure (so MIS with light sampling stays unbiased).
    bool sample(const Vec3& wo, float uLobe, const Vec2& u, BsdfSample& out) const;
    Color3 albedo(const Vec3& wo) const;
    // Σ weight · lobe.integratePolygon, split by category; false unless every lobe has a closed form.
    bool integratePolygon(const Vec3& wo, const Vec3* vertices, int count, BsdfEval& out) const;

private:
    void selectionWeights(const Vec3& wo, float* w, float& sum) const;
    std::array<const BsdfLobe*, kMaxLobes> lobes_{};
    std::array<Color3, kMaxLobes> weights_{};
    int count_ = 0;
};

}  // namespace specula
