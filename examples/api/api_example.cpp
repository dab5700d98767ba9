// libspecula API example (docs/api.md): load a scene from a string, render it asynchronously counting the
// finished tiles, change a roughness by JSON pointer, re-render, compare, write an EXR atomically, and print
// the node catalogue's size and a GLSL module's length. Usage: specula_api_example [OUTPUT_DIR]
#include <specula/specula.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <string>

namespace sp = specula::api;

static const char* kScene = R"({
  "version": 1,
  "render": {"width": 64, "height": 48, "spp": 4, "seed": 7},
  "camera": {"position": [0, -4, 1], "look_at": [0, 0, 0.6], "fov": 40},
  "materials": {
    "gold": {
      "nodes": {"spec": {"type": "bsdf.ggx", "inputs": {"roughness": 0.1, "fresnel": "schlick", "f0": [1.0, 0.78, 0.34]}}},
      "output": "@spec.bsdf"
    },
    "floor": {
      "nodes": {"base": {"type": "bsdf.diffuse", "inputs": {"color": [0.5, 0.5, 0.5]}}},
      "output": "@base.bsdf"
    }
  },
  "shapes": [
    {"type": "sphere", "radius": 0.6, "transform": {"translate": [0, 0, 0.6]}, "material": "gold"},
    {"type": "quad", "size": [8, 8], "material": "floor"}
  ],
  "lights": [{"type": "point", "position": [1.5, -2, 3], "power": 400}]
})";

// Mean of the beauty AOV.
static double meanBeauty(const sp::RenderResult& r) {
    sp::AovView b = r.aov("beauty");
    double s = 0;
    for (int y = 0; y < b.height; ++y)
        for (int x = 0; x < b.width; ++x) s += b.at(x, y)[0] + b.at(x, y)[1] + b.at(x, y)[2];
    return s / (3.0 * b.width * b.height);
}

int main(int argc, char** argv) {
    std::string outDir = argc > 1 ? argv[1] : ".";
    try {
        sp::Scene scene = sp::Scene::fromString(kScene);
        std::printf("materials: %zu\n", scene.materialNames().size());

        // Asynchronous render: the callback runs on a worker thread, one tile at a time.
        std::atomic<int> tiles{0};
        std::atomic<bool> pixelsOk{true};
        sp::RenderJob job = scene.renderAsync({}, [&](const sp::Tile& t) {
            ++tiles;
            const float* c = t.rgb(t.x0, t.y0);  // the finished tile's pixels are final
            if (!(std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]))) pixelsOk = false;
            return true;  // false would cancel
        });
        sp::RenderResult first = job.wait();
        std::printf("render 1: %dx%d, %d/%d tiles, callback saw %d tiles, pixels %s\n", first.width(), first.height(),
                    first.stats().tilesDone, first.stats().tilesTotal, tiles.load(), pixelsOk ? "finite" : "NOT finite");
        std::printf("aovs:");
        for (auto& n : first.aovNames()) std::printf(" %s", n.c_str());
        std::printf("\n");

        // Change one literal without reloading: only the material "gold" is recompiled.
        scene.setLiteral("/materials/gold/nodes/spec/inputs/roughness", "0.6");
        sp::RenderResult second = scene.render();
        double m1 = meanBeauty(first), m2 = meanBeauty(second);
        std::printf("roughness 0.1 -> 0.6: images %s\n", m1 != m2 ? "differ" : "are identical");

        // A bad pointer: one error type with code, pointer, message and suggestion.
        try {
            scene.setLiteral("/materials/glod/nodes/spec/inputs/roughness", "0.2");
        } catch (const specula::Error& e) {
            std::printf("error: code %s (%d), pointer %s, suggestion '%s'\n", specula::errorCodeName(e.code()),
                        e.exitCode(), e.pointer().c_str(), e.suggestion().c_str());
        }

        // Outputs: atomic EXR + PNG beside it.
        sp::WrittenOutputs w = scene.writeOutputs(second, outDir + "/api_example.exr");
        std::printf("wrote %s%s\n", w.exr.substr(w.exr.rfind('/') + 1).c_str(), w.partial ? " (partial)" : "");

        // A cancelled render (here: after its first tile, on one thread) goes to OUT.partial.exr, never over OUT.exr.
        sp::RenderOptions oneThread;
        oneThread.threads = 1;
        sp::RenderResult cancelled = scene.render(oneThread, [](const sp::Tile&) { return false; });
        sp::WrittenOutputs wp = scene.writeOutputs(cancelled, outDir + "/api_example.exr");
        std::printf("cancelled: %s, wrote %s%s\n", cancelled.stats().cancelled ? "yes" : "no",
                    wp.exr.substr(wp.exr.rfind('/') + 1).c_str(), wp.partial ? " (partial)" : "");

        std::string catalogue = sp::nodeCatalogJson(-1);
        size_t nodes = 0;
        for (size_t p = catalogue.find("\"id\":"); p != std::string::npos; p = catalogue.find("\"id\":", p + 1)) ++nodes;
        std::printf("node catalogue: %zu nodes\n", nodes);
        sp::GlslModule glsl = scene.compileGlsl("gold");
        std::printf("glsl module of 'gold': %zu characters\n", glsl.source.size());
        std::printf("glsl resources: %s\n", glsl.resourcesJson.find("\"uniform_block\"") != std::string::npos ? "listed" : "missing");
    } catch (const specula::Error& e) {
        std::fprintf(stderr, "api_example: error (%s): %s\n", specula::errorCodeName(e.code()), e.what());
        return e.exitCode();
    }
    return 0;
}
