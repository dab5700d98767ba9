#include "plugin/cli/validation_metrics.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace specula {

using Json = nlohmann::json;

namespace {

struct D3 {
    double x = 0, y = 0, z = 0;
};

D3 vec3(const Json& j, const char* what) {
    if (!j.is_array() || j.size() != 3) throw std::runtime_error(std::string("camera.") + what + " is not a 3-vector");
    return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}
D3 cross(const D3& a, const D3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double length(const D3& a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }
D3 scaled(const D3& a, double s) { return {a.x / s, a.y / s, a.z / s}; }

}  // namespace

void shiftCameraJson(Json& scene, double dx, double dy, int width, int height) {
    if (!scene.is_object() || !scene.contains("camera")) throw std::runtime_error("the scene has no camera");
    Json& cam = scene["camera"];
    const D3 p = vec3(cam.at("position"), "position"), la = vec3(cam.at("look_at"), "look_at");
    const D3 up = cam.contains("up") ? vec3(cam["up"], "up") : D3{0, 0, 1};
    const double fov = cam.value("fov", 39.6);
    const bool horizontal = cam.value("fov_axis", std::string("x")) == "x";
    D3 f{la.x - p.x, la.y - p.y, la.z - p.z};
    const double dist = length(f);
    if (!(dist > 0)) throw std::runtime_error("camera.look_at equals camera.position");
    f = scaled(f, dist);
    D3 r = cross(f, up);
    const double rl = length(r);
    if (!(rl > 0)) throw std::runtime_error("camera.up is parallel to the view direction");
    r = scaled(r, rl);
    const D3 u = cross(r, f);  // image up
    const double t = std::tan(fov * (M_PI / 180.0) / 2);
    const double px = 2 * dist * t / double(horizontal ? width : height);  // pixel size at the look-at distance
    const double o[3] = {px * (dx * r.x - dy * u.x), px * (dx * r.y - dy * u.y), px * (dx * r.z - dy * u.z)};
    const double pv[3] = {p.x, p.y, p.z}, lv[3] = {la.x, la.y, la.z};
    for (int i = 0; i < 3; ++i) {
        cam["position"][i] = pv[i] + o[i];
        cam["look_at"][i] = lv[i] + o[i];
    }
}

bool parseCameraShift(const std::string& text, double& dx, double& dy) {
    std::istringstream in(text);
    char c = 0;
    return (in >> dx >> c >> dy) && c == ',' && in.peek() == EOF && std::isfinite(dx) && std::isfinite(dy);
}

MaskedError maskedError(const std::vector<float>& test, const std::vector<float>& ref, int channels,
                        const std::vector<char>& mask) {
    if (test.size() != ref.size()) throw std::runtime_error("maskedError: images of different sizes");
    const size_t n = test.size() / size_t(channels);
    if (!mask.empty() && mask.size() != n) throw std::runtime_error("maskedError: mask of the wrong size");
    double se = 0, ae = 0, sr = 0;
    MaskedError e;
    for (size_t i = 0; i < n; ++i) {
        if (!mask.empty() && !mask[i]) continue;
        for (int c = 0; c < channels; ++c) {
            const double d = double(test[channels * i + c]) - double(ref[channels * i + c]);
            se += d * d, ae += std::abs(d);
            sr += ref[channels * i + c];
        }
        ++e.pixels;
    }
    if (e.pixels) {
        const double m = double(channels) * double(e.pixels);
        e.rmse = std::sqrt(se / m), e.mae = ae / m, e.meanRef = sr / m;
        e.relRmse = e.meanRef != 0 ? e.rmse / e.meanRef : 0;
    }
    return e;
}

double flickerMetric(const std::vector<std::vector<float>>& test, const std::vector<std::vector<float>>& ref,
                     int channels, const std::vector<char>& mask) {
    const size_t T = test.size();
    if (T == 0) return 0;
    if (!ref.empty() && ref.size() != T) throw std::runtime_error("flickerMetric: frame counts differ");
    const size_t n = test[0].size();
    for (size_t t = 0; t < T; ++t)
        if (test[t].size() != n || (!ref.empty() && ref[t].size() != n))
            throw std::runtime_error("flickerMetric: frames of different sizes");
    if (!mask.empty() && mask.size() * size_t(channels) != n) throw std::runtime_error("flickerMetric: mask of the wrong size");
    double acc = 0;
    size_t count = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!mask.empty() && !mask[i / size_t(channels)]) continue;
        double s = 0, s2 = 0;
        for (size_t t = 0; t < T; ++t) {
            const double e = double(test[t][i]) - (ref.empty() ? 0.0 : double(ref[t][i]));
            s += e, s2 += e * e;
        }
        const double m = s / double(T);
        acc += std::sqrt(std::max(0.0, s2 / double(T) - m * m));
        ++count;
    }
    return count ? acc / double(count) : 0.0;
}

}  // namespace specula
