// Scene format v1 loader: strict JSON -> Scene (render settings, camera, textures, materials, shapes,
// lights), with every input error reported at its JSON pointer.
#include "core/scene/scene_loader.h"
#include "core/scene/animation.h"

#include "core/color/color_config.h"
#include "core/geometry/mesh_io.h"
#include "core/geometry/shapes.h"
#include "core/graph/graph_material.h"
#include "core/scene/gltf_scene.h"
#include "core/scene/json_reader.h"
#include "core/texture/texture_store.h"
#include "core/util/input_files.h"

#include <glm/gtc/matrix_transform.hpp>

#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace specula {

Scene::Scene() = default;
Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

namespace {

constexpr int kMaxDimension = 16384;
constexpr int64_t kMaxPixels = int64_t(1) << 26;  // 64 Mpixel
constexpr float kBig = 1e7f;

struct Context {
    std::string baseDir;
    Scene* scene = nullptr;
    std::map<std::string, int> materials;
    SceneLimits limits;
    int64_t triangles = 0;  // of the shapes read so far (limits.maxTriangles)
};

std::string resolvePath(const Context& ctx, const std::string& p) {
    fs::path path(p);
    if (path.is_relative()) path = fs::path(ctx.baseDir) / path;
    return path.lexically_normal().string();
}

std::string fileMustExist(const Context& ctx, const JsonReader& r, const std::string& key) {
    std::string file = r.requiredString(key);
    std::string full = resolvePath(ctx, file);
    if (!fs::exists(full)) r.fail(key, "file not found: '" + full + "'");
    return full;
}

void readRender(const Json& j, Scene& s) {
    JsonReader r(j, "/render",
                 {"width", "height", "spp", "seed", "tile", "integrator", "max_depth", "filter", "gaussian_sigma2",
                  "pixel_center", "clamp_indirect", "derivatives", "area_lights", "mesh_lights", "ltc_horizon", "ltc_max_depth", "ltc_shadow_rays",
                  "shadow_map_size", "sample_block"});
    RenderSettings& rs = s.render;
    rs.width = r.integer("width", rs.width, 1, kMaxDimension);
    rs.height = r.integer("height", rs.height, 1, kMaxDimension);
    rs.spp = r.integer("spp", rs.spp, 1, 1 << 20);
    rs.seed = uint64_t(r.integer("seed", 0, 0, 2147483647));
    rs.tile = r.integer("tile", rs.tile, 1, 1024);
    rs.sampleBlock = r.integer("sample_block", rs.sampleBlock, 0, 1 << 20);
    {
        const std::string integrator = r.enumeration("integrator", "path", {"path", "direct", "raster"});
        rs.integrator = integrator == "path"     ? IntegratorKind::Path
                        : integrator == "direct" ? IntegratorKind::Direct
                                                 : IntegratorKind::Raster;
    }
    rs.maxDepth = r.integer("max_depth", rs.maxDepth, 0, 1024);
    rs.filter = r.enumeration("filter", "box", {"box", "gaussian"}) == "box" ? PixelFilterKind::Box
                                                                           : PixelFilterKind::Gaussian;
    rs.gaussianSigma2 = r.number("gaussian_sigma2", rs.gaussianSigma2, 1e-4f, 16.f);
    rs.pixelCenter = r.boolean("pixel_center", false);
    // "derivatives": "ray" (ray differentials, default) | "quad" (GPU 2×2-quad finite differences, filtered-ggx.md §5.2)
    rs.derivatives = r.enumeration("derivatives", "ray", {"ray", "quad"}) == "quad" ? DerivativeMode::Quad : DerivativeMode::Ray;
    rs.clampIndirect = r.number("clamp_indirect", 0.f, 0.f, 1e9f);
    // "area_lights": "ltc" (lobes with a closed form integrate quad lights, with stochastic shadows) | "sampled"
    rs.areaLights = r.enumeration("area_lights", "ltc", {"ltc", "sampled"}) == "ltc" ? AreaLightMode::Ltc : AreaLightMode::Sampled;
    rs.meshLights = r.boolean("mesh_lights", true);
    rs.ltcHorizon = r.enumeration("ltc_horizon", "clip", {"clip", "clipless"}) == "clip" ? 0 : 1;
    rs.ltcMaxDepth = r.integer("ltc_max_depth", rs.ltcMaxDepth, 0, 1024);
    rs.ltcShadowRays = r.integer("ltc_shadow_rays", rs.ltcShadowRays, 1, 64);
    rs.shadowMapSize = r.integer("shadow_map_size", rs.shadowMapSize, 16, 8192);
    if (int64_t(rs.width) * rs.height > kMaxPixels)
        r.fail("width", "image of " + std::to_string(rs.width) + "x" + std::to_string(rs.height) +
                            " pixels exceeds the limit of " + std::to_string(kMaxPixels) + " pixels");
}

void readColor(const Json& j, Scene& s) {
    JsonReader r(j, "/color", {"config", "view", "exposure"});
    s.color.config = r.string("config", "builtin");
    s.color.view = r.string("view", "");
    s.color.exposure = r.number("exposure", 0.f, -30.f, 30.f);
}

void readCamera(const Json& j, Scene& s) {
    JsonReader r(j, "/camera",
                 {"type", "position", "look_at", "up", "fov", "fov_axis", "aperture_radius", "focus_distance"});
    r.enumeration("type", "perspective", {"perspective"});
    CameraDesc& c = s.camera;
    c.position = r.requiredVec3("position");
    c.lookAt = r.requiredVec3("look_at");
    c.up = r.vec3("up", Vec3(0, 0, 1));
    c.fovDegrees = r.number("fov", 39.6f, 0.01f, 179.f);
    c.fovIsHorizontal = r.enumeration("fov_axis", "x", {"x", "y"}) == "x";
    c.apertureRadius = r.number("aperture_radius", 0.f, 0.f, kBig);
    c.focusDistance = r.number("focus_distance", 0.f, 0.f, kBig);
    // In double: positions reach ±1e30, whose squared float length overflows (a camera at 1e30 was reported as "up is
    // parallel to the view direction").
    const glm::dvec3 fwd = glm::dvec3(c.lookAt) - glm::dvec3(c.position);
    if (glm::length(fwd) < 1e-9) r.fail("look_at", "look_at equals position");
    if (glm::length(glm::dvec3(c.up)) < 1e-9) r.fail("up", "up must be a non-zero vector");
    if (glm::length(glm::cross(glm::normalize(fwd), glm::normalize(glm::dvec3(c.up)))) < 1e-6)
        r.fail("up", "up is parallel to the view direction");
}

Mat4 readTransform(const JsonReader& parent) {
    if (!parent.has("transform")) return Mat4(1.f);
    JsonReader r(parent.at("transform"), parent.pointer("transform"), {"translate", "rotate", "scale", "matrix"});
    if (r.has("matrix")) {
        if (r.has("translate") || r.has("rotate") || r.has("scale"))
            r.fail("matrix", "'matrix' cannot be combined with translate/rotate/scale");
        auto m = r.numbers("matrix", 16, {}, -kMaxSceneCoordinate, kMaxSceneCoordinate);
        Mat4 M;
        for (int row = 0; row < 4; ++row)
            for (int col = 0; col < 4; ++col) M[col][row] = m[size_t(row) * 4 + col];  // row-major in JSON
        if (std::abs(glm::determinant(M)) < 1e-12f) r.fail("matrix", "matrix is singular");
        return M;
    }
    auto sc = r.numbers("scale", 3, {1, 1, 1}, -kBig, kBig);
    for (int i = 0; i < 3; ++i)
        if (std::abs(sc[i]) < 1e-9f) r.fail("scale", "scale must be non-zero");
    Vec3 rot = r.vec3("rotate", Vec3(0.f));
    Vec3 tr = r.vec3("translate", Vec3(0.f));
    // T · Rz · Ry · Rx · S (Euler XYZ in degrees, as Blender's default rotation mode)
    Mat4 M = glm::translate(Mat4(1.f), tr);
    M = glm::rotate(M, glm::radians(rot.z), Vec3(0, 0, 1));
    M = glm::rotate(M, glm::radians(rot.y), Vec3(0, 1, 0));
    M = glm::rotate(M, glm::radians(rot.x), Vec3(1, 0, 0));
    M = glm::scale(M, Vec3(sc[0], sc[1], sc[2]));
    return M;
}

void transformMesh(ShapeInstance& sh, const Mat4& M) {
    sh.objectToWorld = M;
    sh.worldToObject = glm::inverse(M);
    sh.normalToWorld = glm::transpose(glm::inverse(Mat3(M)));
    Mat3 lin(M);
    for (auto& p : sh.mesh.positions) p = Vec3(M * Vec4(p, 1.f));
    for (auto& n : sh.mesh.normals) n = glm::normalize(sh.normalToWorld * n);
    for (auto& t : sh.mesh.tangents) {
        Vec3 tw = glm::normalize(lin * Vec3(t));
        t = Vec4(tw, t.w * (glm::determinant(lin) < 0.f ? -1.f : 1.f));
    }
    if (glm::determinant(lin) < 0.f)  // mirrored: keep counter-clockwise winding w.r.t. the normals
        for (auto& i : sh.mesh.indices) std::swap(i.y, i.z);
}

// Every world-space vertex of a shape within ±kMaxSceneCoordinate (json_reader.h): each number of a transform and a
// size is bounded, but their product is not (a radius of 1e7 scaled by 1e7 reaches 1e14), and a mesh file's vertices
// are not scene numbers at all. Named at the transform, else at the mesh file (a built-in shape without a transform
// reaches at most 1e7).
void checkWorldReach(const ShapeInstance& sh, const JsonReader& r, const std::string& type) {
    float reach = 0.f;
    bool nan = false;
    for (const Vec3& p : sh.mesh.positions)
        for (int c = 0; c < 3; ++c) {
            nan = nan || std::isnan(p[c]);
            reach = std::max(reach, std::abs(p[c]));
        }
    if (!nan && reach <= kMaxSceneCoordinate) return;
    std::ostringstream where;
    if (nan) reach = std::numeric_limits<float>::quiet_NaN();
    where << reach;
    const std::string key = r.has("transform") ? "transform" : type == "mesh" ? "file" : "";
    r.fail(key, "the shape reaches " + where.str() + " scene units from the origin" +
                    (r.has("transform") ? " after its transform" : "") +
                    "; world coordinates are limited to [-1e+08, 1e+08]" +
                    (key == "file" ? " (give the shape a transform that scales the mesh down)" : " (a smaller scale, size or translation)"));
}

int materialIndex(const Context& ctx, const JsonReader& r, const std::string& key) {
    std::string name;
    const Json& v = r.at(key);
    std::string ptr = r.pointer(key);
    if (v.is_string()) {
        name = v.get<std::string>();
    } else if (v.is_object()) {
        JsonReader ref(v, ptr, {"ref"});
        name = ref.requiredString("ref");
        ptr += "/ref";
    } else {
        throw InputError(ptr, "expected a material name or {\"ref\": name}, got " + jsonTypeName(v));
    }
    auto it = ctx.materials.find(name);
    if (it == ctx.materials.end()) {
        std::vector<std::string> names;
        for (auto& m : ctx.materials) names.push_back(m.first);
        throw InputError(ptr, "unknown material '" + name + "'", nearestName(name, names));
    }
    return it->second;
}

void readMaterials(const Json& j, Context& ctx) {
    if (!j.is_object()) throw InputError("/materials", "expected an object mapping names to materials, got " + jsonTypeName(j));
    for (auto it = j.begin(); it != j.end(); ++it) {
        std::string ptr = "/materials/" + pointerEscape(it.key());
        if (it.value().is_object() && it.value().contains("nodes") && it.value()["nodes"].is_object() &&
            int64_t(it.value()["nodes"].size()) > ctx.limits.maxGraphNodes)
            throw InputError(ptr + "/nodes", "material '" + it.key() + "' has " + std::to_string(it.value()["nodes"].size()) +
                                                 " nodes; the limit is " + std::to_string(ctx.limits.maxGraphNodes));
        // Every material is a node graph (docs/graph-format.md), compiled once here.
        GraphLoadContext load{ctx.scene->textures.get(), ctx.baseDir, &ctx.scene->warnings};
        // The raster integrator computes what the GPU does, so nodes the GPU runs as a substitute load it here too.
        load.gpuSubstitutes = ctx.scene->render.integrator == IntegratorKind::Raster;
        auto m = loadGraphMaterial(it.value(), ptr, load);
        m->setName(it.key());
        ctx.materials[it.key()] = int(ctx.scene->materials.size());
        ctx.scene->materials.push_back(std::move(m));
    }
}

void readShape(const Json& j, const std::string& ptr, Context& ctx) {
    const std::vector<std::string> types = {"sphere", "quad", "disk", "cylinder", "torus", "mesh"};
    if (!j.is_object()) throw InputError(ptr, "expected an object, got " + jsonTypeName(j));
    if (!j.contains("type")) throw InputError(ptr, "missing required key 'type'");
    std::string type = j.at("type").is_string() ? j.at("type").get<std::string>() : "";
    std::vector<std::string> keys = {"type", "name", "material", "transform", "segments"};
    if (type == "sphere") keys.push_back("radius");
    else if (type == "quad") keys.push_back("size");
    else if (type == "disk") keys.push_back("radius");
    else if (type == "cylinder") { keys.push_back("radius"); keys.push_back("height"); }
    else if (type == "torus") { keys.push_back("major_radius"); keys.push_back("minor_radius"); }
    else if (type == "mesh") { keys.insert(keys.end(), {"file", "shading", "smooth_angle", "gltf_material"}); }
    else
        throw InputError(ptr + "/type", "unknown shape type '" + (type.empty() ? j.at("type").dump() : type) +
                                            "'; valid types: sphere, quad, disk, cylinder, torus, mesh",
                         nearestName(type, types));
    JsonReader r(j, ptr, keys);
    ShapeInstance sh;
    sh.name = r.string("name", type);
    r.require("material");
    sh.material = materialIndex(ctx, r, "material");
    int seg = r.integer("segments", 128, 8, 4096);
    BuiltinShape b;
    if (type == "sphere")
        b = makeSphere(r.number("radius", 1.f, 1e-6f, kBig), seg);
    else if (type == "quad") {
        auto s = r.numbers("size", 2, {1.f, 1.f}, 1e-6f, kBig);
        b = makeQuad(s[0], s[1]);
    } else if (type == "disk")
        b = makeDisk(r.number("radius", 1.f, 1e-6f, kBig), seg);
    else if (type == "cylinder")
        b = makeCylinder(r.number("radius", 1.f, 1e-6f, kBig), r.number("height", 1.f, 1e-6f, kBig), seg);
    else if (type == "torus") {
        float R = r.number("major_radius", 1.f, 1e-6f, kBig), rr = r.number("minor_radius", 0.25f, 1e-6f, kBig);
        if (rr >= R) r.fail("minor_radius", "minor_radius must be smaller than major_radius");
        b = makeTorus(R, rr, seg);
    } else {
        std::string file = fileMustExist(ctx, r, "file");
        MeshShading shading;
        const std::string mode = r.enumeration("shading", "auto", {"auto", "smooth", "flat"});
        shading.mode = mode == "flat" ? MeshShading::Flat : mode == "smooth" ? MeshShading::Smooth : MeshShading::Auto;
        shading.smoothAngleDegrees = r.number("smooth_angle", 30.f, 0.f, 180.f);
        if (r.has("smooth_angle") && shading.mode != MeshShading::Auto)
            r.fail("smooth_angle", "smooth_angle applies to \"shading\": \"auto\" only (this mesh is \"" + mode + "\")");
        // A glTF file's triangles of one material (the glTF scene import makes one shape per material).
        const int gltfMaterial = r.has("gltf_material") ? r.integer("gltf_material", -1, -1, 1 << 20) : kAllGltfMaterials;
        try {
            b.mesh = loadMesh(file, shading, &sh.attributes, gltfMaterial);
        } catch (const GltfValueError& e) {  // a value out of range is bad input here too, as in a glTF scene (exit 1)
            throw InputError(r.pointer("file"), e.file + "#" + e.pointer + ": " + e.reason);
        } catch (const MeshLoadError& e) {
            throw IoError(r.pointer("file") + ": " + e.what());
        }
        sh.meshFile = r.string("file", "");
    }
    sh.mesh = std::move(b.mesh);
    ctx.triangles += int64_t(sh.mesh.triangleCount());
    if (ctx.triangles > ctx.limits.maxTriangles)
        throw InputError(type == "mesh" ? ptr + "/file" : ptr, "the shapes up to this one have " + std::to_string(ctx.triangles) +
                                                              " triangles; the limit is " + std::to_string(ctx.limits.maxTriangles));
    // The rasteriser shades the tessellation's interpolated attributes, so the raster integrator does too: built-in
    // shapes lose their exact-surface projection there (docs/preview.md).
    if (ctx.scene->render.integrator != IntegratorKind::Raster) sh.surface = b.surface;
    transformMesh(sh, readTransform(r));
    checkWorldReach(sh, r, type);
    ctx.scene->shapes.push_back(std::move(sh));
}

// Radiant power -> radiance or intensity, following Blender's light units.
Color3 lightStrength(const JsonReader& r, const std::string& perUnitKey, float powerToUnit, const std::string& powerKey = "power") {
    Color3 color = r.color("color", Color3(1.f));
    if (r.has(powerKey) && r.has(perUnitKey)) r.fail(perUnitKey, "give either '" + powerKey + "' or '" + perUnitKey + "', not both");
    if (r.has(powerKey)) return color * r.number(powerKey, 0.f, 0.f, 1e12f) * powerToUnit;
    if (!r.has(perUnitKey)) r.fail("", "missing required key '" + powerKey + "' (or '" + perUnitKey + "')");
    return color * r.number(perUnitKey, 0.f, 0.f, 1e12f);
}

void readLight(const Json& j, const std::string& ptr, Context& ctx) {
    const std::vector<std::string> types = {"point", "spot", "directional", "quad", "environment"};
    if (!j.is_object()) throw InputError(ptr, "expected an object, got " + jsonTypeName(j));
    if (!j.contains("type")) throw InputError(ptr, "missing required key 'type'");
    std::string type = j.at("type").is_string() ? j.at("type").get<std::string>() : "";
    Scene& s = *ctx.scene;
    if (j.contains("name") && !j.at("name").is_string())
        throw InputError(ptr + "/name", "expected a string, got " + jsonTypeName(j.at("name")));
    std::unique_ptr<Light> light;
    if (type == "point") {
        JsonReader r(j, ptr, {"type", "name", "position", "power", "intensity", "color"});
        light = std::make_unique<PointLight>(r.requiredVec3("position"), lightStrength(r, "intensity", kInv4Pi));
    } else if (type == "spot") {
        JsonReader r(j, ptr, {"type", "name", "position", "look_at", "cone_angle", "blend", "power", "intensity", "color"});
        Vec3 p = r.requiredVec3("position"), at = r.requiredVec3("look_at");
        if (glm::length(at - p) < 1e-9f) r.fail("look_at", "look_at equals position");
        light = std::make_unique<SpotLight>(p, at - p, r.number("cone_angle", 45.f, 0.01f, 180.f),
                                            r.number("blend", 0.15f, 0.f, 1.f), lightStrength(r, "intensity", kInv4Pi));
    } else if (type == "directional") {
        JsonReader r(j, ptr, {"type", "name", "direction", "irradiance", "color"});
        Vec3 d = r.requiredVec3("direction");
        if (glm::length(d) < 1e-9f) r.fail("direction", "direction must be non-zero");
        r.require("irradiance");
        light = std::make_unique<DirectionalLight>(d, r.color("color", Color3(1.f)) * r.number("irradiance", 1.f, 0.f, 1e12f));
    } else if (type == "quad") {
        JsonReader r(j, ptr, {"type", "name", "position", "look_at", "up", "size", "radiance", "power", "color", "two_sided", "visible"});
        Vec3 c = r.requiredVec3("position"), at = r.requiredVec3("look_at");
        Vec3 n = at - c;
        if (glm::length(n) < 1e-9f) r.fail("look_at", "look_at equals position");
        n = glm::normalize(n);
        Vec3 up = r.vec3("up", std::abs(n.z) > 0.99f ? Vec3(0, 1, 0) : Vec3(0, 0, 1));
        Vec3 ex = glm::cross(up, n);
        if (glm::length(ex) < 1e-6f) r.fail("up", "up is parallel to the light's normal");
        ex = glm::normalize(ex);
        Vec3 ey = glm::cross(n, ex);
        auto size = r.numbers("size", 2, {1.f, 1.f}, 1e-6f, kBig);
        bool twoSided = r.boolean("two_sided", false);
        float area = size[0] * size[1];
        Color3 L = lightStrength(r, "radiance", 1.f / (kPi * area * (twoSided ? 2.f : 1.f)));
        // corner + edges with cross(eu, ev) = n (emitting side faces look_at)
        Vec3 eu = ex * size[0], ev = ey * size[1];
        Vec3 corner = c - 0.5f * eu - 0.5f * ev;
        light = std::make_unique<QuadLight>(corner, eu, ev, L, twoSided);
        light->cameraVisible = r.boolean("visible", true);
        // The emitter is visible geometry too.
        ShapeInstance sh;
        sh.name = "light:" + std::to_string(s.lights.size());
        sh.mesh.positions = {corner, corner + eu, corner + eu + ev, corner + ev};
        sh.mesh.normals = {n, n, n, n};
        sh.mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        sh.mesh.indices = {{0, 1, 2}, {0, 2, 3}};
        sh.areaLight = int(s.lights.size());
        s.shapes.push_back(std::move(sh));
    } else if (type == "environment") {
        JsonReader r(j, ptr, {"type", "name", "color", "strength", "file", "colorspace", "rotation"});
        Color3 scale = r.color("color", Color3(1.f)) * r.number("strength", 1.f, 0.f, 1e9f);
        if (r.has("file")) {
            std::string file = fileMustExist(ctx, r, "file");
            std::string cs = r.string("colorspace", "");
            if (cs.empty()) r.fail("", "missing required key 'colorspace' (textures declare their colorspace)");
            if (cs != "raw" && !s.colorConfig->hasColorspace(cs)) {
                auto names = s.colorConfig->colorspaces();
                names.push_back("raw");
                r.fail("colorspace", "unknown colorspace '" + cs + "'", nearestName(cs, names));
            }
            TextureHandle h;
            try {
                h = s.textures->load(file, cs);
            } catch (const TextureInputError& e) {
                throw InputError(r.pointer("file"), e.what());
            } catch (const TextureError& e) {
                throw IoError(r.pointer("file") + ": " + e.what());
            }
            int w = s.textures->width(h), hh = s.textures->height(h), ch = s.textures->channels(h);
            const auto& px = s.textures->pixels(h);
            std::vector<float> rgb(size_t(w) * hh * 3);
            for (size_t i = 0; i < size_t(w) * hh; ++i)
                for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = px[i * ch + std::min(c, ch - 1)];
            light = std::make_unique<EnvironmentLight>(std::move(rgb), w, hh, r.number("rotation", 0.f, -3600.f, 3600.f), scale);
        } else {
            light = std::make_unique<EnvironmentLight>(scale);
        }
    } else {
        throw InputError(ptr + "/type", "unknown light type '" + (type.empty() ? j.at("type").dump() : type) +
                                            "'; valid types: point, spot, directional, quad, environment",
                         nearestName(type, types));
    }
    light->name = j.value("name", type);
    s.lights.push_back(std::move(light));
}

// Nesting deeper than this is refused while parsing: nothing in a scene needs it, and nlohmann's serializer (messages
// dump values) and the loader's readers recurse once per level, so a small file of 100k nested arrays overflowed the
// stack (issue 16).
constexpr int kMaxJsonDepth = 64;

// The structure rules of scene JSON (duplicate keys, nesting depth), checked by a SAX pass over the text before the
// document is built. nlohmann's callback parser, which did this before, scans the parent object for discarded values
// at the end of every child object: quadratic in the number of a object's members (a 20,000-node material took 2.4 s
// in `specula info`, 100,000 nodes several minutes; issue 35). The SAX pass and the plain DOM parse are both linear
// and iterative (no recursion per nesting level).
class JsonStructureCheck {
public:
    using Number = Json::number_float_t;
    JsonStructureCheck(const std::string& name, int maxDepth) : name_(name), maxDepth_(std::min(maxDepth, kMaxJsonDepth)) {}

