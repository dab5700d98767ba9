// bsdf.ltc_normal_map: a GGX + Lambert normal-mapped surface filtered with prefiltered LTCs (Nahmias 2022,
// ltc-filtering.md §4-5): per footprint and view one specular and one diffuse LTC lobe (core/ltc/ltc_prefilter.h).
#include "nodes/node_common.h"

#include "core/graph/closure_util.h"
#include "core/graph/graph_material.h"
#include "core/ltc/ltc_prefilter.h"
#include "core/ltc/ltc_tables.h"
#include "core/texture/normal_map_gen.h"
#include "core/texture/texture_store.h"
#include "core/util/error.h"
#include "nodes/shared/texture_ports.h"

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
    .choice("convention", &Params::convention, "green channel: opengl = +Y up, directx = +Y down")
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
// ports, but a prepare step sees only string literals, so the tables are fitted (or read from the disk cache) on the
// first shading point.
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
    try {
        if (file.rfind("generate:", 0) == 0) {
            // generate:<kind>:<size>:<seed>
            std::string rest = file.substr(9);
            size_t a = rest.find(':'), b = a == std::string::npos ? a : rest.find(':', a + 1);
            if (b == std::string::npos) throw std::runtime_error("expected generate:<kind>:<size>:<seed>");
            NormalMap m = generateNormalMap(parseNormalMapKind(rest.substr(0, a)), std::stoi(rest.substr(a + 1, b - a - 1)),
                                            std::stoull(rest.substr(b + 1)));
            d->normals = ltc::NormalMapLtcPrefilter::normalsOf(m);
            if (directx)
                for (Vec3& n : d->normals) n.y = -n.y;
            d->size = m.size;
        } else {
            if (!pc.load || !pc.load->textures)
                throw InputError(pc.pointer("normal_map"),
                                 "bsdf.ltc_normal_map needs a texture store (none was given to the graph loader)");
            std::filesystem::path p(file);
            if (p.is_relative() && !pc.load->baseDir.empty()) p = std::filesystem::path(pc.load->baseDir) / p;
            TextureStore& store = *pc.load->textures;
            TextureHandle h = store.load(p.string(), "raw");  // normal maps are data: no colour conversion
            d->normals = ltc::NormalMapLtcPrefilter::normalsFromEncodedPixels(store.pixels(h).data(), store.width(h),
                                                                             store.height(h), store.channels(h), directx);
            d->size = store.width(h);
        }
        if (d->size < 1 || (d->size & (d->size - 1)) != 0)
            throw ltc::PrefilterError("the normal map must be square with a power-of-two size");
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(pc.pointer("normal_map"), std::string("bsdf.ltc_normal_map: cannot load normal map: ") + e.what());
    }
    return d;
}

void cpu(EvalContext& c, const Instr& i) {
    const auto* d = static_cast<const Prepared*>(i.data);
    const Params p = kParams.read(c, i);
    const ltc::LtcTables& base = ltc::builtinTables();
    const ltc::NormalMapLtcPrefilter& pf =
        d->tables(std::min(std::max(p.roughness, 0.0316f), 1.f), std::min(std::max(p.strength, 0.f), 16.f));
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
    NodeSpec s;
    s.id = "bsdf.ltc_normal_map";
    s.category = "bsdf";
    s.doc = "Normal-mapped GGX (base roughness per texel) plus Lambert, filtered over the pixel footprint by prefiltered "
            "LTCs (Nahmias 2022; Student-t EM fits per MIP texel and view, ltc-filtering.md §5.3): one specular and one "
            "diffuse LTC lobe in the geometric tangent frame; analytic under quad lights. Tables are fitted on the first "
            "shading point (one fit per MIP texel and view; 128^2: 743k fits, ~20 s on 2 cores) and cached on disk by "
            "content hash ($SPECULA_CACHE_DIR/ltc). CPU only: the GLSL function is a stub that returns no lobe (the "
            "tables depend on the roughness, which a prepare step cannot read, so no GPU resource can hold them).";
    s.inputs = kParams.ports();
    s.outputs = kOutputs.ports();
    s.flags = kNeedsDerivatives;
    s.cpu = &cpu;
    s.prepare = &prepare;
    s.glslFunction = "spc_bsdf_ltc_normal_map";
    s.glslFile = "bsdf/ltc_normal_map/ltc_normal_map.glsl";
    r.add(std::move(s));
}

}  // namespace
SPECULA_REGISTER_NODES(reg);
}  // namespace specula::nodes
