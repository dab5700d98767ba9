// glTF 2.0 scene import (core/scene/gltf_scene.h): a scene document built from detail::describeGltfScene.
#include "core/scene/gltf_scene.h"

#include "core/geometry/mesh_io_detail.h"
#include "core/util/cache_dir.h"
#include "core/util/error.h"
#include "core/util/input_files.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <unistd.h>

namespace fs = std::filesystem;

namespace specula {

namespace {

constexpr double kLumensPerWatt = 683.0;  // glTF's photometric units to Blender's (and Specula's) radiometric ones
constexpr double kPiD = 3.14159265358979323846;

std::string lowerExtension(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

// glTF is y-up, Specula (like Blender) z-up: Blender's importer turns the scene +90 degrees about x.
Vec3 zUp(const glm::dvec3& p) { return Vec3(float(p.x), float(-p.z), float(p.y)); }
nlohmann::json vec(const Vec3& v) { return {v.x, v.y, v.z}; }

// Images are named by their content (FNV-1a 64), so the same file imported twice reuses them; written by the cache
// service (core/util/cache_dir.h: temporary and rename), so a reader never sees half an image.
std::string saveImage(const std::vector<unsigned char>& bytes, const std::string& ext) {
    uint64_t h = 1469598103934665603ull;
    for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
    char name[40];
    std::snprintf(name, sizeof name, "%016llx", (unsigned long long)h);
    const fs::path dir = cacheFolder("gltf-images"), file = dir / (std::string(name) + ext);
    std::error_code ec;
    // Reused only when every byte agrees: a corrupted file of the right size was used before (issue 35).
    if (fs::exists(file, ec)) {
        if (fs::file_size(file, ec) == bytes.size()) {
            std::ifstream in(file, std::ios::binary);
            std::vector<unsigned char> held(bytes.size());
            if (in.read(reinterpret_cast<char*>(held.data()), std::streamsize(held.size())) && held == bytes)
                return file.string();
        }
        warnCorruptCacheEntry(file.string(), "differs from the image its name hashes");
    }
    if (!writeFileAtomically(file.string(), {{bytes.data(), bytes.size()}}))
        throw IoError("cannot write the glTF image '" + file.string() + "'");
    return file.string();
}

// A metallic-roughness material as a graph: diffuse base·(1 − metallic) plus GGX with F0 = mix(0.04, base, metallic)
// and α = roughness², a tangent-space normal map, and emission (glTF 2.0 §B). KHR_materials_transmission mixes in
// bsdf.dielectric (IOR from KHR_materials_ior, tinted by the base colour) by transmissionFactor·(1 − metallic): every
// mesh is then a solid boundary that refracts (KHR_materials_volume's thin-walled default and thickness are not
// modelled, nor the transmission texture). Texture channels as the spec says: roughness in G, metallic in B, colours
// sRGB, data raw.
nlohmann::json materialGraph(const GltfSceneInfo::Material& m) {
    nlohmann::json nodes = nlohmann::json::object();
    auto image = [&](const std::string& id, const std::string& file, const char* colorspace) {
        nodes[id] = {{"type", "texture.image"}, {"inputs", {{"file", file}, {"colorspace", colorspace}}}};
        return "@" + id + ".color";
    };
    const Vec3 baseFactor(m.baseColor);
    nlohmann::json base = vec(baseFactor), metallic = m.metallic, roughness = m.roughness;
    if (!m.baseColorTexture.empty()) {
        nodes["base"] = {{"type", "math.mul.color3"},
                         {"inputs", {{"a", image("base_image", m.baseColorTexture, "srgb_texture")}, {"b", vec(baseFactor)}}}};
        base = "@base.out";
    }
    if (!m.metallicRoughnessTexture.empty()) {
        const std::string mr = image("metal_rough_image", m.metallicRoughnessTexture, "raw");
        nodes["roughness_channel"] = {{"type", "convert.color3_to_float"}, {"inputs", {{"in", mr}, {"channel", "g"}}}};
        nodes["metallic_channel"] = {{"type", "convert.color3_to_float"}, {"inputs", {{"in", mr}, {"channel", "b"}}}};
        nodes["roughness"] = {{"type", "math.mul.float"}, {"inputs", {{"a", "@roughness_channel.out"}, {"b", m.roughness}}}};
        nodes["metallic"] = {{"type", "math.mul.float"}, {"inputs", {{"a", "@metallic_channel.out"}, {"b", m.metallic}}}};
        roughness = "@roughness.out";
        metallic = "@metallic.out";
    }
    nlohmann::json diffuseColor, f0;
    if (base.is_array() && metallic.is_number()) {  // all constant: computed here
        diffuseColor = vec(baseFactor * (1.f - m.metallic));
        f0 = vec(glm::mix(Vec3(0.04f), baseFactor, m.metallic));
    } else {
        nodes["diffuse_color"] = {{"type", "math.mix.color3"}, {"inputs", {{"a", base}, {"b", {0, 0, 0}}, {"t", metallic}}}};
        nodes["f0"] = {{"type", "math.mix.color3"}, {"inputs", {{"a", {0.04, 0.04, 0.04}}, {"b", base}, {"t", metallic}}}};
        diffuseColor = "@diffuse_color.out";
        f0 = "@f0.out";
    }
    nodes["diffuse"] = {{"type", "bsdf.diffuse"}, {"inputs", {{"color", diffuseColor}}}};
    nodes["specular"] = {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", roughness}, {"fresnel", "schlick"}, {"f0", f0}}}};
    if (!m.normalTexture.empty()) {
        nodes["normal_map"] = {{"type", "texture.normal_map"},
                               {"inputs", {{"color", image("normal_image", m.normalTexture, "raw")}, {"strength", m.normalScale}}}};
        nodes["diffuse"]["inputs"]["normal"] = "@normal_map.normal";
        nodes["specular"]["inputs"]["normal"] = "@normal_map.normal";
    }
    nodes["surface"] = {{"type", "closure.add"}, {"inputs", {{"a", "@diffuse.bsdf"}, {"b", "@specular.bsdf"}}}};
    std::string output = "@surface.bsdf";
    if (m.transmission > 0.f) {
        nodes["glass"] = {{"type", "bsdf.dielectric"},
                          {"inputs", {{"roughness", roughness}, {"ior", m.ior}, {"transmission_tint", base}}}};
        if (!m.normalTexture.empty()) nodes["glass"]["inputs"]["normal"] = "@normal_map.normal";
        nlohmann::json t = m.transmission;
        if (metallic.is_number()) {
            t = m.transmission * (1.f - m.metallic);
        } else {
            nodes["transmission"] = {{"type", "math.mix.float"}, {"inputs", {{"a", m.transmission}, {"b", 0.f}, {"t", metallic}}}};
            t = "@transmission.out";
        }
        nodes["surface_with_transmission"] = {{"type", "closure.mix"},
                                              {"inputs", {{"a", "@surface.bsdf"}, {"b", "@glass.bsdf"}, {"t", t}}}};
        output = "@surface_with_transmission.bsdf";
    }
    if (!m.emissiveTexture.empty() || maxComponent(m.emissive) > 0.f) {
        nlohmann::json emitted = vec(m.emissive);
        if (!m.emissiveTexture.empty()) {
            nodes["emission_color"] = {{"type", "math.mul.color3"},
                                       {"inputs", {{"a", image("emission_image", m.emissiveTexture, "srgb_texture")}, {"b", vec(m.emissive)}}}};
            emitted = "@emission_color.out";
        }
        nodes["emission"] = {{"type", "bsdf.emission"}, {"inputs", {{"color", emitted}}}};
        nodes["surface_and_emission"] = {{"type", "closure.add"}, {"inputs", {{"a", output}, {"b", "@emission.bsdf"}}}};
        output = "@surface_and_emission.bsdf";
    }
    return {{"nodes", nodes}, {"output", output}};
}

}  // namespace

bool isGltfScenePath(const std::string& path) {
    const std::string e = lowerExtension(path);
    return e == ".gltf" || e == ".glb";
}

nlohmann::json gltfSceneDocument(const std::string& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw IoError("cannot open glTF scene '" + path + "'");
    noteInputFile(path);
    GltfSceneInfo info;
    try {
        info = detail::describeGltfScene(path, lowerExtension(path) == ".glb", &saveImage);
    } catch (const GltfValueError& e) {
        // A value out of range is bad input like a scene's (exit 1), named by the glTF file and the JSON pointer into
        // it (RFC 6901's URI fragment form): "model.gltf#/cameras/0/perspective/yfov: 0 is outside (0, 3.14159) ...".
        throw InputError(path + "#" + e.pointer, e.reason);
    } catch (const MeshLoadError& e) {
        throw IoError(e.what());
    }
    if (info.usedMaterials.empty()) throw InputError("", "glTF scene '" + path + "' has no triangles to render");
    const std::string absolute = fs::absolute(path).lexically_normal().string();
    nlohmann::json doc;
    doc["description"] = "imported from the glTF file " + fs::path(path).filename().string();

    // Materials: the glTF name where it is unique, else material_<index>; "default" for primitives without one.
    nlohmann::json materials = nlohmann::json::object(), shapes = nlohmann::json::array();
    std::set<std::string> taken;
    for (int k : info.usedMaterials) {
        const GltfSceneInfo::Material fallback;
        const GltfSceneInfo::Material& m = k >= 0 ? info.materials[size_t(k)] : fallback;
        std::string name = k < 0 ? "default" : m.name;
        if (name.empty() || taken.count(name)) name = k < 0 ? "default_" + std::to_string(taken.size()) : "material_" + std::to_string(k);
        taken.insert(name);
        materials[name] = materialGraph(m);
        shapes.push_back({{"type", "mesh"}, {"name", fs::path(path).stem().string() + " (" + name + ")"}, {"file", absolute},
                          {"gltf_material", k}, {"material", name}, {"transform", {{"rotate", {90, 0, 0}}}}});
    }
    doc["materials"] = materials;
    doc["shapes"] = shapes;

    // Camera: the first one of the scene, else one framing the bounds from the front, above and to the right.
    int width = 960, height = GltfSceneInfo::kImageHeight;
    if (!info.cameras.empty()) {
        const GltfSceneInfo::Camera& c = info.cameras.front();
        const glm::dmat3 R(c.world);
        const Vec3 position = zUp(glm::dvec3(c.world[3])), forward = glm::normalize(zUp(R * glm::dvec3(0, 0, -1)));
        const Vec3 up = glm::normalize(zUp(R * glm::dvec3(0, 1, 0)));
        // aspectRatio is checked to give 16 to 8192 columns (gltf_loader.cpp GltfChecker); the clamp only guards that.
        if (c.aspect > 0.0)
            width = int(std::clamp(std::round(height * c.aspect), double(GltfSceneInfo::kMinImageWidth),
                                   double(GltfSceneInfo::kMaxImageWidth)));
        doc["camera"] = {{"position", vec(position)}, {"look_at", vec(position + forward)}, {"up", vec(up)},
                         {"fov", std::clamp(c.yfov * 180.0 / kPiD, 0.1, 179.0)}, {"fov_axis", "y"}};
    } else {
        Vec3 lo(-1.f), hi(1.f);
        if (info.hasBounds) {
            const Vec3 a = zUp(glm::dvec3(info.boundsMin)), b = zUp(glm::dvec3(info.boundsMax));
            lo = glm::min(a, b), hi = glm::max(a, b);
        }
        const Vec3 centre = 0.5f * (lo + hi);
        const float radius = std::max(0.5f * glm::length(hi - lo), 1e-3f);
        // The bounding sphere fits the 39.6-degree horizontal field's vertical half-angle (16:9) with a 10% margin.
        const float halfV = std::atan(std::tan(0.5f * 39.6f * float(kPiD) / 180.f) * 9.f / 16.f);
        const Vec3 dir = glm::normalize(Vec3(0.45f, -1.f, 0.4f));
        doc["camera"] = {{"position", vec(centre + dir * (1.1f * radius / std::sin(halfV)))}, {"look_at", vec(centre)}};
    }
    doc["render"] = {{"width", width}, {"height", height}, {"spp", 64}, {"integrator", "path"}};

    // KHR_lights_punctual: candela -> W/sr and lux -> W/m² at 683 lm/W (Blender's importer); range is ignored.
    nlohmann::json lights = nlohmann::json::array();
    for (const GltfSceneInfo::Light& l : info.lights) {
        const glm::dmat3 R(l.world);
        const Vec3 position = zUp(glm::dvec3(l.world[3])), axis = glm::normalize(zUp(R * glm::dvec3(0, 0, -1)));
        const double value = std::max(0.0, l.intensity) / kLumensPerWatt;
        nlohmann::json j = {{"name", l.name.empty() ? l.type : l.name}, {"color", vec(glm::max(l.color, Vec3(0.f)))}};
        if (l.type == "directional") {
            j["type"] = "directional", j["direction"] = vec(axis), j["irradiance"] = value;
        } else if (l.type == "spot") {
            const double outer = std::clamp(l.outerCone, 1e-3, kPiD / 2), inner = std::clamp(l.innerCone, 0.0, outer);
            j["type"] = "spot", j["position"] = vec(position), j["look_at"] = vec(position + axis);
            j["cone_angle"] = std::clamp(2.0 * outer * 180.0 / kPiD, 0.01, 180.0);
            j["blend"] = std::clamp(1.0 - inner / outer, 0.0, 1.0);
            j["intensity"] = value;
        } else if (l.type == "point") {
            j["type"] = "point", j["position"] = vec(position), j["intensity"] = value;
        } else {
            continue;  // an unknown type from a newer extension version
        }
        lights.push_back(j);
    }
    lights.push_back({{"type", "environment"}, {"name", "environment"}, {"color", {1, 1, 1}}, {"strength", 0.5}});
    doc["lights"] = lights;
    return doc;
}

}  // namespace specula
