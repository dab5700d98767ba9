// Lobe conformance suite (issue 9 item 7, docs/conformance.md), driven by the node registry: every node of category
// "bsdf" with a closure output is loaded alone as a material graph over a grid of parameter values taken from its
// ports' documented ranges, shaded at a fixed shading point, and queried through Closure::evalPdf / Closure::sample
// in world space exactly as the integrator does. Per grid point and view direction:
//   - χ² goodness of fit of sample() against evalPdf() (pbrt-v4's test style), and ∫ pdf dω == acceptance rate ≤ 1;
//   - pdf of a sample: BsdfSample.pdf / .f equal evalPdf(wo, wi) for the sampled wi;
//   - reciprocity where the model is reciprocal (table kReciprocity below says which and why);
//   - energy: ∫ f cos dωi ≤ 1 (+ Monte-Carlo error), per unit of the projected area of the plane the lobe models
//     (planeAreaRatio: a resolved tilted platelet's).
// CPU against GLSL is tests/glsl/test_glsl_parity.cpp (every registered node); here we only assert each BSDF node is
// covered by it. A new lobe gets all of this by being registered. Everything is seeded (deterministic).
#include "core/graph/graph_material.h"
#include "core/graph/node_spec.h"
#include "core/render/bsdf.h"
#include "core/render/material.h"
#include "core/render/shading.h"
#include "tests/unit/render_support.h"
#include "tests/unit/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

using namespace specula;
using namespace specula::graph;
using nlohmann::json;

namespace {

constexpr double kPiD = 3.14159265358979323846;

// ---- χ² settings (docs/conformance.md) ----------------------------------------------------------------------------
constexpr int kThetaBins = 10;       // θ about the lobe's pole, quadratically spaced: θ_k = π (k / 10)²
constexpr int kPhiBins = 20;         // φ uniform
constexpr int kQuadRes = 12;         // midpoint quadrature per bin and axis (12 x 12 pdf evaluations)
constexpr int kRefine = 6;           // ... and per axis of a grid cell where the pdf jumps (6 x 6)
constexpr int kSamples = 100000;     // samples per χ² case
constexpr int kPilotSamples = 2000;  // separate pilot samples that choose the pole (their mean direction)
constexpr double kMinExpected = 5;   // bins with a smaller expected count are pooled
constexpr double kSignificance = 0.01;  // family-wise, Šidák-corrected over every χ² case

// ---- the grid -----------------------------------------------------------------------------------------------------

struct Case {
    std::string node;   // node id
    std::string point;  // grid point label
    json inputs;        // literal inputs of the node
    Vec3 wo;            // view direction (world = the node's frame: normal +z, tangent +x)
    std::string view;   // label of wo
    std::string name() const {
        std::string n = node + "__" + point + "__" + view;
        for (char& c : n)
            if (!std::isalnum((unsigned char)c)) c = '_';
        return n;
    }
};

Vec3 dirFromAngles(double thetaDeg, double phiDeg) {
    double t = thetaDeg * kPiD / 180, p = phiDeg * kPiD / 180;
    return glm::normalize(Vec3(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)), float(std::cos(t))));
}
struct View {
    const char* label;
    Vec3 wo;
};
const std::vector<View>& views() {
    static const std::vector<View> v = {{"wo10", dirFromAngles(10, 30)}, {"wo45", dirFromAngles(45, 200)},
                                        {"wo80", dirFromAngles(80, 110)}};  // 80°: the grazing case
    return v;
}

const PortSpec* closureOutput(const NodeSpec& s) {
    for (const PortSpec& o : s.outputs)
        if (o.type == TypeDesc::Closure) return &o;
    return nullptr;
}
bool isBsdfNode(const NodeSpec& s) { return s.category == "bsdf" && closureOutput(s) != nullptr; }

// The documented (typical) range of a numeric port; the hard range, then [-1, 1], where none is documented.
void portRange(const PortSpec& p, float& lo, float& hi) {
    lo = std::isfinite(p.minValue) ? p.minValue : std::isfinite(p.hardMin) ? p.hardMin : -1.f;
    hi = std::isfinite(p.maxValue) ? p.maxValue : std::isfinite(p.hardMax) ? p.hardMax : 1.f;
}

// A literal for the port, rounded to 5 decimals (readable test names and parameters: 0.9, not 0.8999999761581421).
json literal(const PortSpec& p, const float* v) {
    auto r = [](float x) { return std::round(double(x) * 1e5) / 1e5; };
    int w = typeWidth(p.type);
    if (w == 1) return r(v[0]);
    json a = json::array();
    for (int k = 0; k < w; ++k) a.push_back(r(v[k]));
    return a;
}

