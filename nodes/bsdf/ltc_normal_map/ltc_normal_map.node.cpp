// bsdf.ltc_normal_map: a GGX + Lambert normal-mapped surface filtered with prefiltered LTCs (Nahmias 2022,
// ltc-filtering.md §4-5): per footprint and view one specular and one diffuse LTC lobe (core/ltc/ltc_prefilter.h).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "core/graph/graph_material.h"
#include "nodes/shared/ltc_gpu.h"
#include "core/ltc/ltc_prefilter.h"
#include "core/ltc/ltc_tables.h"
#include "core/texture/normal_map_gen.h"
#include "core/texture/texture_store.h"
#include "core/util/error.h"
#include "nodes/shared/normal_map_source.h"
#include "nodes/shared/texture_ports.h"

#include <glm/gtc/packing.hpp>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <list>
#include <mutex>

namespace specula::nodes {
namespace {

struct Params {
    NormalMapConvention convention;
    float roughness, strength;
    Color3 specular, diffuse;
    Vec2 uv, duvdx, duvdy;
    Vec3 normal, tangent;
    float sign;
};
const NodeParams<Params> kParams = NodeParams<Params>()
    .str("normal_map",
         "tangent-space normal map, square with a power-of-two size, colour = (n + 1)/2, read as raw data (relative "
         "to the scene file); or 'generate:<kind>:<size>:<seed>' for a core/texture/normal_map_gen map")
    .choice("convention", &Params::convention,
            "green channel: opengl = +Y up, directx = +Y down; one value per material (baked into the tables)")
    .uniform()
    .f("roughness", &Params::roughness, 0.3f,
       "base GGX roughness of every texel, alpha = roughness^2; one value per material (the tables are fitted for it)")
    .range(0.1f, 1.f).hard(0.0316f, 1.f).uniform()
    .f("strength", &Params::strength, 1.f, "scales the map's slopes (0 = flat); one value per material").range(0.f, 1.5f)
    .hard(0.f, 16.f).uniform()
    .c3("specular_color", &Params::specular, Vec3(0.04f), "Schlick F0 of the specular lobe").range(0.f, 1.f).hard(0.f, 1.f)
    .c3("diffuse_color", &Params::diffuse, Vec3(0.5f), "Lambert albedo, scaled by 1 - the specular albedo per channel")
    .range(0.f, 1.f).hard(0.f, 1.f)
    .v2("uv", &Params::uv, Vec2(0.f), "texture coordinates").range(-1.f, 2.f).bind(GeomBinding::UV)
    .v2("duvdx", &Params::duvdx, Vec2(0.f), "footprint: d(uv)/dx").range(-0.5f, 0.5f).bind(GeomBinding::DUVDX)
    .v2("duvdy", &Params::duvdy, Vec2(0.f), "footprint: d(uv)/dy").range(-0.5f, 0.5f).bind(GeomBinding::DUVDY)
    .n3("normal", &Params::normal, Vec3(0, 0, 1), "unperturbed surface normal").bind(GeomBinding::N)
    .v3("tangent", &Params::tangent, Vec3(1, 0, 0), "tangent (+u)").bind(GeomBinding::T)
    .f("sign", &Params::sign, 1.f, "bitangent sign (+v = sign N x T)").range(-1.f, 1.f).bind(GeomBinding::TSign);
OutputList kOutputs;
const OutPort<ClosureRef> kBsdf =
    kOutputs.add<ClosureRef>("bsdf", TypeDesc::Closure, "the specular and diffuse LTC lobes of the footprint");

// The hard ranges of the uniform ports (a literal outside them is refused on load; the clamps keep odd callers safe).
float clampRoughness(float r) { return std::min(std::max(r, 0.0316f), 1.f); }
float clampStrength(float s) { return std::min(std::max(s, 0.f), 16.f); }

// The prefilters already built in this process, by content hash (materials of one scene, and the many materials a
// test suite loads for one map, share them). The last few are kept alive even when no material holds them.
std::shared_ptr<const ltc::NormalMapLtcPrefilter> sharedPrefilter(const std::vector<Vec3>& normals, int size,
                                                                  const ltc::PrefilterSettings& s) {
    static std::mutex mutex;
    static std::list<std::pair<uint64_t, std::shared_ptr<const ltc::NormalMapLtcPrefilter>>> recent;
    const uint64_t h = ltc::NormalMapLtcPrefilter::contentHash(normals, size, s);
    // Held while fitting: a second material asking for the same tables waits instead of fitting them twice. The fit
    // runs isolated (ltc_prefilter.cpp), so the waiting render threads cannot be asked to run part of it.
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = recent.begin(); it != recent.end(); ++it)
        if (it->first == h) {
            recent.splice(recent.begin(), recent, it);
            return recent.front().second;
        }
    auto p = ltc::NormalMapLtcPrefilter::loadOrBuild(normals, size, s, ltc::NormalMapLtcPrefilter::defaultCacheDir());
    recent.emplace_front(h, p);
    if (recent.size() > 8) recent.pop_back();
    return p;
}

// Per instance: the decoded normals, and the tables for the (roughness, strength) the material uses. Both are uniform
// ports, so prepare reads their literals (PrepareContext::number) and fits the tables (or reads them from the disk
// cache) before any shading point; the CPU and the GPU resources use that one prepared set. The list below only
// serves a caller that evaluates other values than the prepared ones (a register overwritten after compile).
struct Prepared {
    std::vector<Vec3> normals;  // bottom-up, OpenGL convention
    int size = 0;
    struct Built {
        float roughness, strength;
        std::shared_ptr<const ltc::NormalMapLtcPrefilter> p;
    };
    mutable std::atomic<const Built*> current{nullptr};
    mutable std::mutex mutex;
    mutable std::list<Built> built;  // never shrinks: 'current' points into it
    const ltc::NormalMapLtcPrefilter* prepared = nullptr;  // the tables of the material's literals (fitted in prepare)
    float roughness = 0.f, strength = 0.f;                 // those literals, clamped to the hard ranges

