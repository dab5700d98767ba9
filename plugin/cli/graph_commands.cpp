// Implementation of `specula glsl`, `specula bsdf` and `specula plot`: they read only the "materials"
// object (name -> graph) of a scene JSON file.
#include "plugin/cli/graph_commands.h"

#include <cstdio>

#include "core/api/specula.h"
#include "core/codegen/glsl_emitter.h"
#include "core/codegen/glsl_manifest.h"
#include "core/color/color_config.h"
#include "core/graph/closure_util.h"
#include "core/graph/graph_material.h"
#include "core/io/image_io.h"
#include "core/scene/scene_loader.h"
#include "core/render/lobes/ggx.h"
#include "core/texture/texture_store.h"
#include "plugin/cli/cli_options.h"
#include "plugin/cli/cli_output.h"
#include "core/util/error.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

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

// The file is read as the scene loader reads it: at most 256 MiB, strict JSON (no key twice, nesting bounded).
Loaded readMaterial(const std::string& file, const std::string& wanted) {
    const json scene = parseStrictJson(readJsonText(file), file);
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
    if (!(in >> v.x >> c1 >> v.y >> c2 >> v.z) || c1 != ',' || c2 != ',' || !(in >> std::ws).eof() || !isFinite(v))
        throw UsageError(std::string(what) + " expects X,Y,Z (three finite numbers)");
    return v;
}
// A direction: parseVec3, non-zero, normalised.
Vec3 parseDirection(const std::string& s, const char* what) {
    const Vec3 v = parseVec3(s, what);
    if (!(glm::dot(v, v) > 0.f)) throw UsageError(std::string(what) + " must be a non-zero direction, got " + s);
    return glm::normalize(v);
}
Vec2 parseVec2(const std::string& s, const char* what) {
    Vec2 v;
    char c;
    std::istringstream in(s);
    if (!(in >> v.x >> c >> v.y) || c != ',' || !(in >> std::ws).eof() || !std::isfinite(v.x) || !std::isfinite(v.y))
        throw UsageError(std::string(what) + " expects A,B (two finite numbers)");
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
    } catch (const Error& e) {  // libspecula's policies (core/api/specula.h) carry their own code
        std::fprintf(stderr, "specula: error: %s\n", e.what());
        return e.exitCode();
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

// A 3x5 pixel font for numbers (digits, '.', 'e', '+', '-'), drawn at 2x in white: the colour bars' labels when no
// font is installed for drawText (core/io/image_io.h).
void drawDigits(std::vector<float>& img, int W, int H, int x0, int y0, const std::string& t) {
    static const std::map<char, const char*> glyphs = {
        {'0', "111101101101111"}, {'1', "010110010010111"}, {'2', "111001111100111"}, {'3', "111001111001111"},
        {'4', "101101111001001"}, {'5', "111100111001111"}, {'6', "111100111101111"}, {'7', "111001001001001"},
        {'8', "111101111101111"}, {'9', "111101111001111"}, {'.', "000000000000010"}, {'e', "000111101110111"},
        {'+', "000010111010000"}, {'-', "000000111000000"}};
    for (size_t k = 0; k < t.size(); ++k) {
        auto it = glyphs.find(t[k]);
        if (it == glyphs.end()) continue;
        for (int gy = 0; gy < 5; ++gy)
            for (int gx = 0; gx < 3; ++gx) {
                if (it->second[gy * 3 + gx] != '1') continue;
                for (int sy = 0; sy < 2; ++sy)
                    for (int sx = 0; sx < 2; ++sx) {
                        int x = x0 + int(k) * 8 + gx * 2 + sx, y = y0 + gy * 2 + sy;
                        if (x < 0 || y < 0 || x >= W || y >= H) continue;
                        for (int c = 0; c < 3; ++c) img[(size_t(y) * W + x) * 3 + c] = 1.f;
                    }
            }
    }
}

// The first GGX lobe of a closure, if any.
const GgxLobe* findGgx(const Closure& c) {
    for (int i = 0; i < c.size(); ++i)
        if (auto* g = dynamic_cast<const GgxLobe*>(c.lobe(i))) return g;
    return nullptr;
}


// One `specula bsdf` query: the shading point's differentials and the light, as strings from the command line or
// values from a --batch JSON line (same names without the dashes; vectors as arrays).
struct BsdfRequestArgs {
    std::string file, material, wo, wi, uv = "0.5,0.5", duvdx = "0,0", duvdy = "0,0";
    std::string dpdx = "0,0,0", dpdy = "0,0,0", dndx = "0,0,0", dndy = "0,0,0", dwodx = "0,0,0", dwody = "0,0,0";
    float lightDistance = std::numeric_limits<float>::infinity();

    void fromJson(const json& q) {
        if (!q.is_object()) throw UsageError("a --batch line must be a JSON object");
        static const std::vector<std::string> keys = {"material", "wo", "wi", "uv", "duvdx", "duvdy", "dpdx", "dpdy",
                                                      "dndx", "dndy", "dwodx", "dwody", "light_distance"};
        for (auto it = q.begin(); it != q.end(); ++it) {
            const std::string& k = it.key();
            if (std::find(keys.begin(), keys.end(), k) == keys.end())
                throw InputError("/" + k, "unknown query key '" + k + "'", nearestName(k, keys));
            const json& v = it.value();
            if (k == "material") {
                if (!v.is_string()) throw InputError("/material", "'material' must be a string (a material name)");
                material = v.get<std::string>();
            } else if (k == "light_distance") {
                // A double beyond float's range would be undefined as a float: refuse it here.
                if (!v.is_null() && !(v.is_number() && v.get<double>() > 0.0 && v.get<double>() <= 1e30))
                    throw InputError("/light_distance", "'light_distance' must be a number in (0, 1e30] or null (a direction)");
                lightDistance = v.is_null() ? std::numeric_limits<float>::infinity() : float(v.get<double>());
            } else {
                if (!v.is_array() || v.size() < 2 || v.size() > 3)
                    throw InputError("/" + k, "'" + k + "' must be an array of 2 or 3 numbers");
                for (size_t i = 0; i < v.size(); ++i)
                    if (!v[i].is_number() || !(std::fabs(v[i].get<double>()) <= 1e30))
                        throw InputError("/" + k + "/" + std::to_string(i), "'" + k + "' must hold numbers in [-1e30, 1e30]");
                // Full float precision: std::to_string's 6 decimals would flatten small differentials.
                std::string t;
                char buf[32];
                for (size_t i = 0; i < v.size(); ++i) {
                    std::snprintf(buf, sizeof buf, "%.9g", v[i].get<double>());
                    t += (i ? "," : "") + std::string(buf);
                }
                std::string* dst = k == "wo" ? &wo : k == "wi" ? &wi : k == "uv" ? &uv : k == "duvdx" ? &duvdx : k == "duvdy" ? &duvdy
                                 : k == "dpdx" ? &dpdx : k == "dpdy" ? &dpdy : k == "dndx" ? &dndx : k == "dndy" ? &dndy
                                 : k == "dwodx" ? &dwodx : &dwody;
                *dst = t;
            }
        }
        if (wo.empty() || wi.empty()) throw UsageError("a query needs \"wo\" and \"wi\"");
    }
};

// Materials of one file, instantiated once each (texture loads, graph compilation).
class MaterialCache {
public:
    explicit MaterialCache(std::string file) : file_(std::move(file)) {}
    const MaterialInstance& get(const std::string& name) {
        auto it = cache_.find(name);
        if (it != cache_.end()) return it->second;
        Loaded l = readMaterial(file_, name);
        return cache_.emplace(name, instantiate(l)).first->second;
    }

private:
    std::string file_;
    std::map<std::string, MaterialInstance> cache_;
};

json vecJson(const Vec3& v) { return json::array({v.x, v.y, v.z}); }

// Shades the point described by r and answers its query: f·cos (total, diffuse, specular), the mixture pdf
// (visible-normal sampling pdf of Closure::sample, not renormalised over the hemisphere), and every lobe with its
// weight, frame, own f·cos and pdf and its model parameters for this query (e.g. a filtered roughness matrix).
json evaluateBsdf(MaterialCache& cache, const BsdfRequestArgs& r) {
    Vec3 wo = parseDirection(r.wo, "wo"), wi = parseDirection(r.wi, "wi");
    const MaterialInstance& mi = cache.get(r.material);
    ShadingPoint sp = localPoint(parseVec2(r.uv, "uv"), parseVec2(r.duvdx, "duvdx"), parseVec2(r.duvdy, "duvdy"), wo);
    sp.dpdx = parseVec3(r.dpdx, "dpdx"), sp.dpdy = parseVec3(r.dpdy, "dpdy");
    sp.dndx = parseVec3(r.dndx, "dndx"), sp.dndy = parseVec3(r.dndy, "dndy");
    sp.dwodx = parseVec3(r.dwodx, "dwodx"), sp.dwody = parseVec3(r.dwody, "dwody");
    sp.hasDifferentials = sp.hasDifferentials || sp.dpdx != Vec3(0.f) || sp.dpdy != Vec3(0.f) || sp.dndx != Vec3(0.f) ||
                          sp.dndy != Vec3(0.f) || sp.dwodx != Vec3(0.f) || sp.dwody != Vec3(0.f);
    if (!(r.lightDistance > 0.f)) throw UsageError("light distance must be > 0");
    ScratchArena arena;
    Closure cl;
    mi.material->shade(sp, arena, cl);
    BsdfQuery q;
    q.wo = wo;
    q.wi = wi;
    q.lightDistance = r.lightDistance;
    BsdfValue v = cl.evalPdf(q);
    json lobes = json::array();
    for (int i = 0; i < cl.size(); ++i) {
        const Frame& f = cl.frame(i);
        LobeQuery lq{f.toLocal(wo), f.toLocal(wi), q.lightDistance};
        LobeValue lv = cl.lobe(i)->evalPdf(lq);
        LobeParameters params;
        cl.lobe(i)->parameters(lq, params);
        json pj = json::object();
        for (auto& [name, values] : params) pj[name] = values.size() == 1 ? json(values[0]) : json(values);
        lobes.push_back({{"model", cl.lobe(i)->modelName()},
                         {"kind", cl.lobe(i)->kind() == LobeKind::Diffuse ? "diffuse" : "specular"},
                         {"weight", vecJson(cl.weight(i))},
                         {"normal", vecJson(f.n)},
                         {"tangent", vecJson(f.t)},
                         {"f", vecJson(lv.f)},
                         {"pdf", lv.pdf},
                         {"parameters", pj}});
    }
    Color3 f = v.f.total();
    return {{"f", vecJson(f)}, {"f_diffuse", vecJson(v.f.diffuse)}, {"f_specular", vecJson(v.f.specular)},
            {"pdf", v.pdf}, {"lobes", lobes}};
}

// A --batch line is a short JSON object. A longer one (or an endless stream without a newline, /dev/zero) is answered
// with an error once its first kMaxBatchLine bytes are read, and the batch ends there: finding the next line would
// mean reading an input of no bound.
constexpr size_t kMaxBatchLine = size_t(1) << 20;

// The next line of 'in' without its newline; false at the end of the input. 'tooLong': more than kMaxBatchLine bytes
// came without a newline (the line is not finished).
bool readBatchLine(std::istream& in, std::string& line, bool& tooLong) {
    line.clear();
    tooLong = false;
    std::streambuf* buf = in.rdbuf();
    for (;;) {
        const int c = buf->sbumpc();
        if (c == std::char_traits<char>::eof()) return !line.empty();
        if (c == '\n') return true;
        if (line.size() == kMaxBatchLine) {
            tooLong = true;
            return true;
        }
        line.push_back(char(c));
    }
}

}  // namespace