// Grid points of one node, one factor at a time around the defaults: "defaults"; per numeric port (not bound to the
// geometry: those come from the shading point) the values at 10 % and 90 % of its documented range in every
// component, and for vector ports a mixed point (90 %, 50 %, 10 %); per enum port every non-default value.
// 'needsFile' is set for a node with a free string port (a file) that kFileInputs gives no value: such a node cannot be
// conformance-tested.
// Values of free string ports (files) for the suite, given to every grid point of the node.
struct FileInput {
    const char* node;
    const char* port;
    const char* value;
};
const FileInput kFileInputs[] = {
    // A generated 16² flakes map (no texture store needed); the suite's footprint is far below a texel, so this
    // exercises the level-0 lobes (per-texel base LTCs); the prefiltered levels are tested in test_ltc_prefilter.cpp.
    {"bsdf.ltc_normal_map", "normal_map", "generate:flakes:16:7"},
    // A generated 64² bump map: the suite's footprint is below a texel, so the kernel is clamped to one texel and D is
    // the sum over the few triangles around the shading point (sharp, spiky lobes: a hard case for the χ² binning).
    {"bsdf.glint_pndf", "normal_map", "generate:bumps:16:7"},
};
std::vector<std::pair<std::string, json>> gridPoints(const NodeSpec& s, bool* needsFile = nullptr) {
    std::vector<std::pair<std::string, json>> g = {{"defaults", json::object()}};
    if (needsFile) *needsFile = false;
    json files = json::object();
    for (const PortSpec& p : s.inputs) {
        // The viewer inside a closed object (bsdf.dielectric: the relative IOR inverts, total internal reflection).
        if (p.binding == GeomBinding::FrontFacing) g.push_back({"inside", json{{p.name, 0}}});
        if (p.type == TypeDesc::Closure || p.binding != GeomBinding::None) continue;
        if (p.type == TypeDesc::String) {
            if (p.enumValues.empty()) {
                bool given = false;
                for (const FileInput& f : kFileInputs)
                    if (s.id == f.node && p.name == f.port) files[p.name] = f.value, given = true;
                if (!given && needsFile) *needsFile = true;
                continue;
            }
            for (const std::string& v : p.enumValues)
                if (v != p.defString && !(p.defString.empty() && v == p.enumValues.front()))
                    g.push_back({p.name + "_" + v, json{{p.name, v}}});
            continue;
        }
        float lo, hi;
        portRange(p, lo, hi);
        auto at = [&](float t) { return lo + t * (hi - lo); };
        for (auto [label, t] : {std::pair{"lo", 0.1f}, std::pair{"hi", 0.9f}}) {
            float v[3] = {at(t), at(t), at(t)};
            g.push_back({p.name + "_" + label, json{{p.name, literal(p, v)}}});
        }
        if (typeWidth(p.type) > 1) {
            float v[3] = {at(0.9f), at(0.5f), at(0.1f)};
            g.push_back({p.name + "_mixed", json{{p.name, literal(p, v)}}});
        }
    }
    for (auto& point : g) point.second.update(files);
    return g;
}

// Every grid point with two of the three views (cycling), the defaults with all three.
std::vector<Case> allCases() {
    std::vector<Case> cases;
    for (const NodeSpec* s : NodeRegistry::instance().all()) {
        if (!isBsdfNode(*s) || s->has(kEmissive)) continue;
        bool needsFile = false;
        auto grid = gridPoints(*s, &needsFile);
        if (needsFile) continue;  // reported by LobeRegistry.EveryBsdfNodeIsConformanceTested
        for (size_t k = 0; k < grid.size(); ++k) {
            const int nv = k == 0 ? 3 : 2;
            for (int j = 0; j < nv; ++j) {
                const View& v = views()[(k + j) % 3];
                cases.push_back({s->id, grid[k].first, grid[k].second, v.wo, v.label});
            }
        }
    }
    return cases;
}
// The number of χ² tests (grid points x views): the Šidák correction's family.
size_t caseCount() {
    static const size_t n = allCases().size();
    return n;
}

// ---- shading --------------------------------------------------------------------------------------------------------

// The fixed shading point: the unperturbed frame is the world frame (normal +z, tangent +x), with ray differentials
// (every differential a lobe reads: dp, duv, dn, dwo) so that the footprint-driven lobes filter.
ShadingPoint shadingPoint(const Vec3& wo) {
    ShadingPoint sp = test::shadingPointWithDifferentials(wo, 0.05f);
    sp.dwodx = Vec3(0.002f, 0, 0);
    sp.dwody = Vec3(0, 0.003f, 0);
    return sp;
}

struct Shaded {
    std::shared_ptr<Material> material;
    std::unique_ptr<ScratchArena> arena = std::make_unique<ScratchArena>();
    Closure closure;
};

json materialJson(const std::string& node, const json& inputs) {
    const NodeSpec* s = NodeRegistry::instance().find(node);
    return {{"nodes", {{"n", {{"type", node}, {"inputs", inputs}}}}}, {"output", "@n." + closureOutput(*s)->name}};
}

void shade(const std::string& node, const json& inputs, const Vec3& wo, Shaded& out) {
    out.material = loadGraphMaterial(materialJson(node, inputs), "/materials/x", GraphLoadContext{});
    out.material->shade(shadingPoint(wo), *out.arena, out.closure);
}

// ---- random numbers (bit-reproducible: raw mt19937 output) ------------------------------------------------------------

struct Rng {
    std::mt19937 e;
    explicit Rng(uint32_t seed) : e(seed) {}
    float next() { return float(e() >> 8) * (1.f / 16777216.f); }
    Vec2 next2() {
        float a = next();
        return Vec2(a, next());
    }
};
uint32_t seedOf(const std::string& s) {  // FNV-1a
    uint32_t h = 2166136261u;
    for (char c : s) h = (h ^ uint8_t(c)) * 16777619u;
    return h;
}

BsdfValue query(const Closure& c, const Vec3& wo, const Vec3& wi) { return test::query(c, wo, wi); }

// ---- χ² (pbrt-v4 style) -----------------------------------------------------------------------------------------------

// Regularised upper incomplete gamma Q(a, x) (series / Lentz continued fraction, Numerical Recipes §6.2).
double gammaQ(double a, double x) {
    if (x <= 0) return 1;
    const double lg = -x + a * std::log(x) - std::lgamma(a);
    if (x < a + 1) {
        double ap = a, sum = 1 / a, del = sum;
        for (int n = 0; n < 10000; ++n) {
            ap += 1, del *= x / ap, sum += del;
            if (std::abs(del) < std::abs(sum) * 1e-15) break;
        }
        return std::max(0.0, 1 - sum * std::exp(lg));
    }
    double b = x + 1 - a, c = 1e300, d = 1 / b, h = d;
    for (int i = 1; i < 10000; ++i) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::abs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (std::abs(c) < 1e-300) c = 1e-300;
        d = 1 / d;
        double del = d * c;
        h *= del;
        if (std::abs(del - 1) < 1e-15) break;
    }
    return std::exp(lg) * h;
}