    const ltc::NormalMapLtcPrefilter& tables(float roughness, float strength) const {
        const Built* b = current.load(std::memory_order_acquire);
        if (b && b->roughness == roughness && b->strength == strength) return *b->p;
        std::lock_guard<std::mutex> lock(mutex);
        for (const Built& e : built)
            if (e.roughness == roughness && e.strength == strength) {
                current.store(&e, std::memory_order_release);
                return *e.p;
            }
        std::vector<Vec3> n = normals;
        for (Vec3& v : n) v = Vec3(v.x * strength, v.y * strength, v.z);  // slope scaling (texture.lean's strength)
        ltc::PrefilterSettings s;
        s.alpha = roughness * roughness;
        built.push_back({roughness, strength, sharedPrefilter(n, size, s)});
        current.store(&built.back(), std::memory_order_release);
        return *built.back().p;
    }
};

std::shared_ptr<const void> prepare(const PrepareContext& pc) {
    const std::string& file = pc.str("normal_map");
    const bool directx = pc.str("convention") == "directx";
    auto d = std::make_shared<Prepared>();
    NormalMapSource src = loadNormalMapSource(pc, "normal_map", "bsdf.ltc_normal_map", directx);
    if (src.width != src.height || src.width < 1 || (src.width & (src.width - 1)) != 0)
        throw InputError(pc.pointer("normal_map"), "bsdf.ltc_normal_map: normal map '" + file + "' is " +
                                                       std::to_string(src.width) + "x" + std::to_string(src.height) +
                                                       "; it must be square with a power-of-two size");
    d->normals = std::move(src.normals);
    d->size = src.width;
    // The clamps are cpu()'s (the hard ranges), so its fast path finds exactly these tables.
    d->roughness = clampRoughness(pc.number("roughness"));
    d->strength = clampStrength(pc.number("strength"));
    try {
        d->prepared = &d->tables(d->roughness, d->strength);
    } catch (const std::exception& e) {
        throw InputError(pc.pointer("normal_map"), std::string("bsdf.ltc_normal_map: cannot prefilter: ") + e.what());
    }
    return d;
}

// ---- GPU resources (ltc_normal_map.glsl) ------------------------------------------------------------------------

constexpr int kTexelsPerLtc = 3;  // RGBA layers per LTC: m0-3, m4-7, (m8, mag, fres, 0)

// 'tables': the stored levels 1..L of the prefilter as one 2D array, GL level g = prefilter level g + 1 (so GL's
// trilinear filter between two levels is the CPU's between two stored levels, ltc-filtering.md §5.3), texel (x, y)
// of GL level g = texel (x, y) of prefilter level g + 1 (rows bottom-up, v = 0 first, as the prefilter stores them).
// Layers: per specular view v (v = j·nφ + k) 3 layers from 3v, then per diffuse view 3 layers from 3·nSpec. Each LTC
// is stored premultiplied by its magnitude, (mag·inv(M) normalised, mag, fres): the CPU's filter weights inv(M) by
// filter weight × magnitude (accumulateStored), and a premultiplied texel makes the hardware's linear filter compute
// exactly that sum (the products of two halves are exact in float). The θ ratio scales and the view weights are
// applied in the shader per view, as the CPU does.
graph::ResourceImage tablesImage(const void* prepared) {
    const auto* d = static_cast<const Prepared*>(prepared);
    const ltc::NormalMapLtcPrefilter& p = *d->prepared;
    const ltc::PrefilterSettings& s = p.settings();
    // The GLSL hard-codes the default view grids (SPC_LNM_*): other grids would be read with the wrong layers.
    const ltc::PrefilterSettings def;
    if (s.specTheta != def.specTheta || s.specPhi != def.specPhi || s.diffTheta != def.diffTheta || s.diffPhi != def.diffPhi)
        throw std::logic_error("bsdf.ltc_normal_map: the GLSL reads only the default view grids (8x16, 2x4)");
    const int nSpec = s.specTheta * s.specPhi, nDiff = s.diffTheta * s.diffPhi;
    const int layers = kTexelsPerLtc * (nSpec + nDiff);
    const int H = ltc::NormalMapLtcPrefilter::kRecordHalfs;
    graph::ResourceImage img;
    size_t levelFirst = 0;  // first stored texel of the level (levels are stored finest first)
    for (int l = 1; l <= p.levels(); ++l) {
        const int w = p.size() >> l;
        graph::ResourceImage::Level lv;
        lv.width = lv.height = w;
        lv.layers = layers;
        lv.rgba.assign(size_t(w) * w * layers * 4, 0.f);
        for (int t = 0; t < w * w; ++t) {
            const size_t flat = levelFirst + size_t(t);
            for (int lobe = 0; lobe < 2; ++lobe) {
                const int nv = lobe ? nDiff : nSpec;
                const std::vector<uint16_t>& rec = lobe ? p.diffuseRecords() : p.specRecords();
                for (int v = 0; v < nv; ++v) {
                    const uint16_t* r = &rec[(flat * size_t(nv) + size_t(v)) * H];
                    float x[12] = {};
                    const float mag = glm::unpackHalf1x16(r[9]);
                    for (int k = 0; k < 9; ++k) x[k] = mag * glm::unpackHalf1x16(r[k]);
                    x[9] = mag;
                    x[10] = glm::unpackHalf1x16(r[10]);
                    const int layer0 = kTexelsPerLtc * ((lobe ? nSpec : 0) + v);
                    for (int q = 0; q < kTexelsPerLtc; ++q)
                        std::memcpy(&lv.rgba[((size_t(layer0 + q) * w * w) + size_t(t)) * 4], &x[4 * q], 4 * sizeof(float));
                }
            }
        }
        levelFirst += size_t(w) * w;
        img.levels.push_back(std::move(lv));
    }
    if (img.levels.empty()) {  // a 1×1 map has no stored level: a zero texel keeps the sampler complete (never read)
        graph::ResourceImage::Level lv;
        lv.width = lv.height = 1;
        lv.layers = layers;
        lv.rgba.assign(size_t(layers) * 4, 0.f);
        img.levels.push_back(std::move(lv));
    }
    img.minFilter = "linear_mipmap_linear";
    img.magFilter = "linear";
    img.wrapS = img.wrapT = "repeat";
    return img;
}

// 'normals': the clamped unit normals of level 0 (the per-texel base LTCs of the finest footprints), read with
// texelFetch (the shader wraps the indices itself, as the CPU does).
graph::ResourceImage normalsImage(const void* prepared) {
    const auto* d = static_cast<const Prepared*>(prepared);
    const ltc::NormalMapLtcPrefilter& p = *d->prepared;
    graph::ResourceImage img;
    graph::ResourceImage::Level lv;
    lv.width = lv.height = p.size();
    lv.rgba.assign(size_t(p.size()) * p.size() * 4, 0.f);
    for (size_t i = 0; i < p.normals().size(); ++i) {
        const Vec3& n = p.normals()[i];
        lv.rgba[i * 4 + 0] = n.x, lv.rgba[i * 4 + 1] = n.y, lv.rgba[i * 4 + 2] = n.z;
    }
    img.levels.push_back(std::move(lv));
    img.minFilter = img.magFilter = "nearest";
    img.wrapS = img.wrapT = "repeat";
    return img;
}

void cpu(EvalContext& c, const Instr& i) {
    const auto* d = static_cast<const Prepared*>(i.data);
    const Params p = kParams.read(c, i);
    const ltc::LtcTables& base = ltc::builtinTables();
    const float roughness = clampRoughness(p.roughness), strength = clampStrength(p.strength);
    const ltc::NormalMapLtcPrefilter& pf = roughness == d->roughness && strength == d->strength
                                               ? *d->prepared
                                               : d->tables(roughness, strength);
    // The lobes live in the geometric tangent frame (T, N×T, N), always right-handed so polygon windings survive. The
    // map's +v is sign·(N×T): for sign < 0 the lookup sees wo mirrored in y, and the LTC is mirrored back on both
    // sides (S invM S with S = diag(1, −1, 1): the clamped cosine is symmetric in y, and det invM keeps its sign).
    const Frame f = bsdfFrame(p.normal, p.tangent);
    const ShadingPoint& sp = *c.sp;
    Vec3 wo = f.toLocal(sp.wo);
    const bool mirror = p.sign < 0.f;
    if (mirror) wo.y = -wo.y;
    ltc::LtcPair l = pf.lookup(p.uv, p.duvdx, p.duvdy, wo, base);
    if (mirror) {
        const Mat3 S(Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(0, 0, 1));
        l.spec.invM = S * l.spec.invM * S;
        l.diffuse.invM = S * l.diffuse.invM * S;
    }
    int slot = slotOf(c, i, kBsdf);
    Closure& cl = *c.closures[slot];
    cl.clear();
    c.emission[slot] = Color3(0.f);
    // Schlick through the LTC moments (HDHN16 §4 / ltc_code): ∫ F f·cos = F0·mag + (1 − F0)·fres, so the lobe tint is
    // that over mag. The diffuse gets what the specular does not reflect (per channel), so the sum stays <= 1.
    const float mag = l.spec.magnitude;
    Color3 specAlbedo = p.specular * mag + (Color3(1.f) - p.specular) * l.spec.fresnel;
    specAlbedo = glm::clamp(specAlbedo, Color3(0.f), Color3(1.f));
    if (mag > 0.f) cl.add(Color3(1.f), c.arena->make<ltc::LtcLobe>(l.spec, LobeKind::Specular, specAlbedo / mag), f);
    if (l.diffuse.magnitude > 0.f)
        cl.add(Color3(1.f), c.arena->make<ltc::LtcLobe>(l.diffuse, LobeKind::Diffuse, p.diffuse * (Color3(1.f) - specAlbedo)), f);
}

void reg(NodeRegistry& r) {
    NodeSpec s = declareNode("bsdf.ltc_normal_map",
                             "Normal-mapped GGX (base roughness per texel) plus Lambert, filtered over the pixel "
                             "footprint by prefiltered LTCs (Nahmias 2022; Student-t EM fits per MIP texel and view, "
                             "ltc-filtering.md §5.3): one specular and one diffuse LTC lobe in the geometric tangent "
                             "frame; analytic under quad lights. roughness and strength are uniform (one value per "
                             "material): the tables are fitted for them when the material is loaded (one fit per MIP "
                             "texel and view; 128^2: 743k fits, ~20 s on 2 cores) and cached on disk by content hash "
                             "($SPECULA_CACHE_DIR/ltc); the CPU and the GLSL read the same prepared tables (resources "
                             "'tables', 'normals', plus the base GGX tables), so a host must not change these two "
                             "uniforms without re-exporting the resources. GLSL: direction queries (f·cos = "
                             "tint·magnitude·D_ltc per lobe) and polygon queries (the LTC polygon integral, exact "
                             "clip or clip-free, shared/ltc.glsl).",
                             kParams, kOutputs, &cpu, kNeedsDerivatives);
    s.prepare = &prepare;
    s.glslLibraries = {"shared/ltc.glsl"};
    // The default tolerance holds: both sides read the same prepared tables and filter them alike (GL trilinear =
    // the CPU's texel-centre and MIP conventions), so only float rounding differs.
    s.parityNote = "generated 16^2 map, uniform ports at their defaults, footprints spread over MIP levels -3..4: measured "
                   "5.4e-6 (direction queries); an emitted module with other uniform literals 8.5e-6; polygon queries "
                   "(test_glsl_ltc, quads and triangles) 2.7e-5 exact clip, 2.4e-5 clip-free";
    {
        const ltc::PrefilterSettings def;
        const int layers = kTexelsPerLtc * (def.specTheta * def.specPhi + def.diffTheta * def.diffPhi);
        ResourceSpec tables{"tables", "sampler2DArray", ResourceSpec::Kind::DerivedImage,
                            "the prefiltered LTCs of MIP levels 1..log2(size) (GL level g = prefilter level g + 1; "
                            "size/2 x size/2 at GL level 0), " + std::to_string(layers) +
                                " layers: per view (8 x 16 specular, then 2 x 4 diffuse; v = theta index * n_phi + phi "
                                "index) 3 layers (mag*inv(M)[0..3], mag*inv(M)[4..7], (mag*inv(M)[8], mag, fres, 0)), "
                                "inv(M) in the view-aligned frame, unit Frobenius norm, premultiplied by its magnitude "
                                "so the linear filter is the CPU's magnitude-weighted one; RGBA32F, "
                                "linear_mipmap_linear, repeat (128^2: 64^2 x " + std::to_string(layers) +
                                " texels at level 0, ~36 MB in all)",
                            &tablesImage};
        tables.fileInput = "normal_map";
        ResourceSpec normals{"normals", "sampler2D", ResourceSpec::Kind::DerivedImage,
                             "the map's clamped unit normals (xyz, 0) after strength and convention, rows bottom-up: "
                             "the per-texel base GGX LTCs of MIP 0; RGBA32F, nearest, repeat, read with texelFetch",
                             &normalsImage};
        normals.fileInput = "normal_map";
        s.resources = {std::move(tables), std::move(normals), ltc::matrixResource(), ltc::amplitudeResource()};
    }
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
