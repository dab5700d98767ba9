// Direct lighting and path tracing with next-event estimation and multiple importance sampling
// (Veach 1997, power heuristic β = 2). Throughputs are kept per first-bounce lobe category so the
// diffuse and specular AOVs add up exactly to the reflected part of beauty.
#include "core/render/integrator.h"

#include "core/render/sampler.h"
#include "core/render/sampling.h"
#include "core/scene/scene.h"

#include <tbb/collaborative_call_once.h>

#include <array>
#include <limits>

namespace specula {

Integrator::Integrator(const Scene& scene, const Accel& accel)
    : scene_(scene),
      accel_(accel),
      path_(scene.render.integrator == IntegratorKind::Path),
      raster_(scene.render.integrator == IntegratorKind::Raster),
      maxDepth_(scene.render.integrator == IntegratorKind::Path ? scene.render.maxDepth : 0),
      dimsPerBounce_(uint32_t(2 * scene.lights.size() + 4)),
      camera_(scene.camera, scene.render.width, scene.render.height),
      diffScale_(std::max(0.125f, 1.f / std::sqrt(float(std::max(scene.render.spp, 1))))),
      ltcLights_(scene.render.areaLights == AreaLightMode::Ltc),
      ltcMaxDepth_(scene.render.ltcMaxDepth),
      ltcShadowRays_(std::max(1, scene.render.ltcShadowRays)),
      shadows_(std::make_unique<RasterShadowState>()) {
    derivatives_.reserve(scene.shapes.size());
    for (const ShapeInstance& sh : scene.shapes) {
        const Material* m = sh.material >= 0 ? scene.materials[size_t(sh.material)].get() : nullptr;
        derivatives_.push_back(m ? uint8_t(m->needsDerivatives()) : uint8_t(1));
    }
}

Color3 Integrator::environment(const Vec3& dir) const {
    Color3 L(0.f);
    for (const auto& l : scene_.lights)
        if (l->isEnvironment()) L += l->radiance(dir);
    return L;
}

namespace {
// Lights whose polygon integrals are tracked per path vertex (the rest are sampled only).
constexpr size_t kMaxAnalyticLights = 64;

// Radiance weights of the diffuse and specular AOVs along the current path.
struct Throughput {
    Color3 d{0.f}, s{0.f};
    Color3 total() const { return d + s; }
};

// Adds radiance L arriving along the current path (weighted by beta). Radiance after at least one bounce is
// clamped like Cycles' clamp_indirect: scaled so its largest component is at most 'clamp' (0 = off).
void addPathRadiance(SampleValue& out, const Throughput& beta, const Color3& L, float clamp) {
    Color3 d = beta.d * L, s = beta.s * L;
    if (clamp > 0.f) {
        float m = maxComponent(d + s);
        if (m > clamp) {
            float k = clamp / m;
            d *= k;
            s *= k;
        }
    }
    out.diffuse += d;
    out.specular += s;
}

// Adds a light sample f·L at the vertex at 'depth'. At the camera hit the closure's own split decides
// the AOV (beta is not split yet); deeper, the path's first-bounce category does, and it is indirect.
void addLightSample(SampleValue& out, const Throughput& beta, int depth, const BsdfEval& f, const Color3& L,
                    float clamp) {
    if (depth == 0) {
        out.diffuse += f.diffuse * L;
        out.specular += f.specular * L;
    } else {
        addPathRadiance(out, beta, f.total() * L, clamp);
    }
}

// Shadow ray from a shading point towards a light sample. The origin is offset off the surface, so the
// ray is re-aimed at the sampled point from the offset origin and stops just short of it: otherwise it
// would reach the emitter's own geometry (quad lights are in the BVH) and report the light as occluded.
Ray shadowRay(const ShadingPoint& sp, const LightSample& ls) {
    Ray r;
    r.o = offsetRayOrigin(sp.pGeom, sp.ng, ls.wi);
    if (std::isinf(ls.distance)) {
        r.d = ls.wi;
        r.tMax = std::numeric_limits<float>::infinity();
    } else {
        Vec3 to = sp.pGeom + ls.wi * ls.distance - r.o;
        float t = glm::length(to);
        r.d = to / t;
        r.tMax = t * (1.f - 1e-4f);
    }
    return r;
}

}  // namespace

// The emission of a mesh light's sample: the shape's material shaded at the sampled point, seen from p. Its lobes go
// to the vertex's arena (reset with the vertex), so the vertex's own closure stays valid.
Color3 Integrator::meshLightEmission(const LightSample& ls, const Vec3& p, ScratchArena& arena) const {
    Hit h;
    h.shape = uint32_t(ls.shape);
    h.prim = ls.prim;
    h.b1 = ls.bary.x;
    h.b2 = ls.bary.y;
    h.t = ls.distance;
    RayDifferential r;  // no differentials: emission is looked up at the point
    r.o = p;
    r.d = ls.wi;
    const ShadingPoint lp = accel_.shadingPoint(r, h);
    Closure unused;
    Color3 Le(0.f);
    scene_.materials[size_t(scene_.shapes[size_t(ls.shape)].material)]->shade(lp, arena, unused, &Le);
    return isFinite(Le) ? Le : Color3(0.f);
}

// A camera ray passes through the geometry of lights the camera does not see (Light::cameraVisible): the ray is
// traced again beyond each such hit (the same ray, a larger tMin, so its differentials stay the camera's).
bool Integrator::intersectFromCamera(const Ray& cameraRay, Hit& hit, int firstPass) const {
    Ray r = cameraRay;
    for (int pass = firstPass; pass < 64; ++pass) {
        if (!accel_.intersect(r, hit)) return false;
        const int light = scene_.shapes[hit.shape].areaLight;
        if (light < 0 || scene_.lights[size_t(light)]->cameraVisible) return true;
        r.tMin = std::nextafter(hit.t, std::numeric_limits<float>::infinity()) * (1.f + 1e-6f);
    }
    return false;  // 64 invisible lights in a row: treated as a miss
}

void Integrator::shadeCameraHits(const RayDifferential* rays, size_t n, ScratchArena& arena, CameraVertex* out) const {
    constexpr size_t kBatch = 64;
    Ray plain[kBatch];
    Hit hits[kBatch];
    uint8_t found[kBatch];
    for (size_t begin = 0; begin < n; begin += kBatch) {
        const size_t m = std::min(kBatch, n - begin);
        for (size_t k = 0; k < m; ++k) plain[k] = rays[begin + k];
        accel_.intersectStream(plain, m, hits, found);
        // Shapes grouped by material: the shading points of each material, in ray order.
        const ShadingPoint* sps[kBatch];
        Closure* closures[kBatch];
        Color3 emission[kBatch];
        uint32_t materialOf[kBatch];
        size_t vertexOf[kBatch];
        size_t shadedCount = 0;
        for (size_t k = 0; k < m; ++k) {
            CameraVertex& v = out[begin + k];
            v.shaded = false;
            v.found = found[k];
            Hit hit = hits[k];
            if (v.found) {
                // A light the camera does not see: the rest of intersectFromCamera's passes, ray by ray.
                const int light = scene_.shapes[hit.shape].areaLight;
                if (light >= 0 && !scene_.lights[size_t(light)]->cameraVisible) {
                    Ray r = plain[k];
                    r.tMin = std::nextafter(hit.t, std::numeric_limits<float>::infinity()) * (1.f + 1e-6f);
                    v.found = intersectFromCamera(r, hit, 1);
                }
            }
            if (!v.found) continue;
            v.hit = hit;
            v.sp = accel_.shadingPoint(rays[begin + k], hit, derivatives_[hit.shape]);
            if (scene_.shapes[hit.shape].areaLight >= 0) continue;  // lights do not scatter: li answers alone
            v.sp.depth = 0;
            v.shaded = true;
            materialOf[shadedCount] = uint32_t(scene_.shapes[hit.shape].material);
            vertexOf[shadedCount] = begin + k;
            closures[shadedCount] = &v.closure;
            sps[shadedCount++] = &v.sp;
        }
        // Each material shades its points in one call; the order of materials does not change any point's result.
        bool done[kBatch] = {};
        for (size_t i = 0; i < shadedCount; ++i) {
            if (done[i]) continue;
            const uint32_t mat = materialOf[i];
            const ShadingPoint* groupSp[kBatch];
            Closure* groupCl[kBatch];
            size_t group[kBatch], g = 0;
            for (size_t j = i; j < shadedCount; ++j) {
                if (materialOf[j] != mat) continue;
                done[j] = true;
                group[g] = j;
                groupSp[g] = sps[j];
                groupCl[g++] = closures[j];
            }
            Color3 groupLe[kBatch];
            scene_.materials[mat]->shadeBatch(groupSp, g, arena, groupCl, groupLe);
            for (size_t q = 0; q < g; ++q) emission[group[q]] = groupLe[q];
        }
        for (size_t i = 0; i < shadedCount; ++i)
            out[vertexOf[i]].Le = scene_.materials[materialOf[i]]->isEmissive() ? emission[i] : Color3(0.f);
    }
}

SampleValue Integrator::li(const RayDifferential& cameraRay, PixelSampler& sampler, ScratchArena& arena,
                           const QuadRays* quad, const CameraVertex* first) const {
    SampleValue out;
    Hit hit;
    if (first ? !first->found : !intersectFromCamera(cameraRay, hit)) {
        out.beauty = environment(glm::normalize(cameraRay.d));
        return out;
    }
    if (first) hit = first->hit;
    ShadingPoint sp = first ? first->sp : accel_.shadingPoint(cameraRay, hit, derivatives_[hit.shape]);
    {
        const ShapeInstance& sh = scene_.shapes[hit.shape];
        out.depth = hit.t * glm::dot(cameraRay.d, scene_.camera.lookAt - scene_.camera.position) /
                    std::max(1e-20f, glm::length(scene_.camera.lookAt - scene_.camera.position));
        out.uv = sp.uv;
        out.normal = sp.n;
        if (sh.areaLight >= 0) {  // lights do not scatter
            out.beauty = scene_.lights[sh.areaLight]->radiance(glm::normalize(cameraRay.d), sp.frontFacing);
            return out;
        }
    }

    const uint32_t firstBounceDim = 4;  // 0-1 pixel position, 2-3 lens
    const float clamp = scene_.render.clampIndirect;
    Throughput beta;
    beta.d = beta.s = Color3(1.f);  // split happens at the first scattering event
    Color3 emitted(0.f);
    float prevBsdfPdf = 0.f;
    Vec3 prevDir(0.f);     // the BSDF-sampled direction that reached this vertex, its distance and triangle (mesh-light MIS)
    float prevHitT = 0.f;
    uint32_t prevPrim = 0;

    // One closure for the whole path, replaced at each vertex by Material::shade: constructing it (8 lobe slots with
    // their frames) at every vertex was a measurable part of a vertex's cost (issue 15). Its lobes live in the arena,
    // reset with the vertex.
    Closure pathClosure;
    for (int depth = 0;; ++depth) {
        sampler.setDimension(firstBounceDim + uint32_t(depth) * dimsPerBounce_);
        arena.reset();
        sp.depth = depth;
        if (depth == 0 && quad && derivatives_[sp.shapeId]) {
            // GPU 2×2-quad emulation (filtered-ggx.md §5.2): shade the partners' pixel-centre hits (their lobes are
            // dropped with this vertex's arena) and replace the ray differentials by fine one-sided differences.
            for (int k = 0; k < 2; ++k) {
                ShadingPoint::QuadNeighbour& nb = sp.quad[k];
                Hit hn;
                // Raster: the partner is a helper invocation of this pixel's triangle (its plane, extrapolated),
                // as on a GPU; otherwise the partner's own hit.
                if (raster_ ? !accel_.extrapolate(quad->ray[k], hit, hn)
                            : (!intersectFromCamera(quad->ray[k], hn) || scene_.shapes[hn.shape].areaLight >= 0))
                    continue;
                ShadingPoint spn = accel_.shadingPoint(quad->ray[k], hn);
                Closure partner;
                scene_.materials[scene_.shapes[spn.shapeId].material]->shade(spn, arena, partner);
                nb.valid = true;
                nb.sign = quad->sign[k];
                nb.p = spn.p;
                nb.wo = spn.wo;
                nb.frame = partner.dominantFrame(spn.wo, spn.frame);
                Vec3& dp = k == 0 ? sp.dpdx : sp.dpdy;
                Vec3& dn = k == 0 ? sp.dndx : sp.dndy;
                Vec3& dwo = k == 0 ? sp.dwodx : sp.dwody;
                Vec2& duv = k == 0 ? sp.duvdx : sp.duvdy;
                dp = nb.sign * (spn.p - sp.p);
                dn = nb.sign * (spn.n - sp.n);
                dwo = nb.sign * (spn.wo - sp.wo);
                duv = nb.sign * (spn.uv - sp.uv);
                sp.differentialScale[k] = 1.f;  // a whole pixel step
            }
            // At silhouettes a partner misses the object: that axis keeps its ray differential.
            sp.hasDifferentials = sp.hasDifferentials || (sp.quad[0].valid && sp.quad[1].valid);
        }
        const Material& material = *scene_.materials[scene_.shapes[sp.shapeId].material];
        // The camera vertex may come shaded from the batched camera stage (shadeCameraHits), with the same bits.
        const bool preShaded = depth == 0 && first;
        Color3 Le(0.f);
        if (preShaded) {
            Le = first->Le;
        } else {
            // One shading pass gives the closure and the emission; the shading point stays const while it runs.
            material.shade(sp, arena, pathClosure, material.isEmissive() ? &Le : nullptr);
        }
        const Closure& closure = preShaded ? first->closure : pathClosure;
        if (material.isEmissive()) {
            if (depth == 0) {
                emitted += Le;
            } else {
                // A mesh light was also sampled by next-event estimation at the previous vertex: weigh this BSDF hit by
                // the power heuristic against that strategy's pdf for the same point.
                const int ml = scene_.shapes[sp.shapeId].meshLight;
                float w = 1.f;
                if (ml >= 0) {
                    const float lightPdf = static_cast<const MeshLight&>(*scene_.lights[size_t(ml)]).pdfAt(prevDir, prevHitT, prevPrim);
                    w = powerHeuristic(prevBsdfPdf, lightPdf);
                }
                addPathRadiance(out, beta, Le * w, clamp);
            }
        }
        const Vec3 wo = sp.wo;
        if (depth == 0) {
            out.albedo = closure.albedo(wo);
            out.normal = closure.dominantFrame(wo, sp.frame).n;
        }
        if (closure.empty()) break;
        if (raster_) {
            out.normal = sp.n;  // the GPU's normal AOV is the shading normal (it cannot see the lobes' frames)
            rasterLighting(sp, closure, out);
            break;
        }

        // Next-event estimation: one sample of every light. For polygonal lights (render.area_lights = "ltc"), the
        // lobes with a closed-form polygon integral (BsdfLobe::integratePolygon, e.g. LTC lobes) are integrated
        // analytically with stochastic shadows; the other lobes are estimated from a light sample with MIS, and
        // BSDF sampling later counts only those for this light.
        const bool transmits = closure.transmits();  // paths and light samples may continue below the surface
        std::array<LobeMask, kMaxAnalyticLights> analytic{};
        for (size_t li = 0; li < scene_.lights.size(); ++li) {
            const Light& light = *scene_.lights[li];
            LightSample ls;
            Vec2 u = sampler.get2D();
            BsdfQuery q;
            q.wo = wo;
            q.ng = sp.ng;
            q.polygonHorizon = scene_.render.ltcHorizon;
            if (ltcLights_ && depth <= ltcMaxDepth_ && li < kMaxAnalyticLights) {
                Vec3 poly[4];
                Color3 Lp;
                int n = light.polygon(sp.pGeom, poly, Lp);
                BsdfEval fa;
                std::array<Color3, Closure::kMaxLobes> perLobe{};
                if (n > 0) {
                    for (int k = 0; k < n; ++k) poly[k] = poly[k] - sp.pGeom;
                    analytic[li] = closure.integratePolygon(q, poly, n, fa, perLobe.data());
                }
                if (analytic[li] != 0) {
                    // Shadows by the ratio estimator of Heitz, Hill & McGuire 2018: the unshadowed integral U_j of
                    // each analytic lobe times the shadowed/unshadowed ratio of one sample. The sample is drawn
                    // ∝ that lobe's own integrand over the light (samplePolygon), so the ratio is its visibility
                    // and E[U_j·V] is exactly the shadowed integral: fully lit or fully shadowed pixels are noise-free.
                    const Vec3 lightNormal = glm::cross(poly[1] - poly[0], poly[2] - poly[0]);
                    // Lobes that integrate but cannot sample the polygon: the visibility of one light sample (exact
                    // when unoccluded, biased in penumbrae), computed once.
                    int lightVisible = -1;
                    auto lightSampleVisible = [&]() {
                        if (lightVisible < 0) {
                            LightSample lv;
                            lightVisible = light.sample(sp.pGeom, u, lv) && glm::dot(lv.wi, sp.ng) > 0.f &&
                                           !accel_.occluded(shadowRay(sp, lv));
                        }
                        return lightVisible == 1;
                    };
                    // render.ltc_shadow_rays K per lobe: K directions whose first random pairs are one pair rotated by
                    // k/K along the diagonal (Cranley-Patterson: each uniform, jointly stratified), visibility averaged.
                    const int K = ltcShadowRays_;
                    int rank = 0;
                    for (int j = 0; j < closure.size(); ++j) {
                        if (!((analytic[li] >> j) & 1) || maxComponent(perLobe[j]) <= 0.f) continue;
                        const uint64_t key = (uint64_t(depth) << 40) ^ (uint64_t(li) << 8) ^ uint64_t(j);
                        const Vec2 base = rank++ == 0 ? u
                                                      : Vec2(PixelSampler::unitFloat(sampler.bits(key * 2)),
                                                             PixelSampler::unitFloat(sampler.bits(key * 2 + 1)));
                        int visible = 0;
                        for (int k = 0; k < K; ++k) {
                            const float shift = float(k) / float(K);
                            Vec2 uj(base.x + shift, base.y + shift);
                            uj -= glm::floor(uj);
                            Vec3 wj;
                            if (closure.samplePolygon(q, j, poly, n, uj, sampler.bits(~key + uint64_t(k) * 0x9E37ULL), wj)) {
                                if (glm::dot(wj, sp.ng) <= 0.f) continue;  // below the geometric surface, as sampled NEE
                                float den = glm::dot(wj, lightNormal);
                                if (den == 0.f) continue;
                                LightSample lj;
                                lj.wi = wj;
                                lj.distance = glm::dot(poly[0], lightNormal) / den;
                                if (!(lj.distance > 0.f) || accel_.occluded(shadowRay(sp, lj))) continue;
                            } else if (!lightSampleVisible()) {
                                continue;
                            }
                            ++visible;
                        }
                        if (visible == 0) continue;
                        BsdfEval fj;
                        (closure.lobe(j)->kind() == LobeKind::Diffuse ? fj.diffuse : fj.specular) =
                            perLobe[j] * (float(visible) / float(K));
                        addLightSample(out, beta, depth, fj, Lp, clamp);
                    }
                    // The lobes without a closed form: sampled next-event estimation with MIS, as for other lights.
                    q.lobes = ~analytic[li];
                    if ((q.lobes & closure.allLobes()) == 0) continue;
                    if (!light.sample(sp.pGeom, u, ls) || !(ls.pdf > 0.f) || maxComponent(ls.L) <= 0.f) continue;
                    if (glm::dot(ls.wi, sp.ng) <= 0.f && !transmits) continue;
                    q.wi = ls.wi;
                    BsdfValue v = closure.evalPdf(q);
                    if (maxComponent(v.f.total()) <= 0.f) continue;
                    if (accel_.occluded(shadowRay(sp, ls))) continue;
                    addLightSample(out, beta, depth, v.f, ls.L * (powerHeuristic(ls.pdf, v.pdf) / ls.pdf), clamp);
                    continue;
                }
            }
            if (!light.sample(sp.pGeom, u, ls) || !(ls.pdf > 0.f)) continue;
            // Directions below the geometric surface reach only transmitting lobes (BsdfQuery::ng: no light leaks through
            // shading normals either way).
            if (glm::dot(ls.wi, sp.ng) <= 0.f && !transmits) continue;
            if (ls.shape >= 0) ls.L = meshLightEmission(ls, sp.pGeom, arena);
            if (maxComponent(ls.L) <= 0.f) continue;
            q.wi = ls.wi;
            // Delta lights only: area/environment lights are also reached by BSDF sampling (where dwi = 0), and MIS
            // needs one f for both strategies (filtered-ggx.md §5.1).
            if (ls.delta) q.lightDistance = ls.distance;
            BsdfValue v = closure.evalPdf(q);
            if (maxComponent(v.f.total()) <= 0.f) continue;
            if (accel_.occluded(shadowRay(sp, ls))) continue;
            // A mesh light's emission is found by BSDF sampling only below the last vertex: there the sample is alone.
            float w = ls.delta || (light.isMesh() && depth >= maxDepth_) ? 1.f : powerHeuristic(ls.pdf, v.pdf);
            addLightSample(out, beta, depth, v.f, ls.L * (w / ls.pdf), clamp);
        }

        // BSDF sampling: hits emitters (MIS) and continues the path. At the last vertex its only use is the MIS hit of
        // a light that is not fully integrated analytically: skip the ray when there is none (render.area_lights).
        if (depth >= maxDepth_) {
            bool useful = false;
            for (size_t li = 0; li < scene_.lights.size() && !useful; ++li) {
                const Light& l = *scene_.lights[li];
                if (l.isDelta() || l.isMesh()) continue;  // a mesh light's hit counts only inside max_depth
                useful = li >= kMaxAnalyticLights || (closure.allLobes() & ~analytic[li]) != 0;
            }
            if (!useful) break;
        }
        BsdfSample bs;
        float uLobe = sampler.get1D();
        Vec2 uDir = sampler.get2D();
        float uRr = sampler.get1D();
        BsdfQuery sq;
        sq.wo = wo;
        sq.ng = sp.ng;
        if (!closure.sample(sq, uLobe, uDir, bs)) break;
        const Vec3 wiW = bs.wi;
        if (glm::dot(wiW, sp.ng) <= 0.f && !transmits) break;  // below the geometric surface
        if (transmits && maxComponent(bs.f.total()) <= 0.f) break;  // e.g. a reflection sampled below the surface
        const Throughput betaPrev = beta;
        if (depth == 0) {
            beta.d = bs.f.diffuse / bs.pdf;
            beta.s = bs.f.specular / bs.pdf;
        } else {
            Color3 m = bs.f.total() / bs.pdf;
            beta.d *= m;
            beta.s *= m;
        }
        prevBsdfPdf = bs.pdf;
        if (!isFinite(beta.d) || !isFinite(beta.s)) {
            out.diffuse = Color3(std::numeric_limits<float>::quiet_NaN());  // counted and dropped by the film
            break;
        }

        RayDifferential next;
        next.o = offsetRayOrigin(sp.pGeom, sp.ng, wiW);
        next.d = wiW;
        Hit h;
        if (!accel_.intersect(next, h)) {
            for (const auto& l : scene_.lights) {
                if (!l->isEnvironment()) continue;
                Color3 Le = l->radiance(wiW);
                float w = powerHeuristic(prevBsdfPdf, l->pdf(sp.pGeom, wiW, 0.f));
                addPathRadiance(out, beta, Le * w, depth == 0 ? 0.f : clamp);
            }
            break;
        }
        const ShapeInstance& nextShape = scene_.shapes[h.shape];
        if (nextShape.areaLight >= 0) {
            const LobeMask done = nextShape.areaLight < int(kMaxAnalyticLights) ? analytic[nextShape.areaLight] : 0;
            if ((closure.allLobes() & ~done) == 0) break;  // counted analytically
            const Light& l = *scene_.lights[nextShape.areaLight];
            ShadingPoint lp = accel_.shadingPoint(next, h);
            Color3 Le = l.radiance(wiW, lp.frontFacing);
            float w = powerHeuristic(prevBsdfPdf, l.pdf(sp.pGeom, wiW, h.t));
            if (done == 0) {
                addPathRadiance(out, beta, Le * w, depth == 0 ? 0.f : clamp);
            } else {
                // Only the lobes this light's analytic integral left out: their f·cos over the mixture pdf.
                BsdfQuery rq;
                rq.wo = wo;
                rq.ng = sp.ng;
                rq.wi = wiW;
                rq.lobes = ~done;
                BsdfEval fr = closure.evalPdf(rq).f;
                Throughput part = betaPrev;
                if (depth == 0) {
                    part.d = fr.diffuse / bs.pdf;
                    part.s = fr.specular / bs.pdf;
                } else {
                    Color3 m = fr.total() / bs.pdf;
                    part.d *= m;
                    part.s *= m;
                }
                addPathRadiance(out, part, Le * w, depth == 0 ? 0.f : clamp);
            }
            break;
        }
        if (depth >= maxDepth_) break;
        // Russian roulette after three bounces.
        if (depth >= 3) {
            float q = std::max(0.05f, 1.f - maxComponent(beta.total()));
            if (uRr < q) break;
            beta.d /= (1.f - q);
            beta.s /= (1.f - q);
        }
        prevDir = wiW;
        prevHitT = h.t;
        prevPrim = h.prim;
        const bool derivatives = derivatives_[h.shape];
        sp = accel_.shadingPoint(next, h, derivatives);
        if (derivatives) {
            // Secondary vertices: the camera's footprint at that point (pbrt-v4's approximation), so filtered lobes,
            // glints and textures seen in mirrors or through bounces get a footprint; dwo is not differentiated there.
            camera_.approximateDpDxy(sp.p, sp.n, diffScale_, sp.dpdx, sp.dpdy);
            surfaceDifferentials(sp);
            sp.dwodx = sp.dwody = Vec3(0.f);
            sp.differentialScale = Vec2(diffScale_);
            sp.hasDifferentials = true;
        }
    }
    out.beauty = emitted + out.diffuse + out.specular;
    return out;
}

struct Integrator::RasterShadowState {
    tbb::collaborative_once_flag once;
    RasterShadows maps;
};

Integrator::~Integrator() = default;

const Integrator::RasterShadows& Integrator::rasterShadows() const {
    RasterShadowState& st = *shadows_;
    tbb::collaborative_call_once(st.once, [&] {
        for (const auto& light : scene_.lights) st.maps.lights.push_back(light->raster());
        st.maps.layout = planShadowMaps(scene_, st.maps.lights);
        st.maps.texels = buildShadowMaps(scene_, accel_, st.maps.layout);
        st.maps.environments.resize(st.maps.lights.size());
        for (size_t i = 0; i < st.maps.lights.size(); ++i)
            if (st.maps.lights[i].kind == RasterLight::Kind::Environment)
                st.maps.environments[i] = prefilterEnvironment(st.maps.lights[i]);
    });
    return st.maps;
}

// The GPU preview's light transport on the CPU (docs/preview.md): what plugin/preview/preview_lights.glsl computes,
// so that the two agree image for image. Delta lights by one direction query times the visibility of the preview's
// shadow maps (core/render/shadow_maps.h: the same maps, built here by one ray per texel centre, and the same lookup at
// the tessellated point and its geometric normal); quad lights by the closure's polygon integral (LTC), or, when a lobe
// has no closed form, by a direction query towards the light's centre times its solid angle, both times the visibility
// of the light's centre (a cube map there); an environment by the split sum (core/render/environment_prefilter.h): each
// LTC lobe's polygon integral over the hemisphere of the shading normal (its directional albedo) times the prefiltered
// environment where the lobe's LTC points, at the roughness of its peak (the irradiance map for diffuse lobes); when a
// lobe has no closed form, the closure's f(wi = N)·π times the irradiance at N; both times environmentShadowVisibility
// (the irradiance-weighted visibility of kShadowDirections orthographic maps).
void Integrator::rasterLighting(const ShadingPoint& sp, const Closure& closure, SampleValue& out) const {
    const Vec3 wo = sp.wo;
    const RasterShadows& shadows = rasterShadows();
    auto visibility = [&](size_t li) {
        return shadowVisibility(shadows.layout, shadows.texels.data(), int(li), sp.p, sp.ng);
    };
    auto add = [&](const BsdfEval& f, const Color3& L) {
        out.diffuse += f.diffuse * L;
        out.specular += f.specular * L;
    };
    auto direction = [&](const Vec3& wi, float distance) {
        BsdfQuery q;
        q.wo = wo;
        q.wi = wi;
        q.lightDistance = distance;
        return closure.evalPdf(q).f;
    };
    for (size_t li = 0; li < scene_.lights.size(); ++li) {
        const Light* light = scene_.lights[li].get();
        const RasterLight& r = shadows.lights[li];
        switch (r.kind) {
            case RasterLight::Kind::Point:
            case RasterLight::Kind::Spot: {
                Vec3 d = r.position - sp.p;
                float d2 = glm::dot(d, d);
                if (!(d2 > 0.f)) break;
                float dist = std::sqrt(d2);
                Vec3 wi = d / dist;
                if (glm::dot(wi, sp.ng) <= 0.f) break;
                float falloff = 1.f;
                if (r.kind == RasterLight::Kind::Spot) falloff = rasterSpotFalloff(glm::dot(-wi, r.direction), r);
                if (falloff <= 0.f) break;
                const float vis = visibility(li);
                if (vis > 0.f) add(direction(wi, dist), r.value * (falloff / d2) * vis);
                break;
            }
            case RasterLight::Kind::Directional: {
                if (!(glm::dot(r.direction, sp.ng) > 0.f)) break;
                const float vis = visibility(li);
                if (vis > 0.f) add(direction(r.direction, std::numeric_limits<float>::infinity()), r.value * vis);
                break;
            }
            case RasterLight::Kind::Quad: {
                Vec3 poly[4];
                Color3 Lp;
                int n = light->polygon(sp.p, poly, Lp);
                if (n == 0) break;
                for (int k = 0; k < n; ++k) poly[k] -= sp.p;
                BsdfQuery q;
                q.wo = wo;
                q.polygonHorizon = scene_.render.ltcHorizon;
                BsdfEval fa;
                LobeMask analytic = closure.integratePolygon(q, poly, n, fa);
                const float vis = visibility(li);  // from the light's centre (core/render/shadow_maps.h)
                if ((closure.allLobes() & ~analytic) == 0) {
                    add(fa, Lp * vis);
                    break;
                }
                Vec3 c = (poly[0] + poly[1] + poly[2] + poly[3]) * 0.25f;
                float dist = glm::length(c);
                Vec3 wi = c / dist;
                Vec3 nl = glm::cross(r.direction, r.edgeV);
                float area = glm::length(nl);
                float solidAngle = area * std::abs(glm::dot(wi, nl / area)) / (dist * dist);
                if (glm::dot(wi, sp.ng) > 0.f)
                    add(direction(wi, std::numeric_limits<float>::infinity()), Lp * solidAngle * vis);
                break;
            }
            case RasterLight::Kind::Mesh: break;  // the rasteriser does not light with emissive meshes
            case RasterLight::Kind::Environment: {
                if (!r.hasMap && maxComponent(r.value) <= 0.f) break;
                const Vec3 t = sp.frame.t, b = sp.frame.b, nn = sp.frame.n;
                const float eps = kRasterHemisphereLift;
                Vec3 poly[4] = {glm::normalize(t + eps * nn), glm::normalize(b + eps * nn), glm::normalize(-t + eps * nn),
                                glm::normalize(-b + eps * nn)};
                BsdfQuery q;
                q.wo = wo;
                q.polygonHorizon = scene_.render.ltcHorizon;
                const PrefilteredEnvironment& env = shadows.environments[li];
                BsdfEval fa;
                LobeMask analytic = closure.integrateEnvironment(
                    q, poly, 4, [&env](const Vec3& d, float alpha) { return env.lookup(d, alpha); }, fa);
                // The share of the environment that reaches the point (environmentShadowVisibility): each shadow
                // direction weighted by the irradiance from it.
                float irradiance[kShadowDirections];
                for (int k = 0; k < kShadowDirections; ++k) {
                    const Color3 e = env.lookup(-shadowDirection(k).axis, -1.f);
                    irradiance[k] = e.x + e.y + e.z;
                }
                const float vis = environmentShadowVisibility(shadows.layout, shadows.texels.data(), int(li), sp.p, sp.ng,
                                                              irradiance);
                if ((closure.allLobes() & ~analytic) == 0)
                    add(fa, Color3(vis));
                else
                    add(direction(nn, std::numeric_limits<float>::infinity()), env.lookup(nn, -1.f) * kPi * vis);
                break;
            }
        }
    }
}

}  // namespace specula
