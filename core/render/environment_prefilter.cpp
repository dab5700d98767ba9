// Split-sum prefiltering of a lat-long environment (Karis 2013) and its GL-style trilinear lookup.
#include "core/render/environment_prefilter.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace specula {

namespace {

int floorPow2(int x) {
    int p = 1;
    while (p * 2 <= x) p *= 2;
    return p;
}

// The direction at lat-long (u, v) of a map turned by 'rotation' (EnvironmentLight::uvToDir).
Vec3 uvToDirection(const Vec2& uv, float rotation) {
    float a = (0.5f - uv.x) * 2.f * kPi;
    float theta = uv.y * kPi;
    float st = std::sin(theta);
    Vec3 r(-std::cos(a) * st, std::sin(a) * st, std::cos(theta));
    float c = std::cos(rotation), s = std::sin(rotation);
    return {c * r.x - s * r.y, s * r.x + c * r.y, r.z};
}

// The map resampled to width × height: each target texel is the solid-angle weighted mean of the source texels whose
// centres it contains (a box filter), or, where it contains none (magnification), the source texel under its centre
// (EnvironmentLight::radiance reads the nearest texel). Times 'scale'.
EnvironmentImage resample(const RasterLight& l, int width, int height) {
    EnvironmentImage out{width, height, std::vector<float>(size_t(width) * height * 3, 0.f)};
    const int w = l.mapWidth, h = l.mapHeight;
    for (int y = 0; y < height; ++y) {
        const int y0 = int(std::ceil(double(y) * h / height - 0.5)), y1 = int(std::ceil(double(y + 1) * h / height - 0.5));
        for (int x = 0; x < width; ++x) {
            const int x0 = int(std::ceil(double(x) * w / width - 0.5)), x1 = int(std::ceil(double(x + 1) * w / width - 0.5));
            double sum[3] = {0, 0, 0}, weight = 0;
            for (int sy = std::max(y0, 0); sy < std::min(y1, h); ++sy) {
                const double sinTheta = std::sin(kPi * (sy + 0.5) / h);
                for (int sx = std::max(x0, 0); sx < std::min(x1, w); ++sx) {
                    const float* p = &l.map[(size_t(sy) * w + sx) * 3];
                    for (int c = 0; c < 3; ++c) sum[c] += sinTheta * p[c];
                    weight += sinTheta;
                }
            }
            float* o = &out.rgb[(size_t(y) * width + x) * 3];
            if (weight > 0) {
                for (int c = 0; c < 3; ++c) o[c] = float(sum[c] / weight) * l.mapScale[c];
            } else {
                const int sx = std::clamp(int((x + 0.5) * w / width), 0, w - 1);
                const int sy = std::clamp(int((y + 0.5) * h / height), 0, h - 1);
                const float* p = &l.map[(size_t(sy) * w + sx) * 3];
                for (int c = 0; c < 3; ++c) o[c] = p[c] * l.mapScale[c];
            }
        }
    }
    return out;
}

// The texels of an image as directions, solid angles and radiance (the convolutions' source).
struct SourceTexels {
    std::vector<Vec3> dir;
    std::vector<float> solidAngle;
    std::vector<Color3> radiance;
};

SourceTexels sourceTexels(const EnvironmentImage& img, float rotation) {
    SourceTexels s;
    for (int y = 0; y < img.height; ++y) {
        // exact solid angle of a lat-long row's texel: (2π / width)(cos θ0 − cos θ1)
        const double omega = 2.0 * kPi / img.width *
                             (std::cos(kPi * double(y) / img.height) - std::cos(kPi * double(y + 1) / img.height));
        for (int x = 0; x < img.width; ++x) {
            s.dir.push_back(uvToDirection({(x + 0.5f) / img.width, (y + 0.5f) / img.height}, rotation));
            s.solidAngle.push_back(float(omega));
            const float* p = &img.rgb[(size_t(y) * img.width + x) * 3];
            s.radiance.emplace_back(p[0], p[1], p[2]);
        }
    }
    return s;
}

// out(R) = Σ_j L_j w_j / Σ_j w_j over the source texels, w_j = weight(R·l_j) ΔΩ_j: a normalised convolution on the
// sphere. Each texel is independent (and summed in a fixed order), so any thread count gives the same bits.
template <class Weight>
EnvironmentImage convolve(const SourceTexels& src, int width, int height, float rotation, Weight weight) {
    EnvironmentImage out{width, height, std::vector<float>(size_t(width) * height * 3, 0.f)};
    tbb::parallel_for(0, height, [&](int y) {
        for (int x = 0; x < width; ++x) {
            const Vec3 r = uvToDirection({(x + 0.5f) / width, (y + 0.5f) / height}, rotation);
            double sum[3] = {0, 0, 0}, wsum = 0;
            for (size_t j = 0; j < src.dir.size(); ++j) {
                const float c = glm::dot(r, src.dir[j]);
                if (c <= 0.f) continue;
                const double w = double(weight(c)) * src.solidAngle[j];
                for (int k = 0; k < 3; ++k) sum[k] += w * src.radiance[j][k];
                wsum += w;
            }
            float* o = &out.rgb[(size_t(y) * width + x) * 3];
            for (int k = 0; k < 3; ++k) o[k] = wsum > 0 ? float(sum[k] / wsum) : 0.f;
        }
    });
    return out;
}

}  // namespace

