// Tile scheduler and film. Each pixel averages its own samples (filter importance sampling: offsets
// are drawn from the pixel filter, so every sample has weight 1 and no splatting crosses tiles);
// hence the image does not depend on the number of threads or the tile completion order.
#include "core/render/renderer.h"
#include "core/util/error.h"
#include "core/util/memory_budget.h"

#include "core/render/accel.h"
#include "core/render/camera.h"
#include "core/render/integrator.h"
#include "core/scene/scene.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <mutex>

namespace specula {

namespace {

// Pixel-filter importance sampling: offset from the pixel centre, in pixels.
Vec2 filterOffset(const RenderSettings& rs, const Vec2& u) {
    // Scenes may ask for it at spp = 1 only (the loader checks); in-process tests use it at any spp to measure the
    // noise of a shading estimator without pixel-coverage noise.
    if (rs.pixelCenter) return Vec2(0.f);
    if (rs.filter == PixelFilterKind::Box) return u - Vec2(0.5f);
    // Gaussian: Box-Muller with σ = sqrt(σ²); untruncated, so the estimator is the exact Gaussian filter.
    float sigma = std::sqrt(rs.gaussianSigma2);
    float r = sigma * std::sqrt(-2.f * std::log(std::max(1.f - u.x, 1e-12f)));
    float phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi)};
}

struct Accum {
    Color3 beauty{0.f}, diffuse{0.f}, specular{0.f}, albedo{0.f};
    Vec3 normal{0.f};
    Vec2 uv{0.f};
    double depth = 0;
    int n = 0;
    // Adds one sample (count 1) or a block's sums (its count), field by field.
    template <class Sums>
    void add(const Sums& v, double depthSum, int count) {
        beauty += v.beauty;
        diffuse += v.diffuse;
        specular += v.specular;
        albedo += v.albedo;
        normal += v.normal;
        uv += v.uv;
        depth += depthSum;
        n += count;
    }
};

// Adds a block's sums to the pixel's (the first block is assigned, so that a render of one block is the plain sum).
// With several blocks the block's depth sum is rounded to float first: a farm piece stores it as a float, and the
// merge must add exactly what the single-process render adds.
void foldBlock(Accum& total, const Accum& block, bool first, bool severalBlocks) {
    const double depth = severalBlocks ? double(float(block.depth)) : block.depth;
    if (first) {
        total = block;
        total.depth = depth;
        return;
    }
    total.add(block, depth, block.n);
}

bool finiteSample(const SampleValue& v) {
    return isFinite(v.beauty) && isFinite(v.diffuse) && isFinite(v.specular) && isFinite(v.albedo) &&
           isFinite(v.normal) && std::isfinite(v.uv.x) && std::isfinite(v.uv.y) && std::isfinite(v.depth);
}

}  // namespace