void addGraphCommands(CLI::App& app, int& exitCode) {
    // ---- specula glsl ----
    auto* glsl = app.add_subcommand("glsl", "Write the GLSL 4.50 module of a graph material");
    auto gFile = std::make_shared<std::string>(), gMat = std::make_shared<std::string>(), gOut = std::make_shared<std::string>();
    auto gInline = std::make_shared<bool>(false);
    auto gPrefix = std::make_shared<std::string>(), gRes = std::make_shared<std::string>();
    auto gBase = std::make_shared<int>(0), gSet = std::make_shared<int>(-1);
    glsl->add_option("file", *gFile, "scene or material-library JSON")->required();
    glsl->add_option("--material", *gMat, "material name (needed when the file has several)");
    glsl->add_option("-o,--output", *gOut, "output .glsl file")->required();
    glsl->add_flag("--inline-literals", *gInline, "emit literals as constants instead of a uniform block");
    glsl->add_option("--prefix", *gPrefix, "prefix of the material's names (specula_<prefix>_eval ...), so several modules share a shader");
    glsl->add_option("--binding-base", *gBase, "binding of the uniform block; resources follow (default 0)")->check(CLI::Range(0, 4096));
    glsl->add_option("--set", *gSet, "Vulkan descriptor set of every binding (default: none)")->check(CLI::Range(0, 64));
    glsl->add_option("--resources", *gRes, "write every resource as EXR files plus manifest.json into this folder");
    glsl->callback([=, &exitCode] {
        exitCode = run([&] {
            refuseOverwritingInput(*gOut, {*gFile}, "-o");
            requireOutputFolder(*gOut);
            Loaded l = readMaterial(*gFile, *gMat);
            graph::GraphDesc g = graph::parseGraph(l.material, l.pointer);
            codegen::GlslOptions opt;
            opt.materialName = l.name;
            opt.literalsAsUniforms = !*gInline;
            opt.prefix = *gPrefix;
            opt.bindingBase = *gBase;
            opt.set = *gSet;
            codegen::GlslModule m = codegen::emitGlsl(g, opt);
            for (const std::string& w : m.warnings) std::fprintf(stderr, "specula glsl: warning: %s\n", w.c_str());
            if (!gRes->empty()) {
                if (!std::filesystem::is_directory(*gRes)) throw IoError("resource folder '" + *gRes + "' does not exist");
                MaterialInstance mi = instantiate(l);  // loads the textures the resources are made from
                std::vector<graph::ResourceImage> images =
                    codegen::exportGlslResources(g, m, GraphLoadContext{mi.textures.get(), l.baseDir});
                refuseOverwritingInput(*gOut, {*gFile}, "-o");  // now also against the textures just read
                codegen::writeGlslResources(m, images, *gRes, *ColorConfig::load("builtin"));
            }
            writeFileAtomic(*gOut, m.source);
        });
    });

    // ---- specula bsdf ----
    auto* bsdf = app.add_subcommand("bsdf", "Evaluate a graph material at one shading point: f·cos, pdf and every lobe, for one query "
                                            "or (--batch) one JSON query per stdin line");
    auto b = std::make_shared<BsdfRequestArgs>();
    auto batch = std::make_shared<bool>(false);
    bsdf->add_option("file", b->file, "scene or material-library JSON")->required();
    bsdf->add_option("--material", b->material, "material name");
    bsdf->add_option("--wo", b->wo, "outgoing direction X,Y,Z (local frame of the surface, z = normal, x = tangent)");
    bsdf->add_option("--wi", b->wi, "incident direction X,Y,Z (same frame)");
    bsdf->add_option("--uv", b->uv, "texture coordinates U,V (default 0.5,0.5)");
    bsdf->add_option("--duvdx", b->duvdx, "footprint d(uv)/dx A,B (default 0,0)");
    bsdf->add_option("--duvdy", b->duvdy, "footprint d(uv)/dy C,D (default 0,0)");
    bsdf->add_option("--dpdx", b->dpdx, "dP/dx X,Y,Z per pixel (default 0,0,0)");
    bsdf->add_option("--dpdy", b->dpdy, "dP/dy X,Y,Z per pixel");
    bsdf->add_option("--dndx", b->dndx, "dN/dx X,Y,Z per pixel");
    bsdf->add_option("--dndy", b->dndy, "dN/dy X,Y,Z per pixel");
    bsdf->add_option("--dwodx", b->dwodx, "dwo/dx X,Y,Z per pixel (0: orthographic view)");
    bsdf->add_option("--dwody", b->dwody, "dwo/dy X,Y,Z per pixel");
    bsdf->add_option("--light-distance", b->lightDistance, "distance to a point light along wi (default: a direction, +inf)");
    bsdf->add_flag("--batch", *batch, "read one JSON query per stdin line, write one JSON answer per stdout line");
    bsdf->callback([=, &exitCode] {
        exitCode = run([&] {
            if (!*batch) {
                if (b->wo.empty() || b->wi.empty()) throw UsageError("--wo and --wi are required (or --batch)");
                MaterialCache cache(b->file);
                std::printf("%s\n", evaluateBsdf(cache, *b).dump().c_str());
                return;
            }
            // One process, one material load per material name; a bad line gets an error answer and sets exit 1, and
            // the batch goes on: every answer is valid JSON whatever bytes the line held (NUL, invalid UTF-8).
            if (!b->wo.empty() || !b->wi.empty())
                throw UsageError("--wo/--wi give one query; with --batch every line gives its own \"wo\" and \"wi\" (the other "
                                 "options are defaults for every line)");
            struct stat st {};
            if (::fstat(STDIN_FILENO, &st) == 0 && S_ISDIR(st.st_mode))
                throw IoError("bsdf --batch: standard input is a folder, not a stream of JSON lines");
            MaterialCache cache(b->file);
            std::string line;
            bool failed = false, tooLong = false;
            for (int n = 1; readBatchLine(std::cin, line, tooLong); ++n) {
                if (!tooLong && line.find_first_not_of(" \t\r") == std::string::npos) continue;
                json answer;
                try {
                    if (tooLong)
                        throw Error(ErrorCode::BadInput, "", "line " + std::to_string(n) + " is longer than " + std::to_string(kMaxBatchLine) +
                                                 " bytes (a query is a short JSON object); the batch ends here");
                    const json q = parseStrictJson(line, "line " + std::to_string(n), 8);
                    BsdfRequestArgs r = *b;
                    r.fromJson(q);
                    answer = evaluateBsdf(cache, r);
                } catch (const std::exception& e) {
                    answer = {{"error", e.what()}, {"line", n}};
                    failed = true;
                }
                // Bytes that are not UTF-8 (echoed by a parser's message) become U+FFFD rather than end the batch.
                std::printf("%s\n", answer.dump(-1, ' ', false, json::error_handler_t::replace).c_str());
                std::fflush(stdout);
                if (tooLong) break;
            }
            if (std::cin.bad()) throw IoError("bsdf --batch: cannot read standard input");
            if (failed) throw Error(ErrorCode::BadInput, "", "some --batch queries failed (see their \"error\" answers)");
        });
    });

    // ---- specula plot ----
    auto* plot = app.add_subcommand("plot", "Plot a material's lobe (f·cos over the projected hemisphere) and its GGX slope-space NDF");
    struct PlotArgs {
        std::string file, material, wo, out, raw, uv = "0.5,0.5", duvdx = "0,0", duvdy = "0,0";
        float footprint = 0.f;
        int size = 256;
    };
    auto p = std::make_shared<PlotArgs>();
    plot->add_option("file", p->file, "scene or material-library JSON")->required();
    plot->add_option("--material", p->material, "material name");
    plot->add_option("--wo", p->wo, "outgoing direction X,Y,Z (local frame, z = normal)")->required();
    plot->add_option("-o,--output", p->out, "output image (PNG)")->required();
    plot->add_option("--size", p->size, "panel size in pixels (default 256)");
    plot->add_option("--uv", p->uv, "texture coordinates U,V of the shading point (default 0.5,0.5)");
    plot->add_option("--duvdx", p->duvdx, "footprint d(uv)/dx A,B (default 0,0)");
    plot->add_option("--duvdy", p->duvdy, "footprint d(uv)/dy C,D (default 0,0)");
    // A pixel footprint makes footprint-driven lobes (bsdf.glint's sparkles, filtered GGX) show what one pixel of that
    // size sees; without one (all derivatives 0) they answer with their converged, analytic lobe.
    plot->add_option("--footprint", p->footprint,
                     "isotropic footprint DU: d(uv)/dx = (DU, 0), d(uv)/dy = (0, DU) (overrides --duvdx/--duvdy)")
        ->check(optionCheck(option_rules::footprint));
    plot->add_option("--raw", p->raw, "also write the float values as an EXR (beauty: f·cos RGB of the lobe panel; 'ndf' layer)");
    plot->callback([=, &exitCode] {
        exitCode = run([&] {
            refuseOverwritingInput(p->out, {p->file}, "-o");
            refuseOverwritingInput(p->raw, {p->file, p->out}, "--raw");
            requireOutputFolder(p->out);  // both folders before any work: a missing one loses nothing
            requireOutputFolder(p->raw);
            Vec3 wo = parseDirection(p->wo, "--wo");
            if (p->size < 16 || p->size > 4096) throw UsageError("--size must be in [16, 4096]");
            Loaded l = readMaterial(p->file, p->material);
            MaterialInstance mi = instantiate(l);
            Vec2 duvdx = parseVec2(p->duvdx, "--duvdx"), duvdy = parseVec2(p->duvdy, "--duvdy");
            if (p->footprint > 0.f) duvdx = Vec2(p->footprint, 0.f), duvdy = Vec2(0.f, p->footprint);
            ShadingPoint sp = localPoint(parseVec2(p->uv, "--uv"), duvdx, duvdy, wo);
            ScratchArena arena;
            Closure cl;
            mi.material->shade(sp, arena, cl);
            const int S = p->size;
            std::vector<float> lobe(size_t(S) * S, -1.f), ndf(size_t(S) * S, -1.f);
            std::vector<float> lobeRgb(size_t(S) * S * 3, 0.f);
            float lobeMax = 0.f, ndfMax = 0.f;
            double lobeSum = 0.0;  // for lobe_mean: sparkles show as a large max/mean ratio
            int lobeCount = 0;
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
                        Color3 fc = cl.evalPdf(q).f.total();
                        float val = luminance(fc);
                        std::copy(&fc.x, &fc.x + 3, &lobeRgb[(size_t(y) * S + x) * 3]);
                        lobe[size_t(y) * S + x] = val;
                        lobeMax = std::max(lobeMax, val);
                        lobeSum += val;
                        ++lobeCount;
                    }
                    if (g) {  // slope space: P22(x̃, ỹ) = D(m) cos⁴θm with m = normalize(−x̃, −ỹ, 1) (Heitz 2014, Eq. 10)
                        Vec3 m = glm::normalize(Vec3(-u * range, -v * range, 1.f));
                        float val = ggx::ndf(m, g->alphaX(), g->alphaY()) * std::pow(m.z, 4.f);
                        ndf[size_t(y) * S + x] = val;
                        ndfMax = std::max(ndfMax, val);
                    }
                }
            // Layout: titles above the panels, tick labels and axis names beside and below them, then the colour bars
            // with their range and quantity.
            const int font = 12, left = 40, between = 48, right = 14, top = 24, axes = 34, barGap = 6, bar = 14,
                      barLabels = 20;
            const int W = left + S + between + S + right, H = top + S + axes + barGap + bar + barLabels;
            const int x0[2] = {left, left + S + between}, y0 = top, yBar = top + S + axes + barGap;
            std::vector<float> img(size_t(W) * H * 3, 0.f);
            auto put = [&](int x, int y, Vec3 c) {
                if (x >= 0 && y >= 0 && x < W && y < H) std::copy(&c.x, &c.x + 3, &img[(size_t(y) * W + x) * 3]);
            };
            for (int y = 0; y < S; ++y)
                for (int x = 0; x < S; ++x) {
                    float a = lobe[size_t(y) * S + x], b = ndf[size_t(y) * S + x];
                    put(x0[0] + x, y0 + y, a < 0.f ? Vec3(0.15f) : falseColour(lobeMax > 0.f ? a / lobeMax : 0.f));
                    put(x0[1] + x, y0 + y, b < 0.f ? Vec3(0.15f) : falseColour(ndfMax > 0.f ? b / ndfMax : 0.f));
                }
            for (int y = yBar; y < yBar + bar; ++y)
                for (int x = 0; x < S; ++x) {
                    Vec3 c = falseColour(float(x) / float(S - 1));
                    put(x0[0] + x, y, c);
                    if (g) put(x0[1] + x, y, c);
                }
            auto number = [](double v) {
                char buf[32];
                std::snprintf(buf, sizeof buf, "%.3g", v);
                return std::string(buf);
            };
            const Vec3 white(1.f), grey(0.75f);
            // Tick marks at -1, 0, 1 of each panel's axes (the slope range on the right).
            for (int k = 0; k < 2; ++k)
                for (int t = 0; t < 3; ++t) {
                    const int along = std::min(S - 1, t * (S - 1) / 2);
                    for (int d = 1; d <= 4; ++d) {
                        put(x0[k] + along, y0 + S + d - 1, grey);  // below the panel
                        put(x0[k] - d, y0 + along, grey);          // left of it
                    }
                }
            const std::string rangeText = number(range);
            const std::string ticks[2][3] = {{"-1", "0", "1"}, {"-" + rangeText, "0", rangeText}};
            const std::string titles[2] = {"f(wo, wi) cos(theta_i), projected hemisphere",
                                           g ? "GGX slope-space NDF P22(slope)" : "no GGX lobe: no NDF panel"};
            const std::string xNames[2] = {"wi.x", "slope x"}, yNames[2] = {"wi.y", "slope y"};
            const std::string barNames[2] = {"luminance, 1/sr", "1 / unit slope area"};
            const std::string maxima[2] = {number(lobeMax), number(ndfMax)};
            bool fonts = true;
            auto text = [&](int x, int y, const std::string& t, int align, bool vertical = false, int size = 12) {
                fonts = fonts && drawText(img.data(), W, H, x, y, t, size, white, align, vertical);
            };
            for (int k = 0; k < 2 && fonts; ++k) {
                text(x0[k] + S / 2, 4, titles[k], 0, false, font + 1);
                if (k == 1 && !g) break;
                for (int t = 0; t < 3; ++t) {
                    const int along = t * (S - 1) / 2;
                    text(x0[k] + along, y0 + S + 5, ticks[k][t], t == 0 ? -1 : t == 1 ? 0 : 1);
                    // y ticks: -1 at the bottom; upright numbers right-aligned against the tick marks
                    text(x0[k] - 7, y0 + S - 1 - along - font / 2 - 1, ticks[k][t], 1);
                }
                text(x0[k] + S / 2, y0 + S + 5 + font + 2, xNames[k], 0);
                text(x0[k] - 7 - 6 * int(std::max(ticks[k][0].size(), ticks[k][2].size())) - font - 4, y0 + S / 2,
                     yNames[k], 0, true);
                text(x0[k], yBar + bar + 3, "0", -1);
                text(x0[k] + S, yBar + bar + 3, maxima[k], 1);
                text(x0[k] + S / 2, yBar + bar + 3, barNames[k], 0);
            }
            if (!fonts) {  // no font installed: the colour bars' numbers in the pixel font, and a note
                std::fprintf(stderr, "specula plot: warning: no font for the labels (install fonts-dejavu-core or set "
                                     "SPECULA_FONT); only the colour bars' numbers are drawn\n");
                for (int k = 0; k < (g ? 2 : 1); ++k) {
                    drawDigits(img, W, H, x0[k], yBar + bar + 3, "0");
                    drawDigits(img, W, H, x0[k] + S - 8 * int(maxima[k].size()), yBar + bar + 3, maxima[k]);
                }
            }
            std::ostringstream desc;
            desc << "specula plot: left = luminance of f*cos over the projected hemisphere (0.." << lobeMax
                 << "), right = GGX slope-space NDF P22 over slopes [-" << range << "," << range << "]^2 (0.." << ndfMax
                 << "); titles, axes and colour bars labelled";
            writeImage8(p->out, W, H, 3, img.data(), desc.str());  // via libspecula's lazily loaded image I/O
            if (!p->raw.empty()) {
                ImageSet raw;
                raw.width = raw.height = S;
                raw.aovs.push_back({"beauty", {"R", "G", "B"}, lobeRgb});
                std::vector<float> nd(ndf.size());
                for (size_t i = 0; i < nd.size(); ++i) nd[i] = std::max(ndf[i], 0.f);
                raw.aovs.push_back({"ndf", {"Y"}, nd});
                raw.metadata["specula:plot"] = "beauty: f*cos over the projected hemisphere wi = (x, y, sqrt(1-x^2-y^2)); ndf: GGX P22";
                writeExr(p->raw, raw, *ColorConfig::load("builtin"));
            }
            json j = {{"lobe_max", lobeMax}, {"lobe_mean", lobeCount ? lobeSum / lobeCount : 0.0}, {"ndf_max", ndfMax}, {"slope_range", g ? range : 0.f}, {"has_ggx", g != nullptr}};
            std::printf("%s\n", j.dump().c_str());
        });
    });
}

}  // namespace specula
