// Tile-based parallel rendering (TBB) of a Scene into AOV buffers, with per-tile progress callbacks,
// cooperative cancellation, NaN/Inf accounting and a thread-count-independent result.
#pragma once

#include "core/io/image_io.h"

#include <atomic>
#include <cstdint>
#include <functional>

namespace specula {

struct Scene;

struct RenderProgress {
    int tilesDone = 0, tilesTotal = 0;
    int tileX0 = 0, tileY0 = 0, tileX1 = 0, tileY1 = 0;  // the tile just finished
    double elapsedSeconds = 0;
    double samplesPerSecond = 0;
    double etaSeconds = 0;
    // The buffers being filled (image = the crop window: pixel (x, y) of the frame is (x - originX, y - originY)).
    // The finished tile's pixels are final when onTile runs; other tiles may be in flight.
    const ImageSet* images = nullptr;
    int originX = 0, originY = 0;
};

struct RenderStats {
    uint64_t samples = 0;         // camera samples taken
    uint64_t invalidSamples = 0;  // NaN/Inf samples (counted, never accumulated)
    uint64_t batchedSamples = 0;  // samples whose camera vertex came from the batched camera stage
    double seconds = 0;
    int tilesDone = 0, tilesTotal = 0;
    bool cancelled = false;
};

struct RenderOptions {
    int threads = 0;  // 0 = all cores
    std::function<void(const RenderProgress&)> onTile;  // called serially (under a mutex, from a worker
                                                        // thread), after each finished tile
    const std::atomic<bool>* cancel = nullptr;          // polled between pixel rows
    // Bytes the render may use in all (0: no limit of its own). Whatever the value, a render whose estimate
    // (kRenderBytesPerPixel per pixel, kBvhBytesPerTriangle per triangle) exceeds the memory this process can still get
    // (core/util/memory_budget.h) is refused before anything is allocated.
    uint64_t maxMemoryBytes = 0;
    // The batched camera stage (issue 37 item 1): each tile row's camera rays of one sample index are traced as one
    // Embree stream and their hits shaded per material in one pass (Integrator::shadeCameraHits). The image is the
    // same bits either way; false renders pixel by pixel (tests compare the two). Quad derivatives
    // (render.derivatives "quad") always render pixel by pixel.
    bool batchedCameraHits = true;
};

// The memory estimate of renderScene: the film's 19 floats per pixel, and a copy of them while the EXR and PNG are
// written (with the PNG's tone-mapped buffers), rounded up; Embree's BVH per triangle (measured: docs/performance.md).
constexpr uint64_t kRenderBytesPerPixel = 256;
constexpr uint64_t kBvhBytesPerTriangle = 64;

struct RenderOutput {
    ImageSet images;  // beauty, diffuse, specular, albedo, normal, uv, depth
    RenderStats stats;
};

// Renders scene.render.crop (or the whole frame). Pixels of tiles not finished after a cancel are 0.
RenderOutput renderScene(const Scene& scene, const RenderOptions& options = {});

}  // namespace specula
