// Resource manifest and EXR export of emitted GLSL modules (glsl_manifest.h).
#include "core/codegen/glsl_manifest.h"

#include "core/io/image_io.h"
#include "core/util/error.h"
#include "core/util/input_files.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

namespace specula::codegen {

using nlohmann::json;

json glslManifest(const GlslModule& mod, const std::vector<graph::ResourceImage>& images,
                  const std::vector<std::vector<std::string>>& levelFiles) {
    json m;
    m["format"] = "specula-glsl-manifest";
    m["version"] = 1;
    m["entry_points"] = {{"material", mod.entryPrefix + "material"}, {"eval", mod.entryPrefix + "eval"},
                         {"emission", mod.entryPrefix + "emission"}};
    json members = json::array();
    for (const GlslUniform& u : mod.uniforms) {
        json v = json::array();
        for (int c = 0; c < graph::typeWidth(u.type); ++c) v.push_back(u.value[size_t(c)]);
        members.push_back({{"name", u.name}, {"glsl_type", graph::glslTypeName(u.type)}, {"offset", u.offset},
                           {"value", v}, {"pointer", u.pointer}});
    }
    m["uniform_block"] = {{"binding", mod.uniformBinding}, {"set", mod.uniformSet}, {"size", mod.uniformBlockSize},
                          {"layout", "std140"}, {"members", members}};
    json res = json::array();
    for (size_t r = 0; r < mod.resources.size(); ++r) {
        const GlslResource& g = mod.resources[r];
        json j = {{"name", g.name},         {"binding", g.binding},   {"set", g.set},
                  {"glsl_type", g.glslType}, {"node", g.nodeId},       {"node_type", g.nodeType},
                  {"resource", g.resource},  {"kind", graph::resourceKindName(g.kind)}, {"format", "RGBA32F"}};
        if (!g.file.empty()) j["file"] = g.file;
        if (r < images.size()) {
            const graph::ResourceImage& img = images[r];
            j["colorspace"] = img.colorspace;
            json levels = json::array();
            for (size_t l = 0; l < img.levels.size(); ++l) {
                json lv = {{"width", img.levels[l].width}, {"height", img.levels[l].height}};
                if (img.levels[l].layers != 1) lv["layers"] = img.levels[l].layers;  // 2D arrays only
                if (r < levelFiles.size() && l < levelFiles[r].size()) lv["exr"] = levelFiles[r][l];
                levels.push_back(lv);
            }
            j["levels"] = levels;
            j["generate_mipmaps"] = img.generateMipmaps;
            j["min_filter"] = img.minFilter;
            j["mag_filter"] = img.magFilter;
            j["wrap_s"] = img.wrapS;
            j["wrap_t"] = img.wrapT;
        }
        res.push_back(j);
    }
    m["resources"] = res;
    // Node types whose GPU model is a substitute (GlslModule::warnings): a host shows these to the user.
    if (!mod.warnings.empty()) m["warnings"] = mod.warnings;
    return m;
}

json writeGlslResources(const GlslModule& mod, const std::vector<graph::ResourceImage>& images, const std::string& dir,
                        const ColorConfig& color) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw IoError("resource folder '" + dir + "' does not exist");
    // Every name first: none may be a file this command read (its material file, a texture: issue 35), and nothing is
    // written until all are known to be free.
    std::vector<std::vector<std::string>> files(images.size());
    for (size_t r = 0; r < images.size() && r < mod.resources.size(); ++r)
        for (size_t l = 0; l < images[r].levels.size(); ++l) files[r].push_back(mod.resources[r].name + "_l" + std::to_string(l) + ".exr");
    const std::string manifestPath = (fs::path(dir) / "manifest.json").string();
    refuseOverwritingInputs(manifestPath, {}, "--resources");
    for (const auto& levels : files)
        for (const std::string& name : levels) refuseOverwritingInputs((fs::path(dir) / name).string(), {}, "--resources");

    // Each file to a temporary beside it, committed together once all are written: a full or unwritable folder
    // leaves the previous set (manifest and images) as it was.
    std::vector<std::pair<std::string, std::string>> written;  // (temporary, final)
    auto discard = [&] {
        for (const auto& [tmp, final] : written) fs::remove(tmp, ec);
    };
    try {
        for (size_t r = 0; r < files.size(); ++r) {
            for (size_t l = 0; l < files[r].size(); ++l) {
                const graph::ResourceImage::Level& lv = images[r].levels[l];
                // A 2D array's layers are stacked in one image, layer 0 at the bottom (its rows are the GL rows in order).
                const int rows = lv.height * std::max(lv.layers, 1);
                ImageSet set;
                set.width = lv.width;
                set.height = rows;
                AovBuffer b;
                b.name = "beauty";
                b.channelNames = {"R", "G", "B", "A"};
                b.pixels.resize(size_t(lv.width) * rows * 4);
                for (int y = 0; y < rows; ++y)  // EXR rows run top to bottom; GL row 0 is the bottom one
                    std::copy_n(&lv.rgba[size_t(rows - 1 - y) * lv.width * 4], size_t(lv.width) * 4,
                                &b.pixels[size_t(y) * lv.width * 4]);
                if (lv.layers != 1) set.metadata["specula:layers"] = std::to_string(lv.layers);
                set.aovs.push_back(std::move(b));
                set.metadata["specula:resource"] = mod.resources[r].name;
                const std::string final = (fs::path(dir) / files[r][l]).string();
                written.emplace_back(createTempFileNear(final), final);
                writeExr(written.back().first, set, color);
            }
        }
        json m = glslManifest(mod, images, files);
        written.emplace_back(createTempFileNear(manifestPath), manifestPath);
        std::ofstream out(written.back().first, std::ios::binary | std::ios::trunc);
        out << m.dump(1) << "\n";
        out.flush();
        if (!out) throw IoError("cannot write '" + manifestPath + "' (is the folder full?)");
        out.close();
        for (const auto& [tmp, final] : written) commitTempFile(tmp, final);
        return m;
    } catch (...) {
        discard();
        throw;
    }
}

}  // namespace specula::codegen
