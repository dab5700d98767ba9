// The viewer's loop: GLFW window and input (orbit camera in the manner of MaterialXView: left drag orbits, right
// drag pans, the wheel dollies), polling of the watched files with a one-poll debounce, the reload that keeps the
// last good scene, the display pass, screenshots and JSON events.
#define GL_GLEXT_PROTOTYPES 1
#include "plugin/preview/viewer.h"

#include "core/api/specula.h"
#include "core/color/color_config.h"
#include "core/io/image_io.h"
#include "core/render/camera.h"
#include "core/util/error.h"
#include "plugin/preview/display.h"
#include "plugin/preview/preview.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

namespace fs = std::filesystem;

namespace specula::preview {

namespace {

using Clock = std::chrono::steady_clock;

void emit(bool on, const nlohmann::json& event) {
    if (!on) return;
    std::printf("%s\n", event.dump().c_str());
    std::fflush(stdout);
}

// Every file a reload depends on: the scene and each string of its document that names an existing file beside it
// (textures, meshes, environment maps). An explicit stack: the loader bounds the document's depth, this never recurses.
std::vector<fs::path> watchedFiles(const std::string& scenePath, const std::string& baseDir) {
    std::vector<fs::path> files{fs::path(scenePath)};
    std::ifstream f(scenePath, std::ios::binary);
    nlohmann::json doc = nlohmann::json::parse(f, nullptr, false);
    if (doc.is_discarded()) return files;
    std::vector<const nlohmann::json*> stack{&doc};
    while (!stack.empty()) {
        const nlohmann::json* j = stack.back();
        stack.pop_back();
        if (j->is_structured()) {
            for (const auto& child : *j) stack.push_back(&child);
        } else if (j->is_string()) {
            const std::string& s = j->get_ref<const std::string&>();
            if (s.empty() || s.size() > 4096) continue;
            std::error_code ec;
            fs::path p = fs::path(s).is_absolute() ? fs::path(s) : fs::path(baseDir) / s;
            if (fs::is_regular_file(p, ec) && std::find(files.begin(), files.end(), p) == files.end()) files.push_back(p);
        }
    }
    return files;
}

// What changes when a watched file is written: its modification time and size (a missing file counts as a state).
std::vector<std::pair<long long, long long>> signature(const std::vector<fs::path>& files) {
    std::vector<std::pair<long long, long long>> sig;
    for (const fs::path& p : files) {
        std::error_code ec;
        auto t = fs::last_write_time(p, ec);
        const long long mtime = ec ? -1 : (long long)t.time_since_epoch().count();
        const auto size = fs::file_size(p, ec);
        sig.emplace_back(mtime, ec ? -1 : (long long)size);
    }
    return sig;
}

// An orbit about the scene camera's look-at point, around its up axis; until the user moves it, the camera is the
// scene's own (so that a screenshot is the `specula preview` image).
struct Orbit {
    CameraDesc base;  // the scene's camera
    bool moved = false;
    Vec3 target{0.f}, e1{1, 0, 0}, e2{0, 1, 0}, up{0, 0, 1};
    float distance = 1.f, yaw = 0.f, pitch = 0.f;