    bool null() { return scalar(); }
    bool boolean(bool) { return scalar(); }
    bool number_integer(Json::number_integer_t) { return scalar(); }
    bool number_unsigned(Json::number_unsigned_t) { return scalar(); }
    bool number_float(Number, const Json::string_t&) { return scalar(); }
    bool string(Json::string_t&) { return scalar(); }
    bool binary(Json::binary_t&) { return scalar(); }
    bool start_object(std::size_t) { return open(false); }
    bool start_array(std::size_t) { return open(true); }
    bool end_object() { return close(); }
    bool end_array() { return close(); }
    bool key(Json::string_t& key) {
        checkDepth();
        Frame& f = frames_.back();
        if (!f.keys.insert(key).second) {
            f.key.clear();
            throw InputError(pointer() + "/" + escape(key), name_ + ": duplicate key '" + key +
                                                                "' (JSON allows it, but only one value would be used)");
        }
        f.key = key;
        return true;
    }
    // A syntax error is left to the DOM parse that follows, which reports it with its byte offset.
    bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) { return false; }

private:
    struct Frame {
        bool array;
        int index;
        std::set<std::string> keys;
        std::string key;
    };
    // The depth rule of the callback parser this replaces: a container or value with more than maxDepth enclosing
    // containers is refused (an empty container at exactly maxDepth is not).
    void checkDepth() const {
        if (int(frames_.size()) > maxDepth_)
            throw InputError(pointer(), name_ + ": JSON nested deeper than " + std::to_string(maxDepth_) + " levels");
    }
    bool scalar() {
        checkDepth();
        enterChild();
        return true;
    }
    bool open(bool array) {
        checkDepth();
        enterChild();
        frames_.push_back({array, -1, {}, {}});
        return true;
    }
    bool close() {
        frames_.pop_back();
        return true;
    }
    void enterChild() {
        if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
    }
    static std::string escape(const std::string& k) {
        std::string r;
        for (char c : k) r += c == '~' ? std::string("~0") : c == '/' ? std::string("~1") : std::string(1, c);
        return r;
    }
    // The pointer of the innermost open container (its current key or index not included).
    std::string pointer() const {
        std::string p;
        for (size_t i = 0; i + 1 < frames_.size(); ++i)
            p += "/" + (frames_[i].array ? std::to_string(frames_[i].index) : escape(frames_[i].key));
        return p;
    }
    std::string name_;
    int maxDepth_;
    std::vector<Frame> frames_;
};

