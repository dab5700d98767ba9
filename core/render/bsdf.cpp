// Closure (weighted lobe sum) evaluation, mixture sampling, and the scratch arena.
#include "core/render/bsdf.h"

namespace specula {

void* ScratchArena::allocate(size_t size, size_t align) {
    size_t start = (offset_ + align - 1) & ~(align - 1);
    if (start + size <= size_) {
        offset_ = start + size;
        return buffer_.get() + start;
    }
    // Rare: a shading point needed more than the arena; keep it alive until reset().
    overflow_.emplace_back(new std::byte[size + align]);
    auto p = reinterpret_cast<uintptr_t>(overflow_.back().get());
    return reinterpret_cast<void*>((p + align - 1) & ~(uintptr_t(align) - 1));
}

void ScratchArena::reset() {
    for (auto it = dtors_.rbegin(); it != dtors_.rend(); ++it) it->fn(it->obj);
    dtors_.clear();
    overflow_.clear();
    offset_ = 0;
}

void Closure::add(const Color3& weight, const BsdfLobe* lobe) {
    if (!lobe || count_ >= kMaxLobes || maxComponent(weight) <= 0.f) return;
    lobes_[count_] = lobe;
    weights_[count_] = weight;
    ++count_;
}

void Closure::scale(const Color3& s) {
    for (int i = 0; i < count_; ++i) weights_[i] *= s;
}

void Closure::append(const Closure& other, const Color3& weight) {
    for (int i = 0; i < other.count_; ++i) add(other.weights_[i] * weight, other.lobes_[i]);
}

BsdfEval Closure::eval(const Vec3& wo, const Vec3& wi) const {
    BsdfEval r;
    for (int i = 0; i < count_; ++i) {
        Color3 f = weights_[i] * lobes_[i]->eval(wo, wi);
        (lobes_[i]->kind() == LobeKind::Diffuse ? r.diffuse : r.specular) += f;
    }
    return r;
}

void Closure::selectionWeights(const Vec3& wo, float* w, float& sum) const {
    sum = 0.f;
    for (int i = 0; i < count_; ++i) {
        w[i] = std::max(luminance(weights_[i] * lobes_[i]->albedo(wo)), 0.f);
        sum += w[i];
    }
    if (sum <= 0.f) {  // fall back to uniform selection so no lobe becomes unreachable
        for (int i = 0; i < count_; ++i) w[i] = 1.f;
        sum = float(count_);
    }
}

float Closure::pdf(const Vec3& wo, const Vec3& wi) const {
    if (count_ == 0) return 0.f;
    float w[kMaxLobes], sum;
    selectionWeights(wo, w, sum);
    float p = 0.f;
    for (int i = 0; i < count_; ++i)
        if (w[i] > 0.f) p += w[i] / sum * lobes_[i]->pdf(wo, wi);
    return p;
}

bool Closure::sample(const Vec3& wo, float uLobe, const Vec2& u, BsdfSample& out) const {
    if (count_ == 0) return false;
    float w[kMaxLobes], sum;
    selectionWeights(wo, w, sum);
    float target = uLobe * sum, acc = 0.f;
    int chosen = count_ - 1;
    for (int i = 0; i < count_; ++i) {
        acc += w[i];
        if (target < acc && w[i] > 0.f) {
            chosen = i;
            break;
        }
    }
    Vec3 wi;
    if (!lobes_[chosen]->sample(wo, u, wi)) return false;
    out.wi = wi;
    out.kind = lobes_[chosen]->kind();
    out.pdf = pdf(wo, wi);
    if (!(out.pdf > 0.f)) return false;
    out.f = eval(wo, wi);
    return true;
}

bool Closure::integratePolygon(const Vec3& wo, const Vec3* vertices, int count, BsdfEval& out) const {
    BsdfEval sum;
    for (int i = 0; i < count_; ++i) {
        Color3 r;
        if (!lobes_[i]->integratePolygon(wo, vertices, count, r)) return false;
        (lobes_[i]->kind() == LobeKind::Diffuse ? sum.diffuse : sum.specular) += weights_[i] * r;
    }
    out = sum;
    return count_ > 0;
}

Color3 Closure::albedo(const Vec3& wo) const {
    Color3 a(0.f);
    for (int i = 0; i < count_; ++i) a += weights_[i] * lobes_[i]->albedo(wo);
    return a;
}

}  // namespace specula