// Spherical binning about a pole: θ bins quadratically spaced (fine near the pole, where a sharp lobe puts its mass),
// φ uniform.
struct Binning {
    Vec3 u, v, p;
    explicit Binning(const Vec3& pole) {
        Frame f = Frame::fromNormal(glm::normalize(pole));
        u = f.t, v = f.b, p = f.n;
    }
    static double thetaEdge(int i) { return kPiD * double(i) * i / (double(kThetaBins) * kThetaBins); }
    int index(const Vec3& w) const {
        double ct = std::clamp(double(glm::dot(w, p)), -1.0, 1.0);
        double th = std::acos(ct);
        int i = std::min(int(kThetaBins * std::sqrt(th / kPiD)), kThetaBins - 1);
        double ph = std::atan2(double(glm::dot(w, v)), double(glm::dot(w, u)));
        if (ph < 0) ph += 2 * kPiD;
        int j = std::min(int(kPhiBins * ph / (2 * kPiD)), kPhiBins - 1);
        return i * kPhiBins + j;
    }
    Vec3 dir(double th, double ph) const {
        double st = std::sin(th);
        return glm::normalize(float(st * std::cos(ph)) * u + float(st * std::sin(ph)) * v + float(std::cos(th)) * p);
    }
};

struct Chi2Result {
    double chi2 = 0, pValue = 1;
    int dof = 0;
    double pdfIntegral = 0, acceptance = 0;
    long strayObserved = 0;  // samples where the pdf is zero
    std::string error;
};

using Sampler = std::function<bool(Rng&, Vec3&)>;  // one sample() call: false if rejected
using PdfFn = std::function<double(const Vec3&)>;

// poleRefine: the refinement of the first θ bin's cells (about the pole), kRefine unless a lobe is known to be sharper.
Chi2Result chi2Test(const Sampler& sample, const PdfFn& pdf, uint32_t seed, int n = kSamples, int poleRefine = kRefine) {
    Chi2Result r;
    // Pole from a separate pilot run (so the binning is independent of the tested samples).
    Rng pilot(seed ^ 0x9e3779b9u);
    Vec3 mean(0.f);
    for (int k = 0; k < kPilotSamples; ++k) {
        Vec3 wi;
        if (sample(pilot, wi)) mean += wi;
    }
    Binning bins(glm::length(mean) > 1e-6f ? mean : Vec3(0, 0, 1));
    std::vector<double> obs(kThetaBins * kPhiBins, 0.0), expct(kThetaBins * kPhiBins, 0.0);
    Rng rng(seed);
    long accepted = 0;
    std::vector<Vec3> samples;
    samples.reserve(n);
    for (int k = 0; k < n; ++k) {
        Vec3 wi;
        if (!sample(rng, wi)) continue;
        ++accepted;
        obs[bins.index(wi)] += 1;
        samples.push_back(wi);
    }
    r.acceptance = double(accepted) / n;
    // Expected counts: n ∫_bin pdf dω by the midpoint rule in (θ, φ) with the sin θ Jacobian on a kQuadRes² grid per
    // bin; a grid cell whose pdf differs from a neighbour's (across bins too) by more than 20 % or in being zero (the
    // horizon cut, a sharp peak) is refined to kRefine² points (poleRefine² in the first θ bin, about the pole).
    const int NI = kThetaBins * kQuadRes, NJ = kPhiBins * kQuadRes;
    const double dp = 2 * kPiD / NJ;
    auto theta0 = [](int I) {
        int i = I / kQuadRes;
        double t0 = Binning::thetaEdge(i), t1 = Binning::thetaEdge(i + 1);
        return std::pair{t0 + (I % kQuadRes) * (t1 - t0) / kQuadRes, (t1 - t0) / kQuadRes};
    };
    std::vector<double> val(size_t(NI) * NJ);
    for (int I = 0; I < NI; ++I) {
        auto [t, dt] = theta0(I);
        for (int J = 0; J < NJ; ++J) val[size_t(I) * NJ + J] = pdf(bins.dir(t + 0.5 * dt, (J + 0.5) * dp));
    }
    auto differs = [](double x, double y) { return (x > 0) != (y > 0) || std::abs(x - y) > 0.2 * std::max(x, y); };
    for (int I = 0; I < NI; ++I) {
        auto [t, dt] = theta0(I);
        for (int J = 0; J < NJ; ++J) {
            double v = val[size_t(I) * NJ + J];
            bool refine = differs(v, val[size_t(I) * NJ + (J + 1) % NJ]) || differs(v, val[size_t(I) * NJ + (J + NJ - 1) % NJ]) ||
                          (I > 0 && differs(v, val[size_t(I - 1) * NJ + J])) ||
                          (I + 1 < NI && differs(v, val[size_t(I + 1) * NJ + J]));
            double sum = 0;
            if (refine) {
                const int k = I < kQuadRes ? poleRefine : kRefine;
                for (int a = 0; a < k; ++a) {
                    double th = t + (a + 0.5) * dt / k, st = std::sin(th);
                    for (int b = 0; b < k; ++b) sum += pdf(bins.dir(th, (J + (b + 0.5) / k) * dp)) * st;
                }
                sum *= dt * dp / (k * k);
            } else {
                sum = v * std::sin(t + 0.5 * dt) * dt * dp;
            }
            expct[(I / kQuadRes) * kPhiBins + J / kQuadRes] += sum * n;
        }
    }
    r.pdfIntegral = std::accumulate(expct.begin(), expct.end(), 0.0) / n;
    // A sample where the pdf is zero is an error in itself; the samples of a cell whose quadrature missed a sliver of
    // support (e.g. a cell cut by the horizon) are checked one by one, then pooled like any other small cell.
    for (const Vec3& wi : samples)
        if (expct[bins.index(wi)] == 0 && !(pdf(wi) > 0)) ++r.strayObserved;
    // Pooling (pbrt-v4 chi2test): sort by expected count, pool the cells below kMinExpected.
    std::vector<int> order(expct.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return expct[a] < expct[b]; });
    double pooledObs = 0, pooledExp = 0;
    for (int idx : order) {
        if (expct[idx] < kMinExpected) {
            pooledObs += obs[idx], pooledExp += expct[idx];
        } else if (pooledExp > 0 && pooledExp < kMinExpected) {
            pooledObs += obs[idx], pooledExp += expct[idx];
        } else {
            double d = obs[idx] - expct[idx];
            r.chi2 += d * d / expct[idx];
            ++r.dof;
        }
    }
    if (pooledExp > 0 || pooledObs > 0) {
        double d = pooledObs - pooledExp;
        r.chi2 += pooledExp > 0 ? d * d / pooledExp : 1e30;
        ++r.dof;
    }
    r.dof -= 1;
    if (r.strayObserved > 0) {
        r.error = std::to_string(r.strayObserved) + " samples where evalPdf() is zero";
        r.pValue = 0;
    } else if (r.dof < 1) {
        r.pValue = 1;  // everything in one cell: nothing to test
    } else {
        r.pValue = gammaQ(0.5 * r.dof, 0.5 * r.chi2);
    }
    return r;
}