Json parseJson(const std::string& text, const std::string& name, int maxDepth) {
    try {
        JsonStructureCheck check(name, maxDepth);
        Json::sax_parse(text, &check);
        // Well-formed and within the rules, or malformed (then this parse throws the located parse_error).
        return Json::parse(text);
    } catch (const Json::exception& e) {
        // Convert the byte offset (parse errors) into line:column for the message.
        size_t byte = 0;
        if (auto* pe = dynamic_cast<const Json::parse_error*>(&e)) byte = pe->byte;
        size_t line = 1, col = 1;
        for (size_t i = 0; i < std::min(text.size(), size_t(byte > 0 ? byte - 1 : 0)); ++i) {
            if (text[i] == '\n') {
                ++line;
                col = 1;
            } else
                ++col;
        }
        std::string what = e.what();
        auto pos = what.find("] ");
        std::string where = byte > 0 ? name + ":" + std::to_string(line) + ":" + std::to_string(col) : name;
        throw InputError("", where + ": malformed JSON (" + (pos != std::string::npos ? what.substr(pos + 2) : what) + ")");
    }
}

}  // namespace

// Why a node of a material reads uvs (or a tangent made from them), or "": a port bound to the surface's uvs left
// unconnected, a node that reads them itself (kReadsUv), or an anisotropy-like port in use (PortSpec::orientsByTangent).
std::string uvUse(const graph::NodeInstance& node) {
    using graph::InputValue;
    if (node.spec->has(graph::kReadsUv)) return "reads the surface's uvs";
    for (size_t k = 0; k < node.inputs.size(); ++k) {
        const graph::PortSpec& port = node.spec->inputs[k];
        const InputValue& v = node.inputs[k];
        const bool bound = v.kind == InputValue::Kind::Binding || v.kind == InputValue::Kind::Default;
        switch (port.binding) {
            case graph::GeomBinding::UV:
            case graph::GeomBinding::DUVDX:
            case graph::GeomBinding::DUVDY:
            case graph::GeomBinding::PixelDUVDX:
            case graph::GeomBinding::PixelDUVDY:
                if (bound) return "reads uvs (port '" + port.name + "')";
                break;
            default: break;
        }
        if (port.orientsByTangent &&
            (v.kind == InputValue::Kind::Connection || (v.kind == InputValue::Kind::Literal && v.value[0] != 0.f)))
            return "turns with the tangent, which uvs define (port '" + port.name + "')";
    }
    return "";
}

