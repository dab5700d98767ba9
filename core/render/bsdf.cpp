// Closure (weighted lobe sum, one frame per lobe) evaluation, mixture sampling, polygon integration, and the
// scratch arena.
#include "core/render/bsdf.h"

namespace specula {

void* ScratchArena::allocateOverflow(size_t size, size_t align) {
    // Rare: a shading point needed more than the arena; keep it alive until reset().
    overflow_.emplace_back(new std::byte[size + align]);
    auto p = reinterpret_cast<uintptr_t>(overflow_.back().get());
    return reinterpret_cast<void*>((p + align - 1) & ~(uintptr_t(align) - 1));
}

void ScratchArena::releaseAll() {
    for (auto it = dtors_.rbegin(); it != dtors_.rend(); ++it) it->fn(it->obj);
    dtors_.clear();
    overflow_.clear();
}

namespace {
bool sameFrame(const Frame& a, const Frame& b) { return a.n == b.n && a.t == b.t && a.b == b.b; }
}  // namespace

// The lobes of q.lobes that scatter towards wi (BsdfQuery::ng): the reflecting ones above the geometric surface, the
// transmitting ones below it; q.lobes itself where no geometric normal is given.
LobeMask Closure::sidedLobes(const BsdfQuery& q, const Vec3& wi) const {
    if (q.ng == Vec3(0.f)) return q.lobes;
    return q.lobes & (glm::dot(wi, q.ng) > 0.f ? ~transmitting_ : transmitting_);
}

void Closure::add(const Color3& weight, const BsdfLobe* lobe, const Frame& frame) {
    if (!lobe || count_ >= kMaxLobes || maxComponent(weight) <= 0.f) return;
    lobes_[count_] = lobe;
    weights_[count_] = weight;
    frames_[count_] = frame;
    if (lobe->transmits()) transmitting_ |= LobeMask(1) << count_;
    ++count_;
    sel_.valid = false;
}

void Closure::scale(const Color3& s) {
    for (int i = 0; i < count_; ++i) weights_[i] *= s;
    sel_.valid = false;
}

void Closure::append(const Closure& other, const Color3& weight) {
    for (int i = 0; i < other.count_; ++i) add(other.weights_[i] * weight, other.lobes_[i], other.frames_[i]);
}

const Closure::Selection& Closure::selection(const Vec3& wo) const {
    if (sel_.valid && sel_.wo == wo) return sel_;
    sel_.wo = wo;
    sel_.valid = true;
    sel_.sum = 0.f;
    for (int i = 0; i < count_; ++i) {
        sel_.woLocal[i] = frames_[i].toLocal(wo);
        sel_.w[i] = std::max(luminance(weights_[i] * lobes_[i]->albedo(sel_.woLocal[i])), 0.f);
        sel_.sum += sel_.w[i];
    }
    if (sel_.sum <= 0.f) {  // fall back to uniform selection so no lobe becomes unreachable
        for (int i = 0; i < count_; ++i) sel_.w[i] = 1.f;
        sel_.sum = float(count_);
    }
    return sel_;
}

BsdfValue Closure::evalPdf(const BsdfQuery& q) const {
    BsdfValue r;
    if (count_ == 0) return r;
    const Selection& s = selection(q.wo);
    const Vec3* wo = s.woLocal;
    const float* w = s.w;
    const float sum = s.sum;
    const LobeMask lobes = sidedLobes(q, q.wi);
    for (int i = 0; i < count_; ++i) {
        LobeValue v = lobes_[i]->evalPdf(LobeQuery{wo[i], frames_[i].toLocal(q.wi), q.lightDistance});
        if ((lobes >> i) & 1) (lobes_[i]->kind() == LobeKind::Diffuse ? r.f.diffuse : r.f.specular) += weights_[i] * v.f;
        if (w[i] > 0.f) r.pdf += w[i] / sum * v.pdf;
    }
    return r;
}

bool Closure::sample(const BsdfQuery& q, float uLobe, const Vec2& u, BsdfSample& out) const {
    if (count_ == 0) return false;
    const Selection& s = selection(q.wo);
    const Vec3* wo = s.woLocal;
    const float* w = s.w;
    const float sum = s.sum;
    float target = uLobe * sum, acc = 0.f;
    int chosen = count_ - 1;
    for (int i = 0; i < count_; ++i) {
        acc += w[i];
        if (target < acc && w[i] > 0.f) {
            chosen = i;
            break;
        }
    }
    Vec3 wiChosen;
    if (!lobes_[chosen]->sample(LobeQuery{wo[chosen], wo[chosen], q.lightDistance}, u, wiChosen)) return false;
    const Frame& fc = frames_[chosen];
    out.wi = fc.toWorld(wiChosen);
    out.kind = lobes_[chosen]->kind();
    // Lobes sharing the sampling lobe's frame see the sampled local direction itself (no round trip through world).
    BsdfEval f;
    float pdf = 0.f;
    const LobeMask lobes = sidedLobes(q, out.wi);
    for (int i = 0; i < count_; ++i) {
        Vec3 wi = sameFrame(frames_[i], fc) ? wiChosen : frames_[i].toLocal(out.wi);
        LobeValue v = lobes_[i]->evalPdf(LobeQuery{wo[i], wi, q.lightDistance});
        if ((lobes >> i) & 1) (lobes_[i]->kind() == LobeKind::Diffuse ? f.diffuse : f.specular) += weights_[i] * v.f;
        if (w[i] > 0.f) pdf += w[i] / sum * v.pdf;
    }
    out.pdf = pdf;
    if (!(out.pdf > 0.f)) return false;
    out.f = f;
    return true;
}

LobeMask Closure::integratePolygon(const BsdfQuery& q, const Vec3* vertices, int count, BsdfEval& out,
                                   Color3* perLobe) const {
    LobeMask done = 0;
    Vec3 local[8];
    if (count > 8) return 0;
    for (int i = 0; i < count_; ++i) {
        if (!((q.lobes >> i) & 1)) continue;
        for (int k = 0; k < count; ++k) local[k] = frames_[i].toLocal(vertices[k]);
        Color3 r;
        LobeQuery lq{frames_[i].toLocal(q.wo), frames_[i].toLocal(q.wo), q.lightDistance, q.polygonHorizon};
        if (!lobes_[i]->integratePolygon(lq, local, count, r)) continue;
        (lobes_[i]->kind() == LobeKind::Diffuse ? out.diffuse : out.specular) += weights_[i] * r;
        if (perLobe) perLobe[i] = weights_[i] * r;
        done |= LobeMask(1) << i;
    }
    return done;
}

LobeMask Closure::integrateEnvironment(const BsdfQuery& q, const Vec3* hemisphere, int count,
                                       const std::function<Color3(const Vec3&, float)>& radiance,
                                       BsdfEval& out) const {
    LobeMask done = 0;
    Vec3 local[8];
    if (count > 8) return 0;
    for (int i = 0; i < count_; ++i) {
        if (!((q.lobes >> i) & 1)) continue;
        LobeQuery lq{frames_[i].toLocal(q.wo), frames_[i].toLocal(q.wo), q.lightDistance, q.polygonHorizon};
        Vec3 dir;
        float alpha;
        if (!lobes_[i]->environmentLookup(lq, dir, alpha)) continue;
        for (int k = 0; k < count; ++k) local[k] = frames_[i].toLocal(hemisphere[k]);
        Color3 r;
        if (!lobes_[i]->environmentIntegral(lq, local, count, r)) continue;
        const Color3 L = radiance(frames_[i].toWorld(dir), alpha);
        (lobes_[i]->kind() == LobeKind::Diffuse ? out.diffuse : out.specular) += weights_[i] * r * L;
        done |= LobeMask(1) << i;
    }
    return done;
}

bool Closure::samplePolygon(const BsdfQuery& q, int i, const Vec3* vertices, int count, const Vec2& u, uint64_t seed,
                            Vec3& wi) const {
    if (i < 0 || i >= count_ || count > 8) return false;
    Vec3 local[8];
    for (int k = 0; k < count; ++k) local[k] = frames_[i].toLocal(vertices[k]);
    LobeQuery lq{frames_[i].toLocal(q.wo), frames_[i].toLocal(q.wo), q.lightDistance, q.polygonHorizon};
    Vec3 w;
    if (!lobes_[i]->samplePolygon(lq, local, count, u, seed, w)) return false;
    wi = frames_[i].toWorld(w);
    return true;
}

Color3 Closure::albedo(const Vec3& wo) const {
    Color3 a(0.f);
    for (int i = 0; i < count_; ++i) a += weights_[i] * lobes_[i]->albedo(frames_[i].toLocal(wo));
    return a;
}

const Frame& Closure::dominantFrame(const Vec3& wo, const Frame& fallback) const {
    if (count_ == 0) return fallback;
    const Selection& s = selection(wo);
    int best = 0;
    for (int i = 1; i < count_; ++i)
        if (s.w[i] > s.w[best]) best = i;
    return frames_[best];
}

}  // namespace specula