double sidakThreshold(size_t tests) { return 1 - std::pow(1 - kSignificance, 1.0 / double(std::max<size_t>(tests, 1))); }

Sampler closureSampler(const Closure& c, const Vec3& wo) {
    return [&c, wo](Rng& rng, Vec3& wi) {
        BsdfSample s;
        float ul = rng.next();
        if (!test::sample(c, wo, ul, rng.next2(), s) || !(s.pdf > 0.f)) return false;
        wi = s.wi;
        return true;
    };
}

// ---- reciprocity declarations ---------------------------------------------------------------------------------------

// Whether a grid point of a node is reciprocal, and the cosine measure of the model: f·cos(wo, wi) / cos(wi) must be
// symmetric. The default (a new lobe) is reciprocal with the geometric cosine wi.z.
struct Reciprocity {
    bool reciprocal = true;
    std::string why;                                        // why not, when not
    std::function<double(const Vec3&)> cosine = [](const Vec3& w) { return double(w.z); };
};
float inputOr(const json& in, const char* name, int k, float def) {
    if (!in.contains(name)) return def;
    const json& v = in[name];
    return v.is_array() ? v[k].get<float>() : v.get<float>();
}
// Lobes that are reciprocal only at one value of an enum port (the others are not, for the reason given).
struct ReciprocalOnlyAt {
    const char* node;
    const char* port;
    const char* value;
    const char* why;
};
const ReciprocalOnlyAt kReciprocalOnlyAt[] = {
    {"bsdf.ggx_filtered", "filter", "none",
     "the filter widens the roughness by the footprint of the half vector, differentiated along the viewer (dwo/dx, "
     "dwo/dy) with wi held fixed: swapping wo and wi changes the filtered roughness"},
    {"bsdf.glint", "ggaa", "off",
     "GGAA convolves the glint NDF with a kernel from the derivative of the half vector along the viewer's footprint, "
     "which is not symmetric in wo and wi"},
};
// Lobes that are never reciprocal.
const ReciprocalOnlyAt kNeverReciprocal[] = {
    {"bsdf.ltc_normal_map", "", "",
     "its lobes are LTCs fitted for the shading view (f·cos = mag·D(wi) for that wo only): swapping wo and wi does not "
     "swap the lobe"},
};
Reciprocity reciprocityOf(const Case& c) {
    Reciprocity r;
    for (const ReciprocalOnlyAt& e : kNeverReciprocal)
        if (c.node == e.node) r.reciprocal = false, r.why = e.why;
    const NodeSpec* spec = NodeRegistry::instance().find(c.node);
    for (const ReciprocalOnlyAt& e : kReciprocalOnlyAt) {
        if (c.node != e.node) continue;
        const PortSpec& port = spec->inputs[spec->inputIndex(e.port)];
        const std::string def = port.defString.empty() ? port.enumValues.front() : port.defString;
        if (c.inputs.value(e.port, def) != e.value) r.reciprocal = false, r.why = e.why;
    }
    if (c.node == "bsdf.beckmann_lean") {
        // Reciprocal with respect to the mean microsurface plane (beckmann_lean.h): the cosine is the projected area of
        // the mean plane per unit of the geometric plane, w.z − w.xy·μ (= w.z for μ = 0).
        float mx = inputOr(c.inputs, "slope", 0, 0.f), my = inputOr(c.inputs, "slope", 1, 0.f);
        r.cosine = [mx, my](const Vec3& w) { return double(w.z) - double(w.x) * mx - double(w.y) * my; };
    }
    return r;
}

// ---- the tests ------------------------------------------------------------------------------------------------------

// A transmitting closure's relative IOR η = n_below / n_above (its transmitting lobes' "eta" parameter); 0 if none.
double transmissionEta(const Closure& cl) {
    for (int i = 0; i < cl.size(); ++i) {
        if (!cl.lobe(i)->transmits()) continue;
        LobeParameters ps;
        cl.lobe(i)->parameters(LobeQuery{}, ps);
        for (auto& [name, v] : ps)
            if (name == "eta" && !v.empty()) return v[0];
    }
    return 0;
}