// A mesh file without uvs under a material that reads them renders with u = v = 0 and an arbitrary tangent: the
// glints, LEAN and normal maps then look wrong without an error, so the loader says which shape and node.
void warnAboutMissingUvs(Scene& scene) {
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
        const ShapeInstance& sh = scene.shapes[i];
        if (sh.meshFile.empty() || sh.attributes.uvs != MeshAttributeSources::None || sh.material < 0) continue;
        const auto* gm = dynamic_cast<const GraphMaterial*>(scene.materials[size_t(sh.material)].get());
        if (!gm) continue;
        const graph::GraphDesc& g = gm->desc();
        for (int n : g.liveOrder({{g.outputNode, g.outputPort}})) {
            const graph::NodeInstance& node = g.nodes[size_t(n)];
            const std::string why = uvUse(node);
            if (why.empty()) continue;
            scene.warnings.push_back("/shapes/" + std::to_string(i) + ": mesh '" + sh.meshFile + "' ('" + sh.name +
                                     "') has no uvs, but node '" + node.id + "' (" + node.spec->id + ") of material '" +
                                     gm->name() + "' " + why + ": it will see u = v = 0 and an arbitrary tangent");
        }
    }
}

Scene loadSceneFromString(const std::string& text, const std::string& baseDir, const SceneOverrides& ov,
                          const std::string& name) {
    const SceneLimits& limits = ov.limits;
    Json root = parseJson(text, name, limits.maxJsonDepth);
    const AnimationRange animation = applyAnimation(root, ov.frame);
    JsonReader top(root, "", {"version", "render", "color", "camera", "materials", "shapes", "lights", "$schema", "description",
                              "animation"});
    if (top.has("version")) {
        int v = top.integer("version", 1, 0, 1000000);
        if (v != 1) top.fail("version", "unsupported scene version " + std::to_string(v) + "; this build reads version 1");
    }
    Scene scene;
    scene.sourcePath = name;
    Context ctx;
    ctx.baseDir = baseDir;
    ctx.scene = &scene;
    ctx.limits = limits;
    if (top.has("render")) readRender(root.at("render"), scene);
    if (ov.spp > 0) scene.render.spp = ov.spp;
    if (ov.areaLights) scene.render.areaLights = *ov.areaLights;
    if (ov.integrator) scene.render.integrator = *ov.integrator;
    if (ov.width > 0) scene.render.width = ov.width;
    if (ov.height > 0) scene.render.height = ov.height;
    if (ov.seed >= 0) scene.render.seed = uint64_t(ov.seed);
    if (ov.sampleBlock >= 0) scene.render.sampleBlock = ov.sampleBlock;
    scene.render.frame = animation.frame;
    if (ov.sampleSplitCount > 0) {
        const int k = ov.sampleSplitCount, i = ov.sampleSplitIndex, spp = scene.render.spp;
        if (k < 2 || i < 0 || i >= k || spp % k != 0)
            throw InputError("/render/spp", "a sample split " + std::to_string(i) + "/" + std::to_string(k) +
                                                " needs 0 <= index < count, count >= 2 and a count that divides spp (" +
                                                std::to_string(spp) + ")");
        if (scene.render.sampleBlock > 0 && scene.render.sampleBlock != spp / k)
            throw InputError("/render/sample_block", "sample_block " + std::to_string(scene.render.sampleBlock) +
                                                         " differs from the split's block of " + std::to_string(spp / k) + " samples");
        scene.render.sampleBlock = spp / k;
        scene.render.sampleSplitIndex = i;
        scene.render.sampleSplitCount = k;
    }
    if (int64_t(scene.render.width) * scene.render.height > std::min(limits.maxPixels, kMaxPixels))
        throw InputError("/render/width", "a " + std::to_string(scene.render.width) + "x" + std::to_string(scene.render.height) +
                                              " image exceeds the limit of " + std::to_string(std::min(limits.maxPixels, kMaxPixels)) + " pixels");
    if (scene.render.spp > limits.maxSpp)
        throw InputError("/render/spp", std::to_string(scene.render.spp) + " samples per pixel exceed the limit of " +
                                            std::to_string(limits.maxSpp));
    if (ov.crop) {
        const CropWindow& c = *ov.crop;
        if (c.x0 < 0 || c.y0 < 0 || c.x1 > scene.render.width || c.y1 > scene.render.height || c.x0 >= c.x1 || c.y0 >= c.y1)
            throw InputError("/render", "crop window " + std::to_string(c.x0) + "," + std::to_string(c.y0) + "," +
                                            std::to_string(c.x1) + "," + std::to_string(c.y1) + " is not inside the " +
                                            std::to_string(scene.render.width) + "x" + std::to_string(scene.render.height) + " image");
        scene.render.crop = c;
    }
    if (scene.render.integrator == IntegratorKind::Raster) {
        // What the rasteriser computes: one sample at each pixel centre, 2x2-quad derivatives (docs/preview.md).
        scene.render.spp = 1;
        scene.render.pixelCenter = true;
        scene.render.derivatives = DerivativeMode::Quad;
    }
    {
        // The hash the farm's merge compares (Scene::sourceHash): the text and every setting that changes pixels.
        const RenderSettings& rs = scene.render;
        const int block = rs.sampleBlock > 0 ? std::min(rs.sampleBlock, rs.spp) : rs.spp;
        const std::string settings = "\nspp=" + std::to_string(rs.spp) + ";seed=" + std::to_string(rs.seed) + ";size=" +
                                     std::to_string(rs.width) + "x" + std::to_string(rs.height) + ";integrator=" +
                                     std::to_string(int(rs.integrator)) + ";area_lights=" + std::to_string(int(rs.areaLights)) +
                                     ";sample_block=" + std::to_string(block) + ";frame=" + std::to_string(rs.frame);
        uint64_t h = 1469598103934665603ull;
        for (const std::string* part : {&text, &settings})
            for (unsigned char c : *part) h = (h ^ c) * 1099511628211ull;
        char hex[17];
        std::snprintf(hex, sizeof hex, "%016llx", (unsigned long long)h);
        scene.sourceHash = hex;
    }
    if (scene.render.pixelCenter && scene.render.spp != 1)
        throw InputError("/render/pixel_center", "pixel_center sampling needs spp = 1 (got " + std::to_string(scene.render.spp) + ")");
    if (top.has("color")) readColor(root.at("color"), scene);
    try {
        scene.colorConfig = ColorConfig::load(scene.color.config == "builtin" ? "builtin" : resolvePath(ctx, scene.color.config));
    } catch (const ColorError& e) {
        throw InputError("/color/config", e.what());
    }
    if (!scene.color.view.empty() && !scene.colorConfig->hasView(scene.color.view))
        throw InputError("/color/view", "unknown view '" + scene.color.view + "'",
                         nearestName(scene.color.view, scene.colorConfig->views()));
    scene.textures = std::make_shared<TextureStore>(scene.colorConfig, limits.maxTextureSide);

    top.require("camera");
    readCamera(root.at("camera"), scene);
    if (scene.render.integrator == IntegratorKind::Raster) scene.camera.apertureRadius = 0.f;  // the rasteriser's pinhole
    if (top.has("materials")) readMaterials(root.at("materials"), ctx);
    top.require("shapes");
    const Json& shapes = root.at("shapes");
    if (!shapes.is_array()) throw InputError("/shapes", "expected an array of shapes, got " + jsonTypeName(shapes));
    for (size_t i = 0; i < shapes.size(); ++i) readShape(shapes[i], "/shapes/" + std::to_string(i), ctx);
    warnAboutMissingUvs(scene);
    if (top.has("lights")) {
        const Json& lights = root.at("lights");
        if (!lights.is_array()) throw InputError("/lights", "expected an array of lights, got " + jsonTypeName(lights));
        for (size_t i = 0; i < lights.size(); ++i) readLight(lights[i], "/lights/" + std::to_string(i), ctx);
    }
    // Emissive shapes become mesh lights, after every other light (the rasteriser's light list ends before them).
    if (scene.render.meshLights && scene.render.integrator != IntegratorKind::Raster)
        for (size_t i = 0; i < scene.shapes.size(); ++i) {
            ShapeInstance& sh = scene.shapes[i];
            if (sh.areaLight >= 0 || sh.material < 0 || !scene.materials[size_t(sh.material)]->isEmissive()) continue;
            auto light = std::make_unique<MeshLight>(int(i), sh.mesh.positions, sh.mesh.indices);
            if (!(light->area() > 0.f)) continue;
            light->name = "mesh light '" + sh.name + "' (material '" + scene.materials[size_t(sh.material)]->name() + "')";
            sh.meshLight = int(scene.lights.size());
            scene.lights.push_back(std::move(light));
        }
    return scene;
}

