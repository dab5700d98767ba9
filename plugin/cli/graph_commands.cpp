// Implementation of `specula glsl`, `specula bsdf` and `specula plot`: they read only the "materials"
// object (name -> graph) of a scene JSON file.
#include "plugin/cli/graph_commands.h"

#include "core/codegen/glsl_emitter.h"
#include "core/color/color_config.h"
#include "core/graph/closure_util.h"
#include "core/graph/graph_material.h"
#include "core/io/image_io.h"
#include "core/render/lobes/ggx.h"
#include "core/texture/texture_store.h"
#include "core/util/error.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

namespace specula {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct Loaded {
    json material;
    std::string name, pointer, baseDir;
};

Loaded readMaterial(const std::string& file, const std::string& wanted) {
    std::ifstream in(file);
    if (!in) throw IoError("cannot read '" + file + "'");
    json scene;
    try {
        in >> scene;
    } catch (const json::exception& e) {
        throw InputError("", std::string("invalid JSON: ") + e.what());
    }
    if (!scene.is_object() || !scene.contains("materials") || !scene["materials"].is_object())
        throw InputError("/materials", "the file has no \"materials\" object");
    const json& mats = scene["materials"];
    std::vector<std::string> names;
    for (auto it = mats.begin(); it != mats.end(); ++it) names.push_back(it.key());
    Loaded r;
    if (wanted.empty()) {
        if (mats.size() != 1) {
            std::string list;
            for (auto& n : names) list += (list.empty() ? "" : ", ") + n;
            throw UsageError("the file has " + std::to_string(mats.size()) + " materials; choose one with --material (" + list + ")");
        }
        r.name = names.front();
    } else {
        if (!mats.contains(wanted)) throw InputError("/materials/" + pointerEscape(wanted), "no material '" + wanted + "'", nearestName(wanted, names));
        r.name = wanted;
    }
    r.material = mats[r.name];
    r.pointer = "/materials/" + pointerEscape(r.name);
    r.baseDir = fs::absolute(fs::path(file)).parent_path().string();
    return r;
}

Vec3 parseVec3(const std::string& s, const char* what) {
    Vec3 v;
    char c1, c2;
    std::istringstream in(s);
    if (!(in >> v.x >> c1 >> v.y >> c2 >> v.z) || c1 != ',' || c2 != ',') throw UsageError(std::string(what) + " expects X,Y,Z");
    return v;
}
Vec2 parseVec2(const std::string& s, const char* what) {
    Vec2 v;
    char c;
    std::istringstream in(s);
    if (!(in >> v.x >> c >> v.y) || c != ',') throw UsageError(std::string(what) + " expects A,B");
    return v;
}

// The graph material plus the texture store it samples from.
struct MaterialInstance {
    std::shared_ptr<TextureStore> textures;
    std::shared_ptr<Material> material;
};
MaterialInstance instantiate(const Loaded& l) {
    MaterialInstance m;
    try {
        m.textures = std::make_shared<TextureStore>(ColorConfig::load("builtin"));
    } catch (const std::exception&) {
        m.textures.reset();  // graphs without texture.image still work
    }
    m.material = loadGraphMaterial(l.material, l.pointer, GraphLoadContext{m.textures.get(), l.baseDir});
    return m;
}

ShadingPoint localPoint(Vec2 uv, Vec2 dx, Vec2 dy, const Vec3& wo) {
    ShadingPoint sp;
    sp.n = sp.ng = Vec3(0, 0, 1);
    sp.tangent = Vec4(1, 0, 0, 1);
    sp.frame = Frame();
    sp.uv = uv;
    sp.duvdx = dx;
    sp.duvdy = dy;
    sp.hasDifferentials = dx != Vec2(0.f) || dy != Vec2(0.f);
    sp.wo = wo;
    return sp;
}

int run(const std::function<void()>& body) {
    try {
        body();
        return kExitOk;
    } catch (const UsageError& e) {
        std::fprintf(stderr, "specula: error: %s\n", e.what());
        return kExitUsage;
    } catch (const InputError& e) {
        std::fprintf(stderr, "specula: error: %s\n", e.what());
        return kExitBadInput;
    } catch (const IoError& e) {
        std::fprintf(stderr, "specula: error: %s\n", e.what());
        return kExitIo;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "specula: error: %s\n", e.what());
        return kExitBadInput;
    }
}