// χ² of sample() against evalPdf(), ∫ pdf = acceptance rate ≤ 1, and the pdf and f of a sample, for one view.
void checkChi2AndPdfOfSample(const Case& c) {
    Shaded s;
    shade(c.node, c.inputs, c.wo, s);
    ASSERT_FALSE(s.closure.empty()) << c.node << " produced no lobe at " << c.point;
    const Closure& cl = s.closure;
    const uint32_t seed = seedOf(c.name());
    const double alpha = sidakThreshold(caseCount());
    // A transmitting closure is tested per hemisphere, each binned about its own mean direction: its reflected and
    // refracted peaks are far apart, and binning about their common mean would leave both between coarse bins. Each
    // side's ∫ pdf is then that side's share of the samples; together they are the acceptance rate.
    struct Side {
        const char* name;
        int sign;  // +1: wi.z > 0 only, -1: wi.z < 0 only, 0: the whole sphere
    };
    const std::vector<Side> sides = transmissionEta(cl) > 0 ? std::vector<Side>{{"reflection", 1}, {"transmission", -1}}
                                                            : std::vector<Side>{{"", 0}};
    double pdfTotal = 0;
    for (const Side& side : sides) {
        auto on = [&side](const Vec3& w) { return side.sign == 0 || (side.sign > 0 ? w.z > 0.f : w.z < 0.f); };
        const Sampler all = closureSampler(cl, c.wo);
        const Sampler sampler = [&](Rng& rng, Vec3& wi) { return all(rng, wi) && on(wi); };
        // The pole is each side's mean direction: a refracted peak can be far sharper than a reflected one (at α = 0.01
        // and IOR 1.2 it is under 0.1° wide) and lies inside the first θ bin, refined 4x finer for it.
        Chi2Result r = chi2Test(sampler, [&](const Vec3& wi) { return on(wi) ? double(query(cl, c.wo, wi).pdf) : 0.0; },
                                seed + uint32_t(side.sign == 0 ? 0 : side.sign + 2), kSamples, side.sign ? 4 * kRefine : kRefine);
        std::printf("  [chi2] %s%s%s: p = %.4g (chi2 %.1f, dof %d), ∫pdf = %.5f, accepted %.5f\n", c.name().c_str(),
                    side.sign ? " " : "", side.name, r.pValue, r.chi2, r.dof, r.pdfIntegral, r.acceptance);
        SCOPED_TRACE(side.name);
        EXPECT_TRUE(r.error.empty()) << r.error;
        EXPECT_GT(r.pValue, alpha) << "χ² rejects sample() against evalPdf(): chi2 " << r.chi2 << " with " << r.dof
                                   << " dof (Šidák-corrected significance " << alpha << ")";
        // ∫ pdf dω is the acceptance rate of sample() (the pdf is not renormalised over the hemisphere) and ≤ 1.
        const double sigma = std::sqrt(std::max(r.acceptance * (1 - r.acceptance), 1e-6) / kSamples);
        EXPECT_NEAR(r.pdfIntegral, r.acceptance, 4 * sigma + 3e-3);
        pdfTotal += r.pdfIntegral;
    }
    EXPECT_LE(pdfTotal, 1 + 3e-3);

    // pdf of a sample: the sample's pdf and f are those evalPdf gives for its direction.
    Rng rng(seed + 1);
    int checked = 0;
    double worstPdf = 0, worstF = 0;
    for (int k = 0; k < 4000; ++k) {
        BsdfSample bs;
        float ul = rng.next();
        if (!test::sample(cl, c.wo, ul, rng.next2(), bs)) continue;
        BsdfValue v = query(cl, c.wo, bs.wi);
        ++checked;
        double dp = std::abs(double(bs.pdf) - v.pdf) / std::max({double(bs.pdf), double(v.pdf), 1e-20});
        worstPdf = std::max(worstPdf, dp);
        Color3 a = bs.f.total(), b = v.f.total();
        for (int ch = 0; ch < 3; ++ch) {
            double m = std::max({std::abs(double(a[ch])), std::abs(double(b[ch])), 1e-20});
            worstF = std::max(worstF, std::abs(double(a[ch]) - b[ch]) / m);
        }
        Color3 ad = bs.f.diffuse - v.f.diffuse, as = bs.f.specular - v.f.specular;
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_LE(std::abs(ad[ch]), 1e-4f * std::max(std::abs(v.f.diffuse[ch]), 1e-20f)) << "diffuse part, sample " << k;
            EXPECT_LE(std::abs(as[ch]), 1e-4f * std::max(std::abs(v.f.specular[ch]), 1e-20f)) << "specular part, sample " << k;
        }
    }
    EXPECT_LE(worstPdf, 1e-4) << "BsdfSample.pdf differs from evalPdf(wo, wi).pdf";
    EXPECT_LE(worstF, 1e-4) << "BsdfSample.f differs from evalPdf(wo, wi).f";
    if (pdfTotal > 0.01) EXPECT_GT(checked, 0);
}

// Polygon queries (LTC quad lights), for closures whose lobes integrate polygons: the integral is additive over a split
// of the light, zero seen from behind (one-sided), and each lobe's polygon samples (the shadow-ray directions) fall
// in the sub-quads in proportion to its sub-integrals (χ², 3 dof) and always inside the light.
// Lobes whose polygon integral is a quadrature, not a closed form: additivity holds to their integration error.
struct ApproximatePolygonIntegral {
    const char* node;
    float additivity;
    const char* why;
};
const ApproximatePolygonIntegral kApproximatePolygonIntegrals[] = {
    {"bsdf.glint", 2e-3f,
     "the light's edges map to curves in half-slope space, split into chords to 1e-4 (M^-1 space), and the smooth "
     "factor G (wo.h)/(h_z wo.z) is taken per piece: a split light is chorded and pieced differently (measured 8e-4)"},
};