// A scene is JSON text; anything larger is a wrong file (a mesh, /dev/zero), read no further than this.
constexpr size_t kMaxSceneBytes = size_t(256) << 20;

Json parseStrictJson(const std::string& text, const std::string& name, int maxDepth) { return parseJson(text, name, maxDepth); }

std::string readJsonText(const std::string& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw IoError("scene path '" + path + "' is a folder, not a scene file");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw IoError("cannot open scene file '" + path + "'");
    std::string text;
    char buf[1 << 16];
    while (f.read(buf, sizeof buf) || f.gcount() > 0) {
        text.append(buf, size_t(f.gcount()));
        if (text.size() > kMaxSceneBytes)
            throw InputError("", "scene file '" + path + "' is larger than 256 MiB: not a scene (a scene is JSON text)");
    }
    if (f.bad()) throw IoError("cannot read '" + path + "'");
    noteInputFile(path);
    return text;
}

Scene loadScene(const std::string& path, const SceneOverrides& overrides) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw IoError("scene path '" + path + "' is a folder, not a scene file");
    if (isGltfScenePath(path)) {  // a glTF file is imported as a scene (docs/scene-format.md "glTF scenes")
        std::string base = fs::path(path).parent_path().string();
        return loadSceneFromString(gltfSceneDocument(path).dump(), base.empty() ? "." : base, overrides, path);
    }
    const std::string text = readJsonText(path);
    std::string base = fs::path(path).parent_path().string();
    if (base.empty()) base = ".";
    return loadSceneFromString(text, base, overrides, path);
}

