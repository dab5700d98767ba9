// The Python module `import specula` (docs/python.md): pybind11 bindings over libspecula's public C++ API
// (include/specula/specula.h): scenes from dicts or files, renders to NumPy arrays, GLSL export, node listing.
#include "specula/specula.h"

#include <pybind11/eval.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <map>

#include <atomic>
#include <chrono>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

namespace py = pybind11;
namespace sp = specula::api;
using specula::ErrorCode;

namespace {

// The Python exception classes, created once at import. Heap handles that are never released: they must outlive
// every translator call, and destroying py::objects after the interpreter shut down would crash.
py::handle gErrorBase;
py::handle gErrorBadInput, gErrorUsage, gErrorIo;  // code 'interrupted' (not raised by these calls) maps to Error

py::object jsonModule() { return py::module_::import("json"); }

// Raises the specula.Error subclass of the code, with code/pointer/suggestion/message attributes.
void raiseError(const specula::Error& e) {
    py::handle cls = gErrorBase;
    switch (e.code()) {
        case ErrorCode::BadInput: cls = gErrorBadInput; break;
        case ErrorCode::Usage: cls = gErrorUsage; break;
        case ErrorCode::Io: cls = gErrorIo; break;
        default: break;
    }
    py::object inst = cls(e.what(), specula::errorCodeName(e.code()), e.pointer(), e.suggestion(), e.message(),
                          e.exitCode());
    PyErr_SetObject(cls.ptr(), inst.ptr());
}

[[noreturn]] void throwUsage(const std::string& message) { throw specula::Error(ErrorCode::Usage, "", message); }

// A loaded scene plus a render counter: set() while a render of this scene runs (from another Python thread, since
// render releases the GIL) would modify what the workers read, so it is refused instead.
struct PyScene {
    sp::Scene scene;
    std::atomic<int> rendering{0};
};

// A render's result, shared by the NumPy views handed out (each view keeps the PyResult alive through its base).
struct PyResult {
    sp::RenderResult result;
};

sp::LoadOptions loadOptionsOf(std::optional<int> spp, std::optional<int64_t> seed, std::optional<int> width,
                              std::optional<int> height, std::optional<std::vector<int>> crop,
                              std::optional<std::map<std::string, int64_t>> limits, std::optional<int> frame) {
    sp::LoadOptions o;
    if (frame) o.hasFrame = true, o.frame = *frame;
    if (limits)  // the CLI's --limit names (LoadOptions::setLimit): a bad one raises UsageError naming the nearest
        for (const auto& [name, value] : *limits) o.setLimit(name, value);
    if (spp) {
        if (*spp <= 0) throwUsage("spp must be positive");
        o.spp = *spp;
    }
    if (seed) {
        if (*seed < 0) throwUsage("seed must be non-negative");
        o.seed = *seed;
    }
    if (width) {
        if (*width <= 0) throwUsage("width must be positive");
        o.width = *width;
    }
    if (height) {
        if (*height <= 0) throwUsage("height must be positive");
        o.height = *height;
    }
    if (crop) {
        if (crop->size() != 4) throwUsage("crop is (x0, y0, x1, y1)");
        o.cropX0 = (*crop)[0], o.cropY0 = (*crop)[1], o.cropX1 = (*crop)[2], o.cropY1 = (*crop)[3];
    }
    return o;
}

std::unique_ptr<PyScene> loadString(const std::string& text, const std::string& baseDir, const sp::LoadOptions& o,
                                    const std::string& name) {
    auto s = std::make_unique<PyScene>();
    py::gil_scoped_release nogil;  // loading builds geometry and compiles materials: let other threads run
    s->scene = sp::Scene::fromString(text, baseDir, o, name);
    return s;
}

// The AOV as a read-only (H, W, C) float32 view into the result; 'owner' (the Python RenderResult) is its base.
py::array aovArray(const sp::AovView& v, py::handle owner) {
    const py::ssize_t c = v.channels(), w = v.width, h = v.height, f = sizeof(float);
    py::array_t<float> a({h, w, c}, {w * c * f, c * f, f}, v.pixels, owner);
    // Read-only: the result's buffers are also what write() saves; a writable array is one .copy() away.
    py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    return std::move(a);
}

py::dict tileDict(const sp::Tile& t) {
    py::dict d;
    d["x0"] = t.x0, d["y0"] = t.y0, d["x1"] = t.x1, d["y1"] = t.y1;
    d["origin_x"] = t.originX, d["origin_y"] = t.originY;
    d["tiles_done"] = t.tilesDone, d["tiles_total"] = t.tilesTotal;
    d["elapsed"] = t.elapsedSeconds, d["samples_per_second"] = t.samplesPerSecond, d["eta"] = t.etaSeconds;
    return d;
}

// Renders with the GIL released. The progress callback runs on a render worker thread and takes the GIL for the
// call only. Ctrl-C: CPython runs signal handlers only on the main thread, so the waiting (main) thread polls
// PyErr_CheckSignals() every few milliseconds; a KeyboardInterrupt (or any exception of the callback) cancels the
// job, waits for the workers to stop, then propagates.
std::unique_ptr<PyResult> render(PyScene& self, py::object progress, int threads) {
    sp::RenderOptions ro;
    ro.threads = threads;

    struct Shared {
        std::mutex m;
        std::exception_ptr pending;  // the first Python exception of the callback
        std::atomic<bool> stop{false};
    };
    auto shared = std::make_shared<Shared>();
    sp::TileCallback cb;
    if (!progress.is_none()) {
        if (!PyCallable_Check(progress.ptr())) throw py::type_error("progress must be callable or None");
        // A borrowed PyObject*, not a py::object: the std::function is copied and destroyed without the GIL (in
        // renderAsync and the job), where a py::object's reference counting would race. 'progress' (this call's
        // argument) keeps the callable alive until the job is joined.
        PyObject* fn = progress.ptr();
        cb = [shared, fn](const sp::Tile& t) -> bool {
            if (shared->stop) return false;
            py::gil_scoped_acquire gil;
            try {
                py::object r = py::handle(fn)(tileDict(t));
                // Only an explicit False cancels (None, the result of a function without return, goes on).
                if (r.ptr() == Py_False) return false;
                return true;
            } catch (...) {
                std::lock_guard<std::mutex> lock(shared->m);
                if (!shared->pending) shared->pending = std::current_exception();
                shared->stop = true;
                return false;
            }
        };
    }

    struct Busy {  // counts this render on the scene for set()'s check
        PyScene& s;
        explicit Busy(PyScene& s) : s(s) { ++s.rendering; }
        ~Busy() { --s.rendering; }
    } busy(self);

    auto out = std::make_unique<PyResult>();
    std::exception_ptr interrupt;
    {
        py::gil_scoped_release nogil;
        sp::RenderJob job = self.scene.renderAsync(ro, cb);
        while (!job.done()) {
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
            if (shared->stop) break;
            py::gil_scoped_acquire gil;
            if (PyErr_CheckSignals() != 0) {
                try {
                    throw py::error_already_set();  // takes the KeyboardInterrupt (or the handler's exception)
                } catch (...) {
                    interrupt = std::current_exception();
                }
                break;
            }
        }
        if (interrupt || shared->stop) job.cancel();
        out->result = job.wait();  // an Error of the render propagates (translated) after the GIL is back
    }
    if (interrupt) std::rethrow_exception(interrupt);
    {
        // A signal that arrived after the workers finished still interrupts (as Python would after any call).
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
    if (shared->pending) std::rethrow_exception(shared->pending);
    return out;
}

}  // namespace

PYBIND11_MODULE(specula, m) {
    m.doc() = "Specula: glint, LEAN, filtered-GGX and P-NDF shading nodes and a CPU renderer (docs/python.md).";
    m.attr("__version__") = sp::version();

    // The exception hierarchy, in Python so that it pickles, subclasses and prints like any Python exception.
    py::dict ns;
    ns["__builtins__"] = py::module_::import("builtins");
    ns["__name__"] = "specula";
    py::exec(R"(
class Error(Exception):
    """A libspecula error.

    Attributes: code ('bad_input', 'usage', 'io', 'interrupted'), exit_code (the `specula` CLI's exit code for it),
    pointer (JSON pointer of the offending value, '' when none), suggestion ("did you mean" name, '' when none),
    message (without pointer and suggestion). str(e) is '<pointer>: <message> (did you mean '<suggestion>'?)'.
    """
    def __init__(self, what, code='bad_input', pointer='', suggestion='', message='', exit_code=1):
        super().__init__(what)
        self.code, self.pointer, self.suggestion = code, pointer, suggestion
        self.message, self.exit_code = message or what, exit_code

class BadInputError(Error):
    """An invalid scene, value or name (code 'bad_input')."""

class UsageError(Error):
    """A call the API refuses, e.g. an output path ending in neither .exr nor .png (code 'usage')."""

class IoError(Error):
    """A file that cannot be read or a folder that does not exist (code 'io')."""
)", ns);
    for (const char* n : {"Error", "BadInputError", "UsageError", "IoError"}) {
        m.attr(n) = ns[n];
        m.attr(n).attr("__module__") = "specula";
    }
    gErrorBase = py::object(m.attr("Error")).release();
    gErrorBadInput = py::object(m.attr("BadInputError")).release();
    gErrorUsage = py::object(m.attr("UsageError")).release();
    gErrorIo = py::object(m.attr("IoError")).release();
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const specula::Error& e) {
            raiseError(e);
        }
    });

    m.def(
        "nodes",
        []() -> py::object { return jsonModule().attr("loads")(sp::nodeCatalogJson(-1))["nodes"]; },
        "The node catalogue: a list of dicts {id, version, category, doc, inputs, outputs, ...}, the JSON of\n"
        "`specula nodes --json`.");
    m.def(
        "node_catalog_json", [](int indent) { return sp::nodeCatalogJson(indent); }, py::arg("indent") = 2,
        "The node catalogue as JSON text ({\"nodes\": [...]}); indent -1: one line.");

    py::class_<sp::RenderStats>(m, "RenderStats", "Counters of a finished (or cancelled) render.")
        .def_readonly("samples", &sp::RenderStats::samples, "Camera samples taken.")
        .def_readonly("invalid_samples", &sp::RenderStats::invalidSamples, "Samples discarded as NaN/Inf.")
        .def_readonly("seconds", &sp::RenderStats::seconds, "Wall-clock render time.")
        .def_readonly("tiles_done", &sp::RenderStats::tilesDone)
        .def_readonly("tiles_total", &sp::RenderStats::tilesTotal)
        .def_readonly("cancelled", &sp::RenderStats::cancelled, "True if the render was cancelled (partial image).")
        .def("__repr__", [](const sp::RenderStats& s) {
            return "RenderStats(samples=" + std::to_string(s.samples) + ", seconds=" + std::to_string(s.seconds) +
                   ", tiles=" + std::to_string(s.tilesDone) + "/" + std::to_string(s.tilesTotal) +
                   ", cancelled=" + (s.cancelled ? "True" : "False") + ")";
        });

    py::class_<PyResult>(m, "RenderResult",
                         "A rendered image: its AOVs as NumPy arrays and its stats. result['beauty'] is a read-only\n"
                         "float32 view (H, W, C) that keeps the result alive; use .copy() for a writable array.")
        .def_property_readonly("width", [](const PyResult& r) { return r.result.width(); })
        .def_property_readonly("height", [](const PyResult& r) { return r.result.height(); })
        .def_property_readonly("stats", [](const PyResult& r) { return r.result.stats(); },
                               "RenderStats: samples, invalid_samples, seconds, tiles_done, tiles_total, cancelled.")
        .def_property_readonly("aovs", [](const PyResult& r) { return r.result.aovNames(); },
                               "AOV names: beauty, diffuse, specular, albedo, normal, uv, depth.")
        .def(
            "channels", [](const PyResult& r, const std::string& name) { return r.result.aov(name).channelNames; },
            py::arg("aov"), "Channel names of an AOV, e.g. ['R', 'G', 'B'] or ['Z'].")
        .def(
            "__getitem__",
            [](py::object self, const std::string& name) {
                return aovArray(self.cast<PyResult&>().result.aov(name), self);
            },
            py::arg("aov"),
            "The AOV as a read-only float32 NumPy array (height, width, channels), scene-linear, rows top to\n"
            "bottom; a view into this result (it stays alive while the array does). Unknown name: specula.Error.")
        .def("__contains__",
             [](const PyResult& r, const std::string& name) {
                 for (const auto& n : r.result.aovNames())
                     if (n == name) return true;
                 return false;
             })
        .def("__iter__", [](const PyResult& r) { return py::iter(py::cast(r.result.aovNames())); })
        .def(
            "write",
            [](const PyResult& r, const PyScene& scene, const std::string& path) {
                sp::WrittenOutputs w;
                {
                    py::gil_scoped_release nogil;
                    w = scene.scene.writeOutputs(r.result, path);
                }
                py::dict d;
                d["exr"] = w.exr.empty() ? py::object(py::none()) : py::object(py::str(w.exr)), d["png"] = w.png.empty() ? py::object(py::none()) : py::object(py::str(w.png));
                d["partial"] = w.partial;
                return d;
            },
            py::arg("scene"), py::arg("path"),
            "Writes PATH (.exr, every AOV) and its PNG beside it, or PATH (.png) alone, atomically; a cancelled render\n"
            "writes only PATH.partial.exr (never over PATH). Returns {'exr': path or None, 'png': path or None,\n"
            "'partial': bool}. Errors: UsageError for a path ending in neither .exr nor .png, IoError for a missing folder.")
        .def("__repr__", [](const PyResult& r) {
            return "<specula.RenderResult " + std::to_string(r.result.width()) + "x" +
                   std::to_string(r.result.height()) + (r.result.stats().cancelled ? " cancelled>" : ">");
        });

    py::class_<PyScene>(m, "Scene",
                        "A loaded scene (geometry, camera, lights, compiled materials). Build with Scene.from_file,\n"
                        "Scene.from_dict or Scene.from_json.")
        .def_static(
            "from_file",
            [](const std::string& path, std::optional<int> spp, std::optional<int64_t> seed, std::optional<int> width,
               std::optional<int> height, std::optional<std::vector<int>> crop,
               std::optional<std::map<std::string, int64_t>> limits, std::optional<int> frame) {
                sp::LoadOptions o = loadOptionsOf(spp, seed, width, height, crop, limits, frame);
                auto s = std::make_unique<PyScene>();
                py::gil_scoped_release nogil;
                s->scene = sp::Scene::fromFile(path, o);
                return s;
            },
            py::arg("path"), py::kw_only(), py::arg("spp") = py::none(), py::arg("seed") = py::none(),
            py::arg("width") = py::none(), py::arg("height") = py::none(), py::arg("crop") = py::none(),
            py::arg("limits") = py::none(), py::arg("frame") = py::none(),
            "Loads a scene file (docs/graph-format.md). spp, seed, width, height and crop=(x0, y0, x1, y1) override\n"
            "the file (and keep overriding it across set()). limits={'pixels': N, 'spp': N, ...} caps what the scene\n"
            "may ask for (the names of `specula render --limit`). frame=N evaluates the scene's animation at frame N\n"
            "(`specula render --frame`; default frame_start). A missing file raises IoError, an invalid scene or\n"
            "one beyond a cap BadInputError with the JSON pointer of the bad value.")
        .def_static(
            "from_dict",
            [](py::object d, const std::string& baseDir, std::optional<int> spp, std::optional<int64_t> seed,
               std::optional<int> width, std::optional<int> height, std::optional<std::vector<int>> crop,
               std::optional<std::map<std::string, int64_t>> limits, std::optional<int> frame) {
                std::string text = jsonModule().attr("dumps")(d).cast<std::string>();
                return loadString(text, baseDir, loadOptionsOf(spp, seed, width, height, crop, limits, frame), "<dict>");
            },
            py::arg("scene"), py::arg("base_dir") = ".", py::kw_only(), py::arg("spp") = py::none(),
            py::arg("seed") = py::none(), py::arg("width") = py::none(), py::arg("height") = py::none(),
            py::arg("crop") = py::none(), py::arg("limits") = py::none(), py::arg("frame") = py::none(),
            "Loads a scene from a dict of the scene format (serialised with json.dumps); base_dir resolves relative\n"
            "paths (textures, meshes). Overrides as for from_file.")
        .def_static(
            "from_json",
            [](const std::string& text, const std::string& baseDir, std::optional<int> spp, std::optional<int64_t> seed,
               std::optional<int> width, std::optional<int> height, std::optional<std::vector<int>> crop,
               std::optional<std::map<std::string, int64_t>> limits, std::optional<int> frame) {
                return loadString(text, baseDir, loadOptionsOf(spp, seed, width, height, crop, limits, frame), "<string>");
            },
            py::arg("text"), py::arg("base_dir") = ".", py::kw_only(), py::arg("spp") = py::none(),
            py::arg("seed") = py::none(), py::arg("width") = py::none(), py::arg("height") = py::none(),
            py::arg("crop") = py::none(), py::arg("limits") = py::none(), py::arg("frame") = py::none(), "Loads a scene from JSON text; as from_dict.")
        .def(
            "set",
            [](PyScene& self, const std::string& pointer, py::object value) {
                std::string text = jsonModule().attr("dumps")(value).cast<std::string>();
                if (self.rendering > 0) throwUsage("set() while a render of this scene is running");
                py::gil_scoped_release nogil;
                self.scene.setValue(pointer, text);
            },
            py::arg("pointer"), py::arg("value"),
            "Sets one value of the scene document by JSON pointer, e.g. set('/render/spp', 8) or\n"
            "set('/materials/gold/nodes/s/inputs/roughness', 0.3); '/-' appends to an array. value: anything\n"
            "json.dumps accepts. A material literal recompiles that material only; anything else re-loads the\n"
            "edited document. On error (BadInputError with the pointer, and a suggestion for a misspelt key) the\n"
            "scene is unchanged.")
        .def_property_readonly(
            "document", [](const PyScene& s) { return jsonModule().attr("loads")(s.scene.json(-1)); },
            "The scene document as a dict, with every set() applied.")
        .def_property_readonly("materials", [](const PyScene& s) { return s.scene.materialNames(); })
        .def_property_readonly("warnings", [](const PyScene& s) { return s.scene.warnings(); },
                               "Warnings of loading and set(): '<pointer>: <message>'.")
        .def("render", &render, py::arg("progress") = py::none(), py::arg("threads") = 0,
             "Renders the scene and returns a RenderResult. The GIL is released while rendering.\n\n"
             "progress(tile) is called once per finished tile, serially, on a render thread, with a dict\n"
             "{x0, y0, x1, y1 (frame pixels, x1/y1 exclusive), origin_x, origin_y, tiles_done, tiles_total,\n"
             "elapsed, samples_per_second, eta}; returning False cancels (the result then has\n"
             "stats.cancelled True and a partial image). An exception in the callback cancels the render and is\n"
             "re-raised once the workers stopped. Ctrl-C (SIGINT) cancels and raises KeyboardInterrupt.\n"
             "threads: 0 = all cores (the image does not depend on it).")
        .def(
            "glsl",
            [](const PyScene& s, std::optional<std::string> material, bool inlineLiterals) {
                sp::GlslModule g;
                {
                    py::gil_scoped_release nogil;
                    g = s.scene.compileGlsl(material.value_or(""), !inlineLiterals);
                }
                return py::make_tuple(g.source, jsonModule().attr("loads")(g.resourcesJson));
            },
            py::arg("material") = py::none(), py::kw_only(), py::arg("inline") = false,
            "The GLSL 4.50 module of a material (None: the only one) and its resource manifest as a dict\n"
            "(docs/graph-format.md, 'Resources'). inline=True inlines the literals instead of a uniform block.")
        .def("__repr__", [](const PyScene& s) {
            std::string r = "<specula.Scene materials=[";
            bool first = true;
            for (const auto& n : s.scene.materialNames()) r += (first ? "'" : ", '") + n + "'", first = false;
            return r + "]>";
        });
}