void checkPolygonQueries(const Case& c) {
    float additivity = 2e-4f;
    for (const auto& e : kApproximatePolygonIntegrals)
        if (c.node == e.node) additivity = e.additivity;
    Shaded s;
    shade(c.node, c.inputs, c.wo, s);
    const Closure& cl = s.closure;
    // A tilted quad above the shading point, counter-clockwise seen from it; offsets from the shading point.
    const Vec3 o(-0.5f, -0.3f, 1.1f), e1(1.1f, 0.2f, 0.f), e2(-0.1f, 0.8f, 0.25f);
    auto quad = [&](float s0, float s1, float t0, float t1) {
        std::array<Vec3, 4> q = {o + e1 * s0 + e2 * t0, o + e1 * s1 + e2 * t0, o + e1 * s1 + e2 * t1, o + e1 * s0 + e2 * t1};
        if (glm::dot(glm::cross(q[1] - q[0], q[2] - q[0]), q[0]) < 0.f) std::swap(q[1], q[3]);
        return q;
    };
    BsdfQuery q;
    q.wo = c.wo;
    auto whole = quad(0, 1, 0, 1);
    BsdfEval all;
    std::array<Color3, Closure::kMaxLobes> perLobe{};
    const LobeMask mask = cl.integratePolygon(q, whole.data(), 4, all, perLobe.data());
    if (mask == 0) return;  // no lobe has a closed form: the renderer samples this closure
    for (int ch = 0; ch < 3; ++ch) EXPECT_GE(all.total()[ch], 0.f);
    std::array<Vec3, 4> back = {whole[0], whole[3], whole[2], whole[1]};
    BsdfEval behind;
    cl.integratePolygon(q, back.data(), 4, behind);
    EXPECT_EQ(maxComponent(behind.total()), 0.f) << "a one-sided light seen from behind";
    std::array<std::array<Vec3, 4>, 4> sub = {quad(0, .5f, 0, .5f), quad(.5f, 1, 0, .5f), quad(0, .5f, .5f, 1), quad(.5f, 1, .5f, 1)};
    std::array<std::array<Color3, Closure::kMaxLobes>, 4> subLobe{};
    BsdfEval sum;
    for (int k = 0; k < 4; ++k) cl.integratePolygon(q, sub[k].data(), 4, sum, subLobe[k].data());
    for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(sum.total()[ch], all.total()[ch], additivity * std::max(all.total()[ch], 1e-3f)) << "additivity";
    auto inside = [](const Vec3& w, const std::array<Vec3, 4>& v) {
        Vec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
        float den = glm::dot(w, n);
        if (den == 0.f) return false;
        float t = glm::dot(v[0], n) / den;
        if (t <= 0.f) return false;
        Vec3 p = w * t;
        for (int i = 0; i < 4; ++i)
            if (glm::dot(glm::cross(v[(i + 1) % 4] - v[i], p - v[i]), n) < -1e-5f * glm::length(n)) return false;
        return true;
    };
    Rng rng(seedOf(c.name()) + 11);
    for (int j = 0; j < cl.size(); ++j) {
        if (!((mask >> j) & 1) || maxComponent(perLobe[j]) <= 0.f) continue;
        const int n = 4000;
        std::array<int, 4> count{};
        int outside = 0, failed = 0;
        for (int i = 0; i < n; ++i) {
            Vec3 w;
            if (!cl.samplePolygon(q, j, whole.data(), 4, rng.next2(), uint64_t(i) * 0x9E3779B97F4A7C15ULL + 1, w)) {
                ++failed;
                continue;
            }
            int hit = -1;
            for (int k = 0; k < 4 && hit < 0; ++k)
                if (inside(w, sub[k])) hit = k;
            if (hit < 0) ++outside;
            else ++count[hit];
        }
        EXPECT_EQ(failed, 0) << "lobe " << j;
        EXPECT_LE(outside, n / 500) << "lobe " << j << ": polygon samples outside the light";
        double total = 0, chi2 = 0;
        for (int k = 0; k < 4; ++k) total += luminance(subLobe[k][j]);
        int used = n - failed - outside;
        for (int k = 0; k < 4; ++k) {
            double e = luminance(subLobe[k][j]) / total * used;
            if (e > 0) chi2 += (count[k] - e) * (count[k] - e) / e;
        }
        EXPECT_LT(chi2, 25.0) << "lobe " << j << ": polygon samples do not follow the lobe's polygon integral (3 dof)";
    }
}

// The projected area of the plane a one-lobe closure models per unit of the geometric plane's, seen from wo: 1, or for a
// lobe with the parameter "plane_slope" μ (in its frame, slope = -n.xy / n.z) (wo.z - wo.xy . μ) / wo.z.
double planeAreaRatio(const Closure& cl, const Vec3& woWorld) {
    if (cl.size() != 1) return 1.0;
    const Vec3 wo = cl.frame(0).toLocal(woWorld);
    LobeParameters params;
    cl.lobe(0)->parameters(LobeQuery{wo, wo}, params);
    for (const auto& [name, v] : params)
        if (name == "plane_slope" && v.size() == 2 && wo.z > 0.f) {
            const double ratio = (double(wo.z) - double(wo.x) * v[0] - double(wo.y) * v[1]) / double(wo.z);
            return std::max(ratio, 1.0);  // a plane tilted away bounds nothing tighter than the geometric one
        }
    return 1.0;
}