RenderOutput renderScene(const Scene& scene, const RenderOptions& options) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    const RenderSettings& rs = scene.render;
    CropWindow crop{0, 0, rs.width, rs.height};
    if (rs.crop) crop = *rs.crop;
    const int W = crop.x1 - crop.x0, H = crop.y1 - crop.y0;

    // Refuse a render that cannot fit before allocating its film (8192x8192 under a 4 GB limit ended in an uncaught
    // std::bad_alloc, issue 16).
    uint64_t triangles = 0;
    for (const auto& sh : scene.shapes) triangles += sh.mesh.indices.size();
    const uint64_t needed = uint64_t(W) * uint64_t(H) * kRenderBytesPerPixel + triangles * kBvhBytesPerTriangle;
    const MemoryBudget budget = memoryBudget(options.maxMemoryBytes);
    if (needed > budget.availableBytes)
        throw InputError("/render", "a " + std::to_string(W) + "x" + std::to_string(H) + " image" +
                                        (triangles ? " of " + std::to_string(triangles) + " triangles" : std::string()) +
                                        " needs about " + formatBytes(needed) + " to render and write, but " +
                                        formatBytes(budget.availableBytes) + " are left under " + budget.limitedBy +
                                        "; lower the resolution, render it in --crop pieces, or raise the limit");

    RenderOutput out;
    ImageSet& img = out.images;
    img.width = W;
    img.height = H;
    auto addAov = [&](const char* name, std::vector<std::string> ch) {
        AovBuffer b;
        b.name = name;
        b.channelNames = std::move(ch);
        b.pixels.assign(size_t(W) * H * b.channelNames.size(), 0.f);
        img.aovs.push_back(std::move(b));
        return &img.aovs.back();
    };
    img.aovs.reserve(8);
    AovBuffer* beauty = addAov("beauty", {"R", "G", "B"});
    AovBuffer* diffuse = addAov("diffuse", {"R", "G", "B"});
    AovBuffer* specular = addAov("specular", {"R", "G", "B"});
    AovBuffer* albedo = addAov("albedo", {"R", "G", "B"});
    AovBuffer* normal = addAov("normal", {"X", "Y", "Z"});
    AovBuffer* uvAov = addAov("uv", {"U", "V"});
    AovBuffer* depthAov = addAov("depth", {"Z"});
    // Sample blocks (RenderSettings::sampleBlock) and the one block a farm piece renders.
    const bool splitPiece = rs.sampleSplitCount > 0;
    const int block = splitPiece ? rs.spp / rs.sampleSplitCount : (rs.sampleBlock > 0 ? std::min(rs.sampleBlock, rs.spp) : rs.spp);
    const int sampleBegin = splitPiece ? rs.sampleSplitIndex * block : 0;
    const int sampleEnd = splitPiece ? sampleBegin + block : rs.spp;
    const bool severalBlocks = block < rs.spp;
    AovBuffer* countAov = splitPiece ? addAov("samples", {"N"}) : nullptr;

    Accel accel(scene);
    PerspectiveCamera camera(scene.camera, rs.width, rs.height);
    Integrator integrator(scene, accel);
    const float diffScale = std::max(0.125f, 1.f / std::sqrt(float(rs.spp)));

    const bool batched = options.batchedCameraHits && rs.derivatives != DerivativeMode::Quad;
    const int tile = std::max(1, rs.tile);
    const int tilesX = (W + tile - 1) / tile, tilesY = (H + tile - 1) / tile;
    const int tileCount = tilesX * tilesY;
    std::atomic<int> tilesDone{0};
    std::atomic<uint64_t> samples{0}, invalid{0};
    std::atomic<bool> cancelled{false};
    std::mutex progressMutex;

    auto renderTile = [&](int t) {
        if (cancelled.load() || (options.cancel && options.cancel->load())) {
            cancelled = true;
            return;
        }
        const int tx0 = crop.x0 + (t % tilesX) * tile, ty0 = crop.y0 + (t / tilesX) * tile;
        const int tx1 = std::min(tx0 + tile, crop.x1), ty1 = std::min(ty0 + tile, crop.y1);
        ScratchArena arena;
        uint64_t tileSamples = 0, tileInvalid = 0;
        // The film write of one pixel's accumulated samples.
        auto writePixel = [&](int x, int y, const Accum& acc) {
            const size_t pix = size_t(y - crop.y0) * W + (x - crop.x0);
            if (countAov) countAov->pixels[pix] = float(acc.n);
            if (acc.n > 0) {
                // A farm piece keeps sums (the merge divides by the total count of all pieces).
                const float inv = splitPiece ? 1.f : 1.f / float(acc.n);
                auto put3 = [&](AovBuffer* b, const Vec3& c) {
                    b->pixels[pix * 3 + 0] = c.x;
                    b->pixels[pix * 3 + 1] = c.y;
                    b->pixels[pix * 3 + 2] = c.z;
                };
                put3(beauty, acc.beauty * inv);
                put3(diffuse, acc.diffuse * inv);
                put3(specular, acc.specular * inv);
                put3(albedo, acc.albedo * inv);
                put3(normal, acc.normal * inv);
                uvAov->pixels[pix * 2 + 0] = acc.uv.x * inv;
                uvAov->pixels[pix * 2 + 1] = acc.uv.y * inv;
                depthAov->pixels[pix] = float(acc.depth * inv);
            }
        };
        // The camera sample s of pixel (x, y): its sampler, after the pixel and lens dimensions, and its ray.
        auto cameraSample = [&](int x, int y, int s, PixelSampler& sampler, Vec2& uLens) {
            sampler = PixelSampler(uint32_t(x), uint32_t(y), uint32_t(s), rs.seed);
            Vec2 off = filterOffset(rs, sampler.get2D());
            uLens = sampler.get2D();
            RayDifferential ray = camera.generateRay(x + 0.5f + off.x, y + 0.5f + off.y, uLens);
            ray.scaleDifferentials(diffScale);
            ray.pixelOffset = off;
            return ray;
        };
        // A tile renders row by row in spans of pixels, one sample index at a time across the span; each pixel adds
        // its samples in index order, so the sums do not depend on the span's width. Batched: a span is the whole
        // row, its camera rays are one coherent stream and their hits are shaded per material in one pass
        // (Integrator::shadeCameraHits). Otherwise a span is one pixel, traced and shaded alone (quad derivatives
        // need each pixel's partner rays).
        const int rowWidth = tx1 - tx0;
        const size_t span = batched ? static_cast<size_t>(rowWidth) : 1;
        std::vector<Accum> acc(span), blockAcc(span);
        std::vector<PixelSampler> samplers(span, PixelSampler(0, 0, 0, 0));
        std::vector<RayDifferential> rays(span);
        std::vector<CameraVertex> first(batched ? span : 0);
        ScratchArena cameraArena;
        for (int y = ty0; y < ty1; ++y) {
            if (options.cancel && options.cancel->load()) {
                cancelled = true;
                return;  // tile stays partially rendered; counted as not done
            }
            for (int x0 = tx0; x0 < tx1; x0 += int(span)) {
                std::fill(acc.begin(), acc.end(), Accum{});
                std::fill(blockAcc.begin(), blockAcc.end(), Accum{});
                bool firstBlock = true;
                for (int s = sampleBegin; s < sampleEnd; ++s) {
                    // Block boundaries are fixed sample indices, whichever samples a process renders.
                    if (s > sampleBegin && s % block == 0) {
                        for (size_t i = 0; i < span; ++i) {
                            foldBlock(acc[i], blockAcc[i], firstBlock, severalBlocks);
                            blockAcc[i] = Accum{};
                        }
                        firstBlock = false;
                    }
                    // Checked every 32 samples, not per row: at high spp one row of a tile is seconds of work, and
                    // hosts promise that cancel stops a render within a second. An unfinished pixel stays 0.
                    if ((s & 31) == 31 && options.cancel && options.cancel->load(std::memory_order_relaxed)) {
                        cancelled = true;
                        return;
                    }
                    Vec2 uLens;
                    for (size_t i = 0; i < span; ++i) rays[i] = cameraSample(x0 + int(i), y, s, samplers[i], uLens);
                    if (batched) {
                        cameraArena.reset();
                        integrator.shadeCameraHits(rays.data(), span, cameraArena, first.data());
                    }
                    QuadRays quad;
                    if (rs.derivatives == DerivativeMode::Quad) {
                        // Partners in the aligned 2×2 quad (absolute pixel coordinates), same sub-pixel offset and lens
                        // sample: Δ = q(x0 + 1) − q(x0) as dFdxFine (filtered-ggx.md §5.2). The span is one pixel.
                        const int x = x0, xn = x ^ 1, yn = y ^ 1;
                        const Vec2 off = rays[0].pixelOffset;
                        quad.ray[0] = camera.generateRay(xn + 0.5f + off.x, y + 0.5f + off.y, uLens);
                        quad.ray[1] = camera.generateRay(x + 0.5f + off.x, yn + 0.5f + off.y, uLens);
                        quad.sign[0] = (x & 1) ? -1.f : 1.f;
                        quad.sign[1] = (y & 1) ? -1.f : 1.f;
                    }
                    for (size_t i = 0; i < span; ++i) {
                        SampleValue v = integrator.li(rays[i], samplers[i], arena,
                                                      rs.derivatives == DerivativeMode::Quad ? &quad : nullptr,
                                                      batched ? &first[i] : nullptr);
                        ++tileSamples;
                        if (!finiteSample(v)) {
                            ++tileInvalid;
                            continue;
                        }
                        blockAcc[i].add(v, v.depth, 1);
                    }
                }
                for (size_t i = 0; i < span; ++i) {
                    foldBlock(acc[i], blockAcc[i], firstBlock, severalBlocks);
                    writePixel(x0 + int(i), y, acc[i]);
                }
            }
        }
        samples += tileSamples;
        invalid += tileInvalid;
        int done = ++tilesDone;
        if (options.onTile) {
            std::lock_guard<std::mutex> lock(progressMutex);
            RenderProgress p;
            p.tilesDone = done;
            p.tilesTotal = tileCount;
            p.tileX0 = tx0;
            p.tileY0 = ty0;
            p.tileX1 = tx1;
            p.tileY1 = ty1;
            p.elapsedSeconds = std::chrono::duration<double>(Clock::now() - start).count();
            p.samplesPerSecond = p.elapsedSeconds > 0 ? double(samples.load()) / p.elapsedSeconds : 0.0;
            p.etaSeconds = done > 0 ? p.elapsedSeconds * (tileCount - done) / done : 0.0;
            p.images = &img;
            p.originX = crop.x0;
            p.originY = crop.y0;
            options.onTile(p);
        }
    };

    const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, tileCount, 1), [&](const tbb::blocked_range<int>& r) {
            for (int t = r.begin(); t != r.end(); ++t) renderTile(t);
        });
    });

    out.stats.samples = samples.load();
    out.stats.invalidSamples = invalid.load();
    out.stats.batchedSamples = batched ? samples.load() : 0;
    out.stats.tilesDone = tilesDone.load();
    out.stats.tilesTotal = tileCount;
    out.stats.cancelled = cancelled.load();
    out.stats.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    img.metadata["specula:spp"] = std::to_string(rs.spp);
    img.metadata["specula:seed"] = std::to_string(rs.seed);
    // What a farm merge checks (core/api/farm.h): pieces of one image agree on all of these but crop and split.
    img.metadata["specula:frame"] = std::to_string(rs.frame);
    img.metadata["specula:frame_size"] = std::to_string(rs.width) + "x" + std::to_string(rs.height);
    img.metadata["specula:crop"] = std::to_string(crop.x0) + "," + std::to_string(crop.y0) + "," + std::to_string(crop.x1) +
                                   "," + std::to_string(crop.y1);
    img.metadata["specula:sample_block"] = std::to_string(block);
    if (splitPiece)
        img.metadata["specula:sample_split"] = std::to_string(rs.sampleSplitIndex) + "/" + std::to_string(rs.sampleSplitCount);
    if (!scene.sourceHash.empty()) img.metadata["specula:scene_hash"] = scene.sourceHash;
    img.metadata["specula:version"] = SPECULA_VERSION;
    // For compositing (OpenEXR's worldToCamera and worldToNDC): NDC spans the written image, so a crop window's NDC
    // is the full frame's rescaled to the crop.
    img.matrices["worldToCamera"] = camera.worldToCamera();
    Mat4 toCrop(1.f);
    toCrop[0][0] = float(rs.width) / float(crop.x1 - crop.x0);
    toCrop[3][0] = -float(crop.x0) / float(crop.x1 - crop.x0);
    toCrop[1][1] = float(rs.height) / float(crop.y1 - crop.y0);
    toCrop[3][1] = -float(crop.y0) / float(crop.y1 - crop.y0);
    img.matrices["worldToNDC"] = toCrop * camera.worldToNdc();
    return out;
}

}  // namespace specula