    void reset(const CameraDesc& scene) {
        base = scene;
        moved = false;
        up = glm::normalize(scene.up);
        target = scene.lookAt;
        Vec3 offset = scene.position - scene.lookAt;
        distance = std::max(glm::length(offset), 1e-4f);
        // Any axis perpendicular to up as the yaw origin.
        const Vec3 a = std::abs(up.x) < 0.9f ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
        e1 = glm::normalize(a - up * glm::dot(a, up));
        e2 = glm::cross(up, e1);
        const Vec3 o = offset / distance;
        yaw = std::atan2(glm::dot(o, e2), glm::dot(o, e1));
        pitch = std::asin(std::clamp(glm::dot(o, up), -1.f, 1.f));
    }
    CameraDesc camera() const {
        if (!moved) return base;
        CameraDesc c = base;
        const float lim = 1.55f;  // keep clear of the pole, where the up axis would flip the image
        const float p = std::clamp(pitch, -lim, lim);
        c.position = target + distance * (std::cos(p) * (std::cos(yaw) * e1 + std::sin(yaw) * e2) + std::sin(p) * up);
        c.lookAt = target;
        c.up = up;
        return c;
    }
};

bool sameCamera(const CameraDesc& a, const CameraDesc& b) {
    return a.position == b.position && a.lookAt == b.lookAt && a.up == b.up && a.fovDegrees == b.fovDegrees &&
           a.fovIsHorizontal == b.fovIsHorizontal && a.apertureRadius == b.apertureRadius &&
           a.focusDistance == b.focusDistance;
}

enum class Aov { Beauty = 0, Diffuse = 1, Specular = 2, Normal = 3 };
const char* aovName(Aov a) {
    switch (a) {
        case Aov::Diffuse: return "diffuse";
        case Aov::Specular: return "specular";
        case Aov::Normal: return "normal";
        default: return "beauty";
    }
}

struct Loaded {
    std::unique_ptr<PreviewScene> scene;
    std::unique_ptr<PreviewRenderer> renderer;
};

struct Viewer {
    const ViewerOptions& opt;
    GLFWwindow* window = nullptr;
    Loaded current;
    std::unique_ptr<DisplayPass> display;
    std::vector<std::string> views;
    std::string view;  // the OCIO view shown (starts as the scene's)
    float exposure = 0.f;
    Aov aov = Aov::Beauty;
    Orbit orbit;
    bool dirty = true, screenshotKey = false, drawn = false;
    int generation = 0;
    std::string reloadError;
    double lastGpuMs = 0.0;
    // Mouse drag state.
    bool rotating = false, panning = false;
    double lastX = 0.0, lastY = 0.0;
    int fbWidth = 1, fbHeight = 1;

    explicit Viewer(const ViewerOptions& o) : opt(o) {}

    // 'ps': the scene already read from its files (the first one, read before the window exists), else read here.
    void load(std::unique_ptr<PreviewScene> ps = nullptr) {
        const auto t0 = Clock::now();
        if (!ps) ps = std::make_unique<PreviewScene>(loadPreviewScene(opt.scenePath, opt.overrides));
        auto renderer = std::make_unique<PreviewRenderer>(ps->scene, ps->materials, ps->baseDir);
        const bool first = !current.scene;
        const bool cameraChanged = first || !sameCamera(ps->scene.camera, current.scene->scene.camera);
        std::string newView = first || ps->scene.color.view != current.scene->scene.color.view ? ps->scene.color.view : view;
        const float newExposure = first || ps->scene.color.exposure != current.scene->scene.color.exposure
                                      ? ps->scene.color.exposure
                                      : exposure;
        auto newDisplay = std::make_unique<DisplayPass>(*ps->scene.colorConfig, newView, newExposure);
        for (const std::string& w : ps->scene.warnings) std::fprintf(stderr, "specula: warning: %s\n", w.c_str());
        for (const std::string& w : renderer->warnings()) std::fprintf(stderr, "specula: warning: %s\n", w.c_str());
        // Everything built: the new scene replaces the old one (the renderer first: it refers to its scene).
        current.renderer.reset();
        current.scene = std::move(ps);
        current.renderer = std::move(renderer);
        display = std::move(newDisplay);
        view = newView;
        exposure = newExposure;
        views = current.scene->scene.colorConfig->views();
        if (view.empty()) view = current.scene->scene.colorConfig->defaultView();
        if (cameraChanged) orbit.reset(current.scene->scene.camera);
        if (!first && opt.overrides.width == 0) {
            const int W = current.scene->scene.render.width, H = current.scene->scene.render.height;
            int w = 0, h = 0;
            glfwGetWindowSize(window, &w, &h);
            if (w != W || h != H) glfwSetWindowSize(window, W, H);
        }
        ++generation;
        reloadError.clear();
        dirty = true;
        emit(opt.events, {{"event", "loaded"}, {"generation", generation}, {"scene", opt.scenePath},
                          {"renderer", reinterpret_cast<const char*>(glGetString(GL_RENDERER))},
                          {"seconds", std::chrono::duration<double>(Clock::now() - t0).count()}});
    }

