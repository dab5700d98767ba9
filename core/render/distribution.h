// Piecewise-constant 1D and 2D distributions for importance sampling tabulated functions
// (environment maps), with continuous sampling and exact pdfs (pbrt-v4 §A.4).
#pragma once

#include "core/math/math.h"

#include <vector>

namespace specula {

class Distribution1D {
public:
    Distribution1D() = default;
    explicit Distribution1D(std::vector<float> f);
    // Returns x in [0,1), its density w.r.t. [0,1), and the cell index.
    float sample(float u, float& pdf, int& index) const;
    float pdf(float x) const;
    float integral() const { return integral_; }
    int size() const { return int(f_.size()); }

private:
    std::vector<float> f_, cdf_;
    float integral_ = 0.f;
};

class Distribution2D {
public:
    Distribution2D() = default;
    // f is row-major, height rows of width values; rows index v, columns u.
    Distribution2D(const std::vector<float>& f, int width, int height);
    Vec2 sample(const Vec2& u, float& pdf) const;  // (u, v) in [0,1)^2, pdf w.r.t. area of [0,1)^2
    float pdf(const Vec2& uv) const;

private:
    std::vector<Distribution1D> conditional_;
    Distribution1D marginal_;
    int width_ = 0, height_ = 0;
};

}  // namespace specula