// Perceptually ordered false colour (polynomial fit of matplotlib's viridis, t in [0,1]).
Vec3 falseColour(float t) {
    t = std::clamp(t, 0.f, 1.f);
    const Vec3 c0(0.2777f, 0.0054f, 0.3341f), c1(0.1051f, 1.4046f, 1.3846f), c2(-0.3309f, 0.2148f, 0.0951f),
        c3(-4.6342f, -5.7991f, -19.3324f), c4(6.2283f, 14.1799f, 56.6906f), c5(4.7764f, -13.7451f, -65.3530f),
        c6(-5.4355f, 4.6459f, 26.3124f);
    return glm::clamp(c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6))))), Vec3(0.f), Vec3(1.f));
}

// The first GGX lobe of a closure, if any.
const GgxLobe* findGgx(const Closure& c) {
    for (int i = 0; i < c.size(); ++i)
        if (auto* g = dynamic_cast<const GgxLobe*>(c.lobe(i))) return g;
    return nullptr;
}

}  // namespace

void addGraphCommands(CLI::App& app, int& exitCode) {
    // ---- specula glsl ----
    auto* glsl = app.add_subcommand("glsl", "Write the GLSL 4.50 module of a graph material");
    auto gFile = std::make_shared<std::string>(), gMat = std::make_shared<std::string>(), gOut = std::make_shared<std::string>();
    auto gInline = std::make_shared<bool>(false);
    glsl->add_option("file", *gFile, "scene or material-library JSON")->required();
    glsl->add_option("--material", *gMat, "material name (needed when the file has several)");
    glsl->add_option("-o,--output", *gOut, "output .glsl file")->required();
    glsl->add_flag("--inline-literals", *gInline, "emit literals as constants instead of a uniform block");
    glsl->callback([=, &exitCode] {
        exitCode = run([&] {
            Loaded l = readMaterial(*gFile, *gMat);
            graph::GraphDesc g = graph::parseGraph(l.material, l.pointer);
            codegen::GlslOptions opt;
            opt.materialName = l.name;
            opt.literalsAsUniforms = !*gInline;
            codegen::GlslModule m = codegen::emitGlsl(g, opt);
            std::ofstream out(*gOut);
            if (!(out << m.source)) throw IoError("cannot write '" + *gOut + "'");
        });
    });

    // ---- specula bsdf ----
    auto* bsdf = app.add_subcommand("bsdf", "Evaluate a graph material's f·cos and pdf for one direction pair");
    struct BsdfArgs {
        std::string file, material, wo, wi, uv = "0.5,0.5", dx = "0,0", dy = "0,0";
    };
    auto b = std::make_shared<BsdfArgs>();
    bsdf->add_option("file", b->file, "scene or material-library JSON")->required();
    bsdf->add_option("--material", b->material, "material name");
    bsdf->add_option("--wo", b->wo, "outgoing direction X,Y,Z (local frame, z = normal)")->required();
    bsdf->add_option("--wi", b->wi, "incident direction X,Y,Z (local frame, z = normal)")->required();
    bsdf->add_option("--uv", b->uv, "texture coordinates U,V (default 0.5,0.5)");
    bsdf->add_option("--duvdx", b->dx, "footprint d(uv)/dx A,B (default 0,0)");
    bsdf->add_option("--duvdy", b->dy, "footprint d(uv)/dy C,D (default 0,0)");
    bsdf->callback([=, &exitCode] {
        exitCode = run([&] {
            Vec3 wo = glm::normalize(parseVec3(b->wo, "--wo")), wi = glm::normalize(parseVec3(b->wi, "--wi"));
            Loaded l = readMaterial(b->file, b->material);
            MaterialInstance mi = instantiate(l);
            ShadingPoint sp = localPoint(parseVec2(b->uv, "--uv"), parseVec2(b->dx, "--duvdx"), parseVec2(b->dy, "--duvdy"), wo);
            ScratchArena arena;
            Closure cl;
            mi.material->shade(sp, arena, cl);
            BsdfQuery q;
            q.wo = wo;
            q.wi = wi;
            BsdfValue v = cl.evalPdf(q);
            Color3 f = v.f.total();
            json j = {{"f", {f.x, f.y, f.z}}, {"pdf", v.pdf}};
            std::printf("%s\n", j.dump().c_str());
        });
    });

    // ---- specula plot ----
    auto* plot = app.add_subcommand("plot", "Plot a material's lobe (f·cos over the projected hemisphere) and its GGX slope-space NDF");
    struct PlotArgs {
        std::string file, material, wo, out;
        int size = 256;
    };
    auto p = std::make_shared<PlotArgs>();
    plot->add_option("file", p->file, "scene or material-library JSON")->required();
    plot->add_option("--material", p->material, "material name");
    plot->add_option("--wo", p->wo, "outgoing direction X,Y,Z (local frame, z = normal)")->required();
    plot->add_option("-o,--output", p->out, "output image (PNG)")->required();
    plot->add_option("--size", p->size, "panel size in pixels (default 256)");
    plot->callback([=, &exitCode] {
        exitCode = run([&] {
            Vec3 wo = glm::normalize(parseVec3(p->wo, "--wo"));
            if (p->size < 16 || p->size > 4096) throw UsageError("--size must be in [16, 4096]");
            Loaded l = readMaterial(p->file, p->material);
            MaterialInstance mi = instantiate(l);
            ShadingPoint sp = localPoint(Vec2(0.5f), Vec2(0.f), Vec2(0.f), wo);
            ScratchArena arena;
            Closure cl;
            mi.material->shade(sp, arena, cl);
            const int S = p->size, bar = 16, gap = 8, W = 2 * S + gap, H = S + gap + bar;
            std::vector<float> lobe(size_t(S) * S, -1.f), ndf(size_t(S) * S, -1.f);
            float lobeMax = 0.f, ndfMax = 0.f;
            const GgxLobe* g = findGgx(cl);
            float range = g ? std::clamp(3.f * std::max(g->alphaX(), g->alphaY()), 0.05f, 4.f) : 1.f;
            for (int y = 0; y < S; ++y)
                for (int x = 0; x < S; ++x) {
                    float u = (x + 0.5f) / S * 2.f - 1.f, v = 1.f - (y + 0.5f) / S * 2.f;
                    if (u * u + v * v < 1.f) {  // projected hemisphere: wi = (u, v, sqrt(1 - u² - v²))
                        Vec3 wi(u, v, std::sqrt(1.f - u * u - v * v));
                        BsdfQuery q;
                        q.wo = wo;
                        q.wi = wi;
                        float val = luminance(cl.evalPdf(q).f.total());
                        lobe[size_t(y) * S + x] = val;
                        lobeMax = std::max(lobeMax, val);
                    }
                    if (g) {  // slope space: P22(x̃, ỹ) = D(m) cos⁴θm with m = normalize(−x̃, −ỹ, 1) (Heitz 2014, Eq. 10)
                        Vec3 m = glm::normalize(Vec3(-u * range, -v * range, 1.f));
                        float val = ggx::ndf(m, g->alphaX(), g->alphaY()) * std::pow(m.z, 4.f);
                        ndf[size_t(y) * S + x] = val;
                        ndfMax = std::max(ndfMax, val);
                    }
                }
            std::vector<float> img(size_t(W) * H * 3, 0.f);
            auto put = [&](int x, int y, Vec3 c) { std::copy(&c.x, &c.x + 3, &img[(size_t(y) * W + x) * 3]); };
            for (int y = 0; y < S; ++y)
                for (int x = 0; x < S; ++x) {
                    float a = lobe[size_t(y) * S + x], b = ndf[size_t(y) * S + x];
                    put(x, y, a < 0.f ? Vec3(0.15f) : falseColour(lobeMax > 0.f ? a / lobeMax : 0.f));
                    put(S + gap + x, y, b < 0.f ? Vec3(0.15f) : falseColour(ndfMax > 0.f ? b / ndfMax : 0.f));
                }
            for (int y = S + gap; y < H; ++y)
                for (int x = 0; x < S; ++x) {
                    Vec3 c = falseColour(float(x) / (S - 1));
                    put(x, y, c);
                    if (g) put(S + gap + x, y, c);
                }
            std::ostringstream desc;
            desc << "specula plot: left = luminance of f*cos over the projected hemisphere (0.." << lobeMax
                 << "), right = GGX slope-space NDF P22 over slopes [-" << range << "," << range << "]^2 (0.." << ndfMax
                 << "); colour bars below map 0..max";
            writeImage8(p->out, W, H, 3, img.data(), desc.str());  // via libspecula's lazily loaded image I/O
            json j = {{"lobe_max", lobeMax}, {"ndf_max", ndfMax}, {"slope_range", g ? range : 0.f}, {"has_ggx", g != nullptr}};
            std::printf("%s\n", j.dump().c_str());
        });
    });
}

}  // namespace specula