    void rebuildDisplay() {
        display = std::make_unique<DisplayPass>(*current.scene->scene.colorConfig, view, exposure);
        dirty = true;
    }

    void updateTitle() {
        char buf[512];
        std::snprintf(buf, sizeof buf, "specula view: %s (%s, view %s, %+.1f EV, %.2f ms)%s%s",
                      fs::path(opt.scenePath).filename().c_str(), aovName(aov), view.c_str(), double(exposure),
                      lastGpuMs, reloadError.empty() ? "" : " - reload failed: ",
                      reloadError.substr(0, 200).c_str());
        glfwSetWindowTitle(window, buf);
    }

    void drawFrame() {
        glfwGetFramebufferSize(window, &fbWidth, &fbHeight);
        if (fbWidth < 1 || fbHeight < 1) return;  // minimised
        lastGpuMs = current.renderer->draw(orbit.camera(), fbWidth, fbHeight) * 1e-6;
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        display->draw(current.renderer->aovTexture(int(aov)), fbWidth, fbHeight,
                      aov == Aov::Normal ? DisplayPass::Mode::Normal : DisplayPass::Mode::Colour);
        drawn = true;
    }

    // The last frame, before the buffers swap: .png the window's pixels as shown, .exr the AOVs (and the CPU's PNG
    // beside them, by the render's output policy). Both atomic.
    void screenshot() {
        if (!drawn) return;
        const std::string& path = opt.screenshotPath;
        if (fs::path(path).extension() == ".png") {
            std::vector<unsigned char> px(size_t(fbWidth) * fbHeight * 3);
            glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
            glReadBuffer(GL_BACK);
            glPixelStorei(GL_PACK_ALIGNMENT, 1);
            glReadPixels(0, 0, fbWidth, fbHeight, GL_RGB, GL_UNSIGNED_BYTE, px.data());
            std::vector<float> rows(px.size());
            for (int y = 0; y < fbHeight; ++y)  // GL row 0 is the bottom
                for (size_t i = 0; i < size_t(fbWidth) * 3; ++i)
                    rows[size_t(y) * fbWidth * 3 + i] = float(px[size_t(fbHeight - 1 - y) * fbWidth * 3 + i]) / 255.f;
            const std::string tmp = createTempFileNear(path);
            try {
                writeImage8(tmp, fbWidth, fbHeight, 3, rows.data(), "specula view");
            } catch (...) {
                std::error_code ec;
                fs::remove(tmp, ec);
                throw;
            }
            commitTempFile(tmp, path);
        } else {
            ImageSet img = current.renderer->readBack();
            img.metadata["specula:renderer"] = std::string("view (") + reinterpret_cast<const char*>(glGetString(GL_RENDERER)) + ")";
            img.metadata["specula:spp"] = "1";
            img.metadata["specula:version"] = SPECULA_VERSION;
            RenderStats stats;
            stats.samples = uint64_t(fbWidth) * fbHeight;
            stats.tilesDone = stats.tilesTotal = 1;
            writeRenderResult(path, current.scene->scene, img, stats);
        }
        std::fprintf(stderr, "specula: wrote %s\n", path.c_str());
        emit(opt.events, {{"event", "screenshot"}, {"path", path}, {"generation", generation}});
    }
};

Viewer* self(GLFWwindow* w) { return static_cast<Viewer*>(glfwGetWindowUserPointer(w)); }

void onKey(GLFWwindow* w, int key, int, int action, int) {
    if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
    Viewer& v = *self(w);
    switch (key) {
        case GLFW_KEY_ESCAPE:
        case GLFW_KEY_Q: glfwSetWindowShouldClose(w, GLFW_TRUE); break;
        case GLFW_KEY_1: v.aov = Aov::Beauty, v.dirty = true; break;
        case GLFW_KEY_2: v.aov = Aov::Diffuse, v.dirty = true; break;
        case GLFW_KEY_3: v.aov = Aov::Specular, v.dirty = true; break;
        case GLFW_KEY_4: v.aov = Aov::Normal, v.dirty = true; break;
        case GLFW_KEY_R: v.orbit.moved = false, v.dirty = true; break;  // back to the scene's camera
        case GLFW_KEY_EQUAL:
        case GLFW_KEY_KP_ADD: v.exposure += 0.5f, v.rebuildDisplay(); break;
        case GLFW_KEY_MINUS:
        case GLFW_KEY_KP_SUBTRACT: v.exposure -= 0.5f, v.rebuildDisplay(); break;
        case GLFW_KEY_V:
            if (!v.views.empty()) {
                auto it = std::find(v.views.begin(), v.views.end(), v.view);
                v.view = (it == v.views.end() || it + 1 == v.views.end()) ? v.views.front() : *(it + 1);
                v.rebuildDisplay();
            }
            break;
        case GLFW_KEY_S: v.screenshotKey = true; break;
        default: break;
    }
}

void onMouseButton(GLFWwindow* w, int button, int action, int) {
    Viewer& v = *self(w);
    const bool down = action == GLFW_PRESS;
    if (button == GLFW_MOUSE_BUTTON_LEFT) v.rotating = down;
    if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) v.panning = down;
    glfwGetCursorPos(w, &v.lastX, &v.lastY);
}

void onCursor(GLFWwindow* w, double x, double y) {
    Viewer& v = *self(w);
    const double dx = x - v.lastX, dy = y - v.lastY;
    v.lastX = x, v.lastY = y;
    if (!v.rotating && !v.panning) return;
    if (!v.orbit.moved) {
        v.orbit.reset(v.orbit.base);
        v.orbit.moved = true;
    }
    int ww = 1, wh = 1;
    glfwGetWindowSize(w, &ww, &wh);
    if (v.rotating) {
        v.orbit.yaw -= float(dx) * 0.01f;
        v.orbit.pitch = std::clamp(v.orbit.pitch + float(dy) * 0.01f, -1.55f, 1.55f);
    } else {
        // One pixel of drag moves the target by one pixel's footprint at the target's distance.
        PerspectiveCamera cam(v.orbit.camera(), std::max(ww, 1), std::max(wh, 1));
        const float perPixel = 2.f * cam.halfWidth() * v.orbit.distance / float(std::max(ww, 1));
        v.orbit.target += (-float(dx) * cam.right() + float(dy) * cam.up()) * perPixel;
    }
    v.dirty = true;
}

void onScroll(GLFWwindow* w, double, double yoff) {
    Viewer& v = *self(w);
    if (!v.orbit.moved) {
        v.orbit.reset(v.orbit.base);
        v.orbit.moved = true;
    }
    v.orbit.distance = std::max(v.orbit.distance * std::pow(0.9f, float(yoff)), 1e-4f);
    v.dirty = true;
}

void onResize(GLFWwindow* w, int, int) { self(w)->dirty = true; }
void onRefresh(GLFWwindow* w) { self(w)->dirty = true; }

void onGlfwError(int code, const char* what) { std::fprintf(stderr, "specula: GLFW error %d: %s\n", code, what); }

}  // namespace