Vec2 environmentUv(const Vec3& d, float rotation) {
    float c = std::cos(rotation), s = std::sin(rotation);
    Vec3 r(c * d.x + s * d.y, -s * d.x + c * d.y, d.z);  // rotate by -rotation
    float u = 0.5f - std::atan2(r.y, -r.x) * kInv2Pi;
    u -= std::floor(u);
    float v = std::acos(std::clamp(r.z, -1.f, 1.f)) * kInvPi;
    return {u, v};
}

Color3 sampleBilinear(const EnvironmentImage& img, const Vec2& uv) {
    const float fx = uv.x * img.width - 0.5f, fy = uv.y * img.height - 0.5f;
    const float x0f = std::floor(fx), y0f = std::floor(fy);
    const float ax = fx - x0f, ay = fy - y0f;
    auto wrap = [&](int i) { return ((i % img.width) + img.width) % img.width; };
    auto clampY = [&](int j) { return std::clamp(j, 0, img.height - 1); };
    const int x0 = wrap(int(x0f)), x1 = wrap(int(x0f) + 1), y0 = clampY(int(y0f)), y1 = clampY(int(y0f) + 1);
    auto at = [&](int x, int y) {
        const float* p = &img.rgb[(size_t(y) * img.width + x) * 3];
        return Color3(p[0], p[1], p[2]);
    };
    return (1.f - ay) * ((1.f - ax) * at(x0, y0) + ax * at(x1, y0)) + ay * ((1.f - ax) * at(x0, y1) + ax * at(x1, y1));
}

Color3 PrefilteredEnvironment::lookup(const Vec3& dir, float alpha) const {
    if (!hasMap) return constant;
    const Vec2 uv = environmentUv(dir, rotation);
    if (alpha < 0.f) return sampleBilinear(irradiance, uv);
    const float lod = std::clamp(alpha, 0.f, 1.f) * float(kEnvironmentLevels - 1);
    const int k0 = std::min(int(lod), kEnvironmentLevels - 1), k1 = std::min(k0 + 1, kEnvironmentLevels - 1);
    const float f = lod - float(k0);
    const Color3 a = sampleBilinear(levels[size_t(k0)], uv);
    return f > 0.f ? (1.f - f) * a + f * sampleBilinear(levels[size_t(k1)], uv) : a;
}

PrefilteredEnvironment prefilterEnvironment(const RasterLight& l) {
    PrefilteredEnvironment p;
    if (!l.hasMap || !l.map || l.mapWidth <= 0 || l.mapHeight <= 0) {
        p.constant = l.value;
        return p;
    }
    p.hasMap = true;
    p.rotation = l.mapRotation;
    const int w0 = std::clamp(floorPow2(l.mapWidth), kEnvironmentMinWidth, kEnvironmentMaxWidth);
    const int h0 = w0 / 2;
    const int ws = std::min(kEnvironmentSourceWidth, w0);
    const SourceTexels src = sourceTexels(resample(l, ws, ws / 2), p.rotation);
    p.levels.push_back(resample(l, w0, h0));
    for (int k = 1; k < kEnvironmentLevels; ++k) {
        const float alpha = float(k) / float(kEnvironmentLevels - 1), a2 = alpha * alpha;
        // N = V = R: the reflected lobe in l is D(h)(n·h)/(4 h·l) = D(h)/4 (n·h = h·l), weighted by n·l = R·l;
        // cos θh = R·h = sqrt((1 + R·l)/2). GGX D (Walter et al. 2007, Eq. 33), constants cancel in the normalisation.
        p.levels.push_back(convolve(src, std::max(1, w0 >> k), std::max(1, h0 >> k), p.rotation, [a2](float c) {
            const float ch2 = 0.5f * (1.f + c);
            const float e = ch2 * (a2 - 1.f) + 1.f;
            return c / (e * e);
        }));
    }
    // The cosine-weighted mean of L about n: E(n)/π.
    p.irradiance = convolve(src, kEnvironmentIrradianceWidth, kEnvironmentIrradianceWidth / 2, p.rotation,
                            [](float c) { return c; });
    return p;
}

}  // namespace specula