void setSceneLimit(SceneLimits& limits, const std::string& assignment) {
    const SceneLimits builtin;
    const size_t eq = assignment.find('=');
    const std::string name = assignment.substr(0, eq), value = eq == std::string::npos ? "" : assignment.substr(eq + 1);
    struct Entry {
        const char* name;
        int64_t max;
        std::function<void(int64_t)> set;
    };
    const Entry entries[] = {
        {"pixels", builtin.maxPixels, [&](int64_t v) { limits.maxPixels = v; }},
        {"spp", builtin.maxSpp, [&](int64_t v) { limits.maxSpp = int(v); }},
        {"triangles", builtin.maxTriangles, [&](int64_t v) { limits.maxTriangles = v; }},
        {"texture_side", builtin.maxTextureSide, [&](int64_t v) { limits.maxTextureSide = int(v); }},
        {"graph_nodes", builtin.maxGraphNodes, [&](int64_t v) { limits.maxGraphNodes = int(v); }},
        {"json_depth", builtin.maxJsonDepth, [&](int64_t v) { limits.maxJsonDepth = int(v); }},
    };
    std::vector<std::string> names;
    for (const Entry& e : entries) {
        names.push_back(e.name);
        if (name != e.name) continue;
        size_t used = 0;
        int64_t v = 0;
        try {
            v = std::stoll(value, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (value.empty() || used != value.size() || v < 1 || v > e.max)
            throw std::invalid_argument("--limit " + name + " expects a whole number from 1 to " + std::to_string(e.max) +
                                        ", got '" + value + "'");
        e.set(v);
        return;
    }
    const std::string near = nearestName(name, names);
    throw std::invalid_argument("--limit: unknown limit '" + name + "'" + (near.empty() ? "" : " (did you mean '" + near + "'?)") +
                                "; limits: pixels, spp, triangles, texture_side, graph_nodes, json_depth");
}

std::string describeScene(const Scene& s) {
    std::ostringstream o;
    size_t tris = 0;
    for (auto& sh : s.shapes) tris += sh.areaLight < 0 ? sh.mesh.triangleCount() : 0;
    o << "scene: " << s.sourcePath << "\n";
    o << "image: " << s.render.width << "x" << s.render.height << ", " << s.render.spp << " spp, seed " << s.render.seed
      << ", " << (s.render.integrator == IntegratorKind::Path ? "path tracer (max depth " + std::to_string(s.render.maxDepth) + ")" : s.render.integrator == IntegratorKind::Raster ? "raster (the GPU preview's lighting, shadow maps " + std::to_string(s.render.shadowMapSize) + " texels wide)" : std::string("direct lighting"))
      << ", " << (s.render.filter == PixelFilterKind::Box ? "box" : "gaussian") << " filter\n";
    o << "camera: position (" << s.camera.position.x << ", " << s.camera.position.y << ", " << s.camera.position.z
      << "), fov " << s.camera.fovDegrees << " deg (" << (s.camera.fovIsHorizontal ? "x" : "y") << ")\n";
    // Light geometry (quad lights) is listed with its light, not counted as a shape.
    size_t shapeCount = 0;
    for (auto& sh : s.shapes) shapeCount += sh.areaLight < 0;
    o << "shapes: " << shapeCount << " (" << tris << " triangles)\n";
    for (auto& sh : s.shapes) {
        if (sh.areaLight >= 0) continue;
        o << "  - " << sh.name << ": " << sh.mesh.triangleCount() << " triangles, material '"
          << s.materials[size_t(sh.material)]->name() << "'";
        if (!sh.meshFile.empty())
            o << "\n      mesh " << sh.meshFile << ": " << sh.mesh.positions.size() << " vertices; normals "
              << attributeSourceName(sh.attributes.normals) << ", uvs " << attributeSourceName(sh.attributes.uvs)
              << ", tangents " << attributeSourceName(sh.attributes.tangents);
        o << "\n";
    }
    o << "materials: " << s.materials.size() << "\n";
    o << "lights: " << s.lights.size() << "\n";
    for (size_t i = 0; i < s.lights.size(); ++i) {
        o << "  - " << s.lights[i]->name;
        for (auto& sh : s.shapes)
            if (sh.areaLight == int(i)) o << " (" << sh.mesh.triangleCount() << " triangles of light geometry)";
        o << "\n";
    }
    return o.str();
}

}  // namespace specula