int runViewer(const ViewerOptions& opt, const std::atomic<bool>& stop) {
    Viewer v(opt);
    glfwSetErrorCallback(onGlfwError);
    if (!glfwInit()) {
        std::fprintf(stderr, "specula: error: no window system for `specula view` (is DISPLAY set? under CI run it as "
                             "xvfb-run -s '-screen 0 1920x1080x24' specula view ...; `specula preview` needs no window)\n");
        return kExitIo;
    }
    struct Terminate {
        ~Terminate() { glfwTerminate(); }
    } terminate;
    int exitCode = kExitOk;
    try {
        // The scene is read before the context exists (reading needs no GL, building its renderer does): its
        // resolution (or the override, which the loader applied) is the window's first size.
        auto first = std::make_unique<PreviewScene>(loadPreviewScene(opt.scenePath, opt.overrides));
        const int W = first->scene.render.width, H = first->scene.render.height;
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_FALSE);
        glfwWindowHint(GLFW_DOUBLEBUFFER, GLFW_TRUE);
        v.window = glfwCreateWindow(W, H, "specula view", nullptr, nullptr);
        if (!v.window) throw IoError("cannot open a window with an OpenGL 4.5 core context");
        glfwMakeContextCurrent(v.window);
        glfwSwapInterval(1);
        glfwSetWindowUserPointer(v.window, &v);
        glfwSetKeyCallback(v.window, onKey);
        glfwSetMouseButtonCallback(v.window, onMouseButton);
        glfwSetCursorPosCallback(v.window, onCursor);
        glfwSetScrollCallback(v.window, onScroll);
        glfwSetFramebufferSizeCallback(v.window, onResize);
        glfwSetWindowRefreshCallback(v.window, onRefresh);
        v.load(std::move(first));
        std::vector<fs::path> watched = watchedFiles(opt.scenePath, v.current.scene->baseDir);
        auto loadedSig = signature(watched), lastSig = loadedSig;
        auto nextPoll = Clock::now();
        int frames = 0;
        bool announced = false;
        while (!glfwWindowShouldClose(v.window) && !stop.load()) {
            if (opt.exitAfterFrames > 0)
                glfwPollEvents();
            else
                glfwWaitEventsTimeout(std::min(opt.pollSeconds, 0.25));  // also how often 'stop' is seen
            if (Clock::now() >= nextPoll) {
                nextPoll = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(opt.pollSeconds));
                auto sig = signature(watched);
                // Reload once the files have stood still for one poll (an editor's save is several writes).
                if (sig != loadedSig && sig == lastSig) {
                    loadedSig = sig;
                    try {
                        v.load();
                        announced = false;
                        watched = watchedFiles(opt.scenePath, v.current.scene->baseDir);
                        loadedSig = lastSig = sig = signature(watched);
                    } catch (const std::exception& e) {
                        v.reloadError = e.what();
                        std::fprintf(stderr, "specula: error: reload failed (the last good scene stays): %s\n", e.what());
                        emit(opt.events, {{"event", "reload_failed"}, {"message", e.what()}, {"code", exitCodeFor(e)}});
                        v.dirty = true;
                    }
                }
                lastSig = sig;
            }
            if (v.dirty || opt.exitAfterFrames > 0) {
                v.dirty = false;
                v.drawFrame();
                v.updateTitle();
                ++frames;
                if (!announced) {
                    announced = true;
                    emit(opt.events, {{"event", "shown"}, {"generation", v.generation}, {"width", v.fbWidth},
                                      {"height", v.fbHeight}, {"gpu_ms", v.lastGpuMs}});
                }
                const bool last = opt.exitAfterFrames > 0 && frames >= opt.exitAfterFrames;
                if ((v.screenshotKey || last) && !opt.screenshotPath.empty()) v.screenshot();
                if (v.screenshotKey && opt.screenshotPath.empty())
                    std::fprintf(stderr, "specula: no --screenshot path was given; key S has nothing to write\n");
                v.screenshotKey = false;
                glfwSwapBuffers(v.window);
                if (last) break;
            } else if (v.screenshotKey) {
                v.dirty = true;  // drawn (and written) on the next pass
            }
        }
        // Closed or stopped before exit-after: the last frame as the screenshot.
        if ((glfwWindowShouldClose(v.window) || stop.load()) && !opt.screenshotPath.empty() &&
            !(opt.exitAfterFrames > 0 && frames >= opt.exitAfterFrames)) {
            v.drawFrame();
            v.screenshot();
        }
        emit(opt.events, {{"event", "closed"}, {"frames", frames}});
    } catch (const std::exception& e) {
        std::fprintf(stderr, "specula: error: %s\n", e.what());
        exitCode = exitCodeFor(e);
    }
    v.display.reset();
    v.current.renderer.reset();
    if (v.window) glfwDestroyWindow(v.window);
    return exitCode;
}

}  // namespace specula::preview