// Energy ≤ 1 and, where the model is reciprocal, reciprocity, for one view. A transmitting closure scatters over the
// whole sphere: its refracted radiance carries the factor (n_wo / n_wi)² (radiance is compressed entering a denser
// medium), so energy is checked on flux, f·cos·(n_wi / n_wo)², and reciprocity in its generalised form
// f(a, b) / n_a² = f(b, a) / n_b² (Veach 1997, §5.2), n being the index of each direction's side.
void checkReciprocityAndEnergy(const Case& c) {
    Shaded s;
    shade(c.node, c.inputs, c.wo, s);
    ASSERT_FALSE(s.closure.empty());
    const Closure& cl = s.closure;
    Rng rng(seedOf(c.name()) + 7);
    const double eta = transmissionEta(cl);  // 0: reflection only
    auto index = [eta](const Vec3& w) { return eta > 0 && w.z < 0.f ? eta : 1.0; };  // n of w's side (above: 1)

    // Energy: ∫ f cos dωi ≤ 1 per channel, importance-sampled (f·cos / pdf, zero for rejected samples).
    const int n = 50000;
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    for (int k = 0; k < n; ++k) {
        BsdfSample bs;
        float ul = rng.next();
        if (!test::sample(cl, c.wo, ul, rng.next2(), bs) || !(bs.pdf > 0.f)) continue;
        Color3 w = bs.f.total() / bs.pdf * float(sqr(index(bs.wi) / index(c.wo)));
        for (int ch = 0; ch < 3; ++ch) sum[ch] += w[ch], sum2[ch] += double(w[ch]) * w[ch];
    }
    // A lobe that models a tilted plane (LobeParameters "plane_slope": bsdf.glint's platelets at close range) receives
    // and reflects with that plane's projected area, (wo.z - wo.xy . slope) per unit of the geometric plane's wo.z: its
    // albedo is bounded by that ratio, as a normal-mapped lobe's is by its shading normal's.
    const double area = planeAreaRatio(cl, c.wo);
    double worstE = 0, worstSe = 0;
    for (int ch = 0; ch < 3; ++ch) {
        double m = sum[ch] / n / area, var = std::max(sum2[ch] / n / (area * area) - m * m, 0.0), se = std::sqrt(var / n);
        EXPECT_LE(m, 1 + 4 * se + 1e-3) << "albedo of channel " << ch << " exceeds 1 (standard error " << se << ")";
        if (m > worstE) worstE = m, worstSe = se;
    }

    // Reciprocity: f·cos(a, b) / cos(b) == f·cos(b, a) / cos(a), over pairs (wo, sampled wi) and uniform pairs.
    Reciprocity rec = reciprocityOf(c);
    double worstRel = 0;
    int pairs = 0, nonZero = 0;  // pairs tested, pairs where f is not ~0
    if (rec.reciprocal) {
        for (int k = 0; k < 3000; ++k) {
            Vec3 a = c.wo, b;
            if (k % 3 == 2) {  // uniform pair over the upper hemisphere (the sphere for a transmitting closure)
                auto hemi = [&] {
                    float z = eta > 0 ? 2 * rng.next() - 1 : rng.next(), ph = 2 * kPi * rng.next(),
                          r = std::sqrt(std::max(0.f, 1 - z * z));
                    return Vec3(r * std::cos(ph), r * std::sin(ph), z);
                };
                a = hemi(), b = hemi();
            } else {
                BsdfSample bs;
                float ul = rng.next();
                if (!test::sample(cl, c.wo, ul, rng.next2(), bs)) continue;
                b = bs.wi;
            }
            double ca = rec.cosine(a), cb = rec.cosine(b);
            if (eta > 0) ca = std::abs(ca), cb = std::abs(cb);
            if (ca < 1e-3 || cb < 1e-3) continue;
            Color3 fab = query(cl, a, b).f.total(), fba = query(cl, b, a).f.total();
            const double na2 = sqr(index(a)), nb2 = sqr(index(b));
            bool any = false;
            for (int ch = 0; ch < 3; ++ch) {
                double x = fab[ch] / cb / na2, y = fba[ch] / ca / nb2, m = std::max(std::abs(x), std::abs(y));
                if (m < 1e-6) continue;
                any = true;
                worstRel = std::max(worstRel, std::abs(x - y) / m);
            }
            ++pairs;
            nonZero += any;
        }
        EXPECT_GT(pairs, 100);
        EXPECT_GT(nonZero, 20) << "reciprocity tested only where f vanishes";
        EXPECT_LE(worstRel, 2e-3) << "f(wo, wi)/cos θi != f(wi, wo)/cos θo";
    }
    std::printf("  [energy] %s: max albedo %.4f (± %.4f); reciprocity %s\n", c.name().c_str(), worstE, worstSe,
                rec.reciprocal ? ("worst relative difference " + std::to_string(worstRel) + " over " + std::to_string(pairs) +
                                  " pairs (" + std::to_string(nonZero) + " with f > 0)").c_str()
                               : ("not reciprocal: " + rec.why).c_str());
}

// One test per node and grid point (its views inside: one process per grid point under ctest, whose start-up
// dominates otherwise), named node__point; a failure names the view and the property.
struct GridCase {
    std::vector<Case> views;
    std::string name() const {
        std::string n = views.front().node + "__" + views.front().point;
        for (char& c : n)
            if (!std::isalnum((unsigned char)c)) c = '_';
        return n;
    }
};
std::vector<GridCase> allGridCases() {
    std::vector<GridCase> g;
    for (const Case& c : allCases()) {
        if (g.empty() || g.back().views.front().node != c.node || g.back().views.front().point != c.point) g.push_back({});
        g.back().views.push_back(c);
    }
    return g;
}
void PrintTo(const GridCase& g, std::ostream* os) { *os << g.name() << " inputs " << g.views.front().inputs.dump(); }

class LobeConformance : public ::testing::TestWithParam<GridCase> {};

