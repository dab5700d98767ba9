// Piecewise-constant distributions.
#include "core/render/distribution.h"

namespace specula {

Distribution1D::Distribution1D(std::vector<float> f) : f_(std::move(f)), cdf_(f_.size() + 1) {
    int n = int(f_.size());
    cdf_[0] = 0.f;
    double acc = 0.0;
    for (int i = 0; i < n; ++i) {
        f_[i] = std::max(0.f, std::isfinite(f_[i]) ? f_[i] : 0.f);
        acc += double(f_[i]) / n;
        cdf_[i + 1] = float(acc);
    }
    integral_ = float(acc);
    if (integral_ <= 0.f) {
        for (int i = 0; i <= n; ++i) cdf_[i] = float(i) / n;
    } else {
        for (int i = 1; i <= n; ++i) cdf_[i] /= integral_;
    }
    cdf_[n] = 1.f;
}

float Distribution1D::sample(float u, float& pdf, int& index) const {
    int n = int(f_.size());
    auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u);
    index = std::clamp(int(it - cdf_.begin()) - 1, 0, n - 1);
    float width = cdf_[index + 1] - cdf_[index];
    float du = width > 0.f ? (u - cdf_[index]) / width : 0.5f;
    pdf = integral_ > 0.f ? f_[index] / integral_ : 1.f;
    return std::min((index + du) / n, 0.99999994f);
}

float Distribution1D::pdf(float x) const {
    int n = int(f_.size());
    int i = std::clamp(int(x * n), 0, n - 1);
    return integral_ > 0.f ? f_[i] / integral_ : 1.f;
}

Distribution2D::Distribution2D(const std::vector<float>& f, int width, int height) : width_(width), height_(height) {
    std::vector<float> marginal(height);
    conditional_.reserve(height);
    for (int v = 0; v < height; ++v) {
        conditional_.emplace_back(std::vector<float>(f.begin() + size_t(v) * width, f.begin() + size_t(v + 1) * width));
        marginal[v] = conditional_.back().integral();
    }
    marginal_ = Distribution1D(std::move(marginal));
}

Vec2 Distribution2D::sample(const Vec2& u, float& pdf) const {
    float pv, pu;
    int iv, iu;
    float v = marginal_.sample(u.y, pv, iv);
    float x = conditional_[iv].sample(u.x, pu, iu);
    pdf = pv * pu;
    return {x, v};
}

float Distribution2D::pdf(const Vec2& uv) const {
    int iv = std::clamp(int(uv.y * height_), 0, height_ - 1);
    return marginal_.pdf(uv.y) * conditional_[iv].pdf(uv.x);
}

}  // namespace specula