TEST_P(LobeConformance, Conforms) {
    for (const Case& c : GetParam().views) {
        SCOPED_TRACE("view " + c.view);
        {
            SCOPED_TRACE("chi2 / pdf of sample");
            checkChi2AndPdfOfSample(c);
        }
        {
            SCOPED_TRACE("reciprocity / energy");
            checkReciprocityAndEnergy(c);
        }
        {
            SCOPED_TRACE("polygon queries");
            checkPolygonQueries(c);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Registry, LobeConformance, ::testing::ValuesIn(allGridCases()),
                         [](const ::testing::TestParamInfo<GridCase>& info) { return info.param.name(); });

// ---- registry-level checks ------------------------------------------------------------------------------------------

TEST(LobeConformanceRegistry, EveryBsdfNodeIsConformanceTested) {
    std::vector<Case> cases = allCases();
    int lobes = 0;
    for (const NodeSpec* s : NodeRegistry::instance().all()) {
        if (!isBsdfNode(*s)) continue;
        SCOPED_TRACE(s->id);
        bool needsFile = false;
        const auto grid = gridPoints(*s, &needsFile);
        EXPECT_FALSE(needsFile) << "a BSDF node with a free string (file) port: give the suite a test file for it (kFileInputs)";
        if (needsFile) continue;
        Shaded sh;
        shade(s->id, grid[0].second, views()[1].wo, sh);  // the defaults (with the kFileInputs values)
        if (s->has(kEmissive)) {
            // bsdf.emission scatters nothing: its closure is empty, so it has no lobe to test.
            EXPECT_TRUE(sh.closure.empty()) << "an emissive bsdf node that also scatters: remove it from this branch";
            continue;
        }
        EXPECT_FALSE(sh.closure.empty()) << "no lobe at the defaults";
        int n = int(std::count_if(cases.begin(), cases.end(), [&](const Case& c) { return c.node == s->id; }));
        EXPECT_GE(n, 3) << "no conformance cases";
        ++lobes;
    }
    EXPECT_GE(lobes, 5);  // diffuse, ggx, ggx_filtered, beckmann_lean, glint at the time of writing
    std::printf("  %zu conformance cases (grid point x view) in %zu tests over %d lobes; Šidák threshold %.3g\n",
                cases.size(), allGridCases().size(), lobes, sidakThreshold(caseCount()));
}

// CPU against GLSL is tests/glsl/test_glsl_parity.cpp: it runs GlslParity/NodeMatchesCpu for every registered node id.
// Here: every BSDF node has the GLSL twin that test needs, and that test still enumerates the whole registry.
TEST(LobeConformanceRegistry, EveryBsdfNodeIsCoveredByGlslParity) {
    const std::string parity = test::readFile(test::sourcePath("tests/glsl/test_glsl_parity.cpp"));
    EXPECT_NE(parity.find("NodeRegistry::instance().ids()"), std::string::npos)
        << "test_glsl_parity.cpp no longer instantiates over every registered node";
    EXPECT_NE(parity.find("INSTANTIATE_TEST_SUITE_P(AllNodes, GlslParity"), std::string::npos);
    for (const NodeSpec* s : NodeRegistry::instance().all()) {
        if (!isBsdfNode(*s)) continue;
        SCOPED_TRACE(s->id);
        EXPECT_FALSE(s->glslFunction.empty());
        EXPECT_FALSE(s->glslFile.empty());
        ASSERT_NE(s->glslSource(), nullptr) << "missing embedded " << s->glslFile;
        EXPECT_NE(s->glslSource()->find(s->glslFunction + "("), std::string::npos);
        // No id-based exclusion of this node in the parity harness.
        EXPECT_EQ(parity.find("\"" + s->id + "\") continue"), std::string::npos);
    }
}

// ---- self-checks: the tests can fail --------------------------------------------------------------------------------

// Samples cos θ (Malley) but reports the pdf of cos^k θ (k ≠ 1: wrong, though a valid density): χ² must reject it.
class MismatchedLobe final : public BsdfLobe {
public:
    explicit MismatchedLobe(float k) : k_(k) {}
    LobeKind kind() const override { return LobeKind::Diffuse; }
    using BsdfLobe::sample;
    LobeValue evalPdf(const LobeQuery& q) const override {
        LobeValue v;
        if (q.wo.z <= 0 || q.wi.z <= 0) return v;
        v.pdf = (k_ + 1) / (2 * kPi) * std::pow(q.wi.z, k_);
        v.f = Color3(q.wi.z / kPi);
        return v;
    }
    bool sample(const LobeQuery& q, const Vec2& u, Vec3& wi) const override {
        if (q.wo.z <= 0) return false;
        float r = std::sqrt(u.x), ph = 2 * kPi * u.y;
        wi = Vec3(r * std::cos(ph), r * std::sin(ph), std::sqrt(std::max(0.f, 1 - u.x)));
        return true;
    }
    Color3 albedo(const Vec3&) const override { return Color3(1.f); }
    const char* modelName() const override { return "mismatched_test_lobe"; }

private:
    float k_;
};

Chi2Result testLobe(const BsdfLobe& lobe, const Vec3& wo) {
    Closure cl;
    cl.add(Color3(1.f), &lobe, Frame());
    return chi2Test(closureSampler(cl, wo), [&](const Vec3& wi) { return double(query(cl, wo, wi).pdf); }, 12345u);
}

TEST(LobeConformanceSelfCheck, Chi2RejectsAWrongPdf) {
    const Vec3 wo = dirFromAngles(30, 0);
    MismatchedLobe right(1.f), wrong(1.1f);
    Chi2Result ok = testLobe(right, wo), bad = testLobe(wrong, wo);
    std::printf("  matching pdf: p = %.4g (chi2 %.1f, dof %d); cos^1.1 pdf for cos samples: p = %.4g (chi2 %.1f)\n",
                ok.pValue, ok.chi2, ok.dof, bad.pValue, bad.chi2);
    EXPECT_GT(ok.pValue, sidakThreshold(caseCount()));
    EXPECT_NEAR(ok.pdfIntegral, 1.0, 2e-3);
    EXPECT_LT(bad.pValue, 1e-6) << "the χ² test cannot tell a 10 % wrong exponent";
}

TEST(LobeConformanceSelfCheck, PdfIntegralDetectsRejectedSamples) {
    // A sampler that rejects half its samples while the pdf says it accepts all: ∫ pdf != acceptance rate.
    MismatchedLobe right(1.f);
    Closure cl;
    cl.add(Color3(1.f), &right, Frame());
    const Vec3 wo = dirFromAngles(30, 0);
    Sampler half = [&](Rng& rng, Vec3& wi) {
        BsdfSample s;
        float ul = rng.next();
        Vec2 u = rng.next2();
        if (u.y >= 0.5f) return false;
        if (!test::sample(cl, wo, ul, u, s)) return false;
        wi = s.wi;
        return true;
    };
    Chi2Result r = chi2Test(half, [&](const Vec3& wi) { return double(query(cl, wo, wi).pdf); }, 99u);
    EXPECT_NEAR(r.acceptance, 0.5, 0.01);
    EXPECT_NEAR(r.pdfIntegral, 1.0, 2e-3);
    EXPECT_LT(r.pValue, 1e-6);
}

TEST(LobeConformanceSelfCheck, GammaQMatchesKnownValues) {
    EXPECT_NEAR(gammaQ(0.5, 0.5 * 3.841458820694124), 0.05, 1e-9);   // χ²(1): 95 % quantile
    EXPECT_NEAR(gammaQ(5.0, 0.5 * 23.209251158954356), 0.01, 1e-9);  // χ²(10): 99 % quantile
    EXPECT_NEAR(gammaQ(100.0, 0.5 * 200.0), 0.4867, 1e-3);          // χ²(200) at its mean
}

}  // namespace
