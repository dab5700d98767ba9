#!/usr/bin/env python3
"""Glint validation (issue 6; protocol ../shared/specs/validation.md; page docs/validation/glint.md).

Reproduces the claims of Chermain et al. 2021 (C21) for the `bsdf.glint` node on three small scenes in
examples/glint/ (tubes = Fig. 8, brushed_sphere = Fig. 7, horizon = Fig. 1) and a convergence scene (Fig. 10):

  * references: 1024 spp, box filter, GGAA off, full-resolution normal map, GPU-quad derivatives (so the glint
    footprint/LOD is the 1-pixel one the 1-spp tests use), cached as half-float EXRs (specular AOV + a coverage
    channel) in tests/validation/glint/ with the toolkit's manifest (tools/specula_validation/manifest.py: SHA-256
    of scenes and maps, the derived scenes, and a behavioural fingerprint of the renderer);
  * tests: 1 spp at the pixel centre; RMSE / MAE / relative RMSE of the specular AOV inside the object mask;
  * flicker: 16 frames, camera translated by 1/8 pixel per frame (`specula render --camera-shift-px`); flicker =
    mean over the mask of the per-pixel standard deviation over t of (test_t - ref_t) (`specula compare --frames`);
    frame references 256 spp, cached too.

Usage (run from anywhere; BIN defaults to build/bin/specula):
  tools/validate_glint.py --specula BIN --refs       regenerate the cached references + manifest (~15 min on 2 cores)
  tools/validate_glint.py --specula BIN --manifest   rewrite only the manifest for the cached files as they are
  tools/validate_glint.py --specula BIN              evaluate every method against the cached references, print tables
  tools/validate_glint.py --specula BIN --docs       ... and write docs/validation/img/glint-*.png and the generated
                                                     block of docs/validation/glint.md (adds timings, convergence figure)
  tools/validate_glint.py --specula BIN --check-cache   only check that the cache is up to date (exit 1 if stale)
Metrics come from `specula compare --json` (masks: the coverage channel of the cached references). Needs python3 and
oiiotool (OpenImageIO tools); no numpy. Shared steps: tools/specula_validation/ (docs/validation/README.md).
"""
import argparse
import copy
import json
import math
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from specula_validation import exr, metrics, ratio, rel  # noqa: E402
from specula_validation.manifest import Cache  # noqa: E402
from specula_validation.page import Canvas, colorbar, errmap, percentile, temporal_std_map, tonemap, viridis  # noqa: E402
from specula_validation.render import Renderer, specula_version  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLES = os.path.join(ROOT, "examples", "glint")
CACHE = os.path.join(ROOT, "tests", "validation", "glint")
MANIFEST = os.path.join(CACHE, "manifest.json")
DOC = os.path.join(ROOT, "docs", "validation", "glint.md")
IMG = os.path.join(ROOT, "docs", "validation", "img")

REF_SPP = 1024      # main references (C21: 1,024 spp)
FRAME_SPP = 256     # per-frame references of the flicker sequences
FRAMES = 16         # K (validation.md §2)
SHIFT_PX = 0.125    # camera translation per frame, in pixels at the look-at distance
COVER_SPP = 64      # coverage (object mask) renders


# ---- methods -------------------------------------------------------------------------------------------------
def M(ggaa=True, sk=0.5, deriv="projected_half", derivs="quad", normals=None, spp=1):
    return {"ggaa": ggaa, "sk": sk, "deriv": deriv, "derivs": derivs, "normals": normals, "spp": spp}


REF = M(ggaa=False, normals="full", spp=REF_SPP)

SCENES = {
    "tubes": {
        "file": "tubes.json", "title": "(a) thin curved tubes (C21 Fig. 8)", "baseline": "c20",
        "methods": [
            ("c20", "no GGAA (C20)", M(ggaa=False)),
            ("ggaa05", "GGAA s_K 0.5, projected h", M()),
            ("ggaa1", "GGAA s_K 1, projected h", M(sk=1.0)),
            ("ggaa05_hs", "GGAA s_K 0.5, half slope", M(deriv="half_slope")),
            ("ggaa1_hs", "GGAA s_K 1, half slope", M(sk=1.0, deriv="half_slope")),
            ("ray_c20", "no GGAA, ray differentials", M(ggaa=False, derivs="ray")),
            ("ray_ggaa05", "GGAA s_K 0.5, projected h, ray differentials", M(derivs="ray")),
            ("ray_ggaa05_hs", "GGAA s_K 0.5, half slope, ray differentials", M(deriv="half_slope", derivs="ray")),
        ],
        "flicker": ["c20", "ggaa05", "ggaa1"],
        "pictures": ["c20", "ggaa05", "ggaa1", "ggaa05_hs"],
    },
    "sphere": {
        "file": "brushed_sphere.json", "title": "(b) brushed normal-mapped sphere at a distance (C21 Fig. 7)",
        "baseline": "naive_c20",
        "methods": [
            ("naive_c20", "glint alone (MIP normals), no GGAA", M(ggaa=False, normals="naive")),
            ("naive_ggaa05", "glint alone (MIP normals), GGAA 0.5", M(normals="naive")),
            ("lean_norho_ggaa05", "LEAN without rho + glint, GGAA 0.5", M(normals="lean_norho")),
            ("lean_c20", "LEAN + glint, no GGAA", M(ggaa=False, normals="lean")),
            ("lean_ggaa05", "LEAN + glint, GGAA 0.5", M(normals="lean")),
            ("lean_ggaa1", "LEAN + glint, GGAA 1", M(sk=1.0, normals="lean")),
        ],
        "flicker": ["naive_c20", "naive_ggaa05", "lean_ggaa05"],
        "pictures": ["naive_c20", "naive_ggaa05", "lean_norho_ggaa05", "lean_ggaa05"],
    },
    "horizon": {
        "file": "horizon.json", "title": "(c) glinty normal-mapped plane to the horizon (C21 Fig. 1)",
        "baseline": "naive_c20", "far_rows": True,
        "methods": [
            ("naive_c20", "glint alone (MIP normals), no GGAA (Fig. 1a)", M(ggaa=False, normals="naive")),
            ("naive_ggaa05", "glint alone (MIP normals), GGAA 0.5 (Fig. 1b)", M(normals="naive")),
            ("naive_ggaa1", "glint alone (MIP normals), GGAA 1", M(sk=1.0, normals="naive")),
            ("naive_ggaa05_hs", "glint alone (MIP normals), GGAA 0.5, half slope", M(deriv="half_slope", normals="naive")),
            ("lean_c20", "LEAN + glint, no GGAA", M(ggaa=False, normals="lean")),
            ("lean_ggaa05", "LEAN + glint, GGAA 0.5 (Fig. 1c)", M(normals="lean")),
        ],
        "flicker": ["naive_c20", "naive_ggaa05", "lean_ggaa05"],
        "pictures": ["naive_c20", "naive_ggaa05", "lean_ggaa05"],
    },
}


# ---- small utilities ------------------------------------------------------------------------------------------
def load_scene(sid):
    with open(os.path.join(EXAMPLES, SCENES[sid]["file"])) as f:
        return json.load(f)


def glint_nodes(scene):
    return [(m, n) for m in scene.get("materials", {}).values() for n in m.get("nodes", {}).values()
            if n.get("type") == "bsdf.glint"]


# ---- scene variants ---------------------------------------------------------------------------------------------
def shift_px(frame):
    """The camera offset of flicker frame 'frame' (`specula render --camera-shift-px`): sideways, 1/8 px a frame."""
    return None if frame is None else (frame * SHIFT_PX, 0.0)


def derive(base, method):
    """The scene of one method (M(...)) or of the reference (flicker frames: the same, rendered with shift_px(t)).
    Paths stay relative to examples/glint/ (so the hash does not depend on the checkout)."""
    s = copy.deepcopy(base)
    s.pop("description", None)
    r = s["render"]
    r.update({"spp": method["spp"], "pixel_center": method["spp"] == 1, "seed": 0, "filter": "box",
              "derivatives": method["derivs"], "integrator": "direct"})
    for mat, g in glint_nodes(s):
        gi = g["inputs"]
        gi["ggaa"] = "on" if method["ggaa"] else "off"
        gi["kernel_scale"] = method["sk"]
        gi["derivative"] = method["deriv"]
        nodes = mat["nodes"]
        mode = method["normals"]
        if mode is None or "lean" not in nodes:
            continue
        if mode in ("full", "naive"):
            for k in ("lean_mean", "lean_cov"):
                gi.pop(k, None)
            gi["normal"] = "@nm.normal"
            del nodes["lean"]
            if mode == "full":  # the reference: full-resolution normal map (bilinear, MIP level 0)
                nodes["img"]["inputs"]["duvdx"] = [0, 0]
                nodes["img"]["inputs"]["duvdy"] = [0, 0]
        else:  # lean / lean_norho: the glint node shades in the LEAN mean-normal frame (spec S6)
            gi.pop("normal", None)
            gi["lean_mean"] = "@lean.slope"
            gi["lean_cov"] = "@lean.covariance"
            nodes["lean"]["inputs"]["correlation"] = "ignore" if mode == "lean_norho" else "full"
            for k in ("img", "nm"):
                nodes.pop(k, None)
    return s


def coverage_scene(base):
    """Object mask: every glint material becomes white emission, everything else black; no lights."""
    s = copy.deepcopy(base)
    s.pop("description", None)
    s["render"] = {"width": base["render"]["width"], "height": base["render"]["height"], "spp": COVER_SPP,
                   "seed": 0, "filter": "box", "integrator": "direct", "derivatives": "ray"}
    for name, m in list(s["materials"].items()):
        glinty = any(n.get("type") == "bsdf.glint" for n in m["nodes"].values())
        s["materials"][name] = {"nodes": {"e": {"type": "bsdf.emission", "inputs": {"color": 1.0 if glinty else 0.0}}},
                                "output": "@e.bsdf"}
    s["lights"] = []
    return s


def renderer(specula, workdir, verbose=False):
    return Renderer(specula, workdir, verbose, scene_dir=EXAMPLES)


def spec(img):
    return exr.layer(img, "specular")


def cache_ref(rnd, scene, cover, out_path, name, spp, frame):
    """Renders the reference and its coverage and writes the cached half EXR (specular.RGB + coverage.Y)."""
    full, secs = rnd.render(scene, name, spp=spp, shift_px=shift_px(frame))
    cov, _ = rnd.render(cover, name + "_cov", shift_px=shift_px(frame))
    exr.write_cached(full, out_path, ["specular.R", "specular.G", "specular.B"], coverage=cov)
    return secs


# ---- metrics ------------------------------------------------------------------------------------------------------
def mask_pixels(img):
    """Indices of the pixels with coverage in a cached reference (pictures only; metrics mask in `specula compare`)."""
    return [i for i, c in enumerate(img["ch"]["coverage.Y"]) if c > 0]


# ---- the cache -----------------------------------------------------------------------------------------------------
def ref_name(sid, frame=None):
    return f"{sid}_ref.exr" if frame is None else f"{sid}_f{frame:02d}.exr"


def regenerate_command(specula):
    return f"python3 tools/validate_glint.py --specula {rel(os.path.abspath(specula))} --refs"


def cache_spec(specula, scenes):
    """The cache as this script derives it now (tools/specula_validation/manifest.py): per scene the reference and
    coverage variants, the main reference (REF_SPP) and FRAMES flicker frames (FRAME_SPP, camera shifted)."""
    c = Cache(CACHE, page=rel(DOC), generator="tools/validate_glint.py", regenerate=regenerate_command(specula),
              protocol={"ref_spp": REF_SPP, "frame_spp": FRAME_SPP, "frames": FRAMES, "shift_px": SHIFT_PX,
                        "coverage_spp": COVER_SPP, "filter": "box", "ggaa": "off", "derivatives": "quad",
                        "normal_map": "full resolution (texture.image with zero footprint)",
                        "storage": "specular AOV (half) + coverage.Y (the coverage variant's R channel), ZIP"})
    for sid in scenes:
        base = load_scene(sid)
        c.add_scene(sid, os.path.join(EXAMPLES, SCENES[sid]["file"]), EXAMPLES)
        c.add_variant(sid, "reference", derive(base, REF))
        c.add_variant(sid, "coverage", coverage_scene(base))
        c.add_file(sid, ref_name(sid), "reference", REF_SPP)
        for t in range(FRAMES):
            c.add_file(sid, ref_name(sid, t), "reference", FRAME_SPP, shift_px(t))
    return c


def file_command(name, spp, frame):
    shift = f" --camera-shift-px {frame * SHIFT_PX!r},0.0" if frame else ""
    stem = name[:-4]
    return (f"specula render reference.json -o {stem}_full.exr --spp {spp}{shift}  &&  specula render "
            f"coverage.json -o {stem}_cov.exr{shift}  &&  oiiotool {stem}_full.exr --ch specular.R,specular.G,"
            f"specular.B {stem}_cov.exr --ch R --chnames coverage.Y --chappend -d half --compression zip -o {name}")


def check_cache(specula, scenes, workdir=None):
    """Human-readable problems (empty = the cache matches scenes, maps, derivation and the renderer's output)."""
    with tempfile.TemporaryDirectory(prefix="glint_probe_") as tmp:
        return cache_spec(specula, scenes).check(specula, workdir or tmp)


def frame_ref_noise(rnd, sid):
    """Reference noise floor of the flicker metric: a second frame-0 reference with another seed."""
    sc = derive(load_scene(sid), REF)
    a, _ = rnd.render(sc, f"{sid}_noise0", spp=FRAME_SPP, shift_px=shift_px(0))
    b, _ = rnd.render(sc, f"{sid}_noise1", spp=FRAME_SPP, shift_px=shift_px(0), seed=1)
    ia, ib, ic = exr.read([a, b, os.path.join(CACHE, ref_name(sid, 0))])
    idx = mask_pixels(ic)
    d = sum(abs(spec(ia)[c][i] - spec(ib)[c][i]) for c in range(3) for i in idx) / (3 * len(idx))
    return {"mean_abs_diff_seed0_seed1": d, "sigma_estimate": d * math.sqrt(math.pi) / 2,
            "note": "per-pixel noise std of a 256-spp frame reference, mean over the mask "
                    "(sqrt(pi)/2 E|X-Y|); the flicker metric cannot go below about this"}


def write_manifest(specula, scenes, workdir, records=None, extra=None):
    """The manifest for the cached files as they are (records: how each was made; extra: per-scene notes)."""
    old = {}
    if os.path.exists(MANIFEST):
        with open(MANIFEST) as f:
            old = json.load(f).get("scenes", {})
    c = cache_spec(specula, scenes)
    recs, ext = {}, {}
    for sid in scenes:
        for f in old.get(sid, {}).get("files", []):
            recs[f["file"]] = {k: f[k] for k in ("command", "seconds") if k in f}
        ext[sid] = old.get(sid, {}).get("extra", {})
    recs.update(records or {})
    for sid, e in (extra or {}).items():
        ext.setdefault(sid, {}).update(e)
    c.write(specula, workdir, recs, specula_version(specula), ext)


def build_cache(specula, scenes, workdir, verbose):
    os.makedirs(CACHE, exist_ok=True)
    rnd = renderer(specula, workdir, verbose)
    records, extra = {}, {}
    for sid in scenes:
        base = load_scene(sid)
        sc, cov = derive(base, REF), coverage_scene(base)
        for frame in [None] + list(range(FRAMES)):
            t0 = time.time()
            name, spp = ref_name(sid, frame), REF_SPP if frame is None else FRAME_SPP
            secs = cache_ref(rnd, sc, cov, os.path.join(CACHE, name), name[:-4], spp, frame)
            records[name] = {"command": file_command(name, spp, frame), "seconds": secs}
            print(f"  {name}: {spp} spp, render {secs:.1f} s (wall {time.time() - t0:.1f} s)", flush=True)
        extra[sid] = {"frame_ref_noise": frame_ref_noise(rnd, sid)}
    write_manifest(specula, scenes, workdir, records, extra)
    total = sum(os.path.getsize(os.path.join(CACHE, f)) for f in os.listdir(CACHE) if f.endswith(".exr"))
    print(f"cache: {rel(CACHE)} ({total / 1e6:.2f} MB of EXRs), manifest {rel(MANIFEST)}")


# ---- evaluation --------------------------------------------------------------------------------------------------
def evaluate(specula, workdir, scenes, methods=None, flicker_methods=None, verbose=False, keep=False,
             cross_check=False, images=False):
    """Renders the 1-spp tests and compares them with the cached references (`specula compare`, masked by the
    references' coverage). methods / flicker_methods: dict scene -> list of method ids (None = all of the
    scene's). images: also read the pictures' pixels (for --docs). Returns {scene: {...}}."""
    rnd = renderer(specula, workdir, verbose)
    results = {}
    for sid in scenes:
        cfg = SCENES[sid]
        base = load_scene(sid)
        mdefs = {k: (label, m) for k, label, m in cfg["methods"]}
        mids = [k for k, _, _ in cfg["methods"]] if methods is None else methods.get(sid, [])
        fids = cfg["flicker"] if flicker_methods is None else flicker_methods.get(sid, [])
        far = cfg.get("far_rows", False)
        res = {"methods": {}, "flicker": {}, "baseline": cfg["baseline"]}
        ref = os.path.join(CACHE, ref_name(sid))
        mask = [ref + ":coverage"]
        paths = {}
        for k in mids:
            p, secs = rnd.render(derive(base, mdefs[k][1]), f"{sid}_{k}")
            paths[k] = p
            m = metrics.compare(specula, p, ref, masks=mask)
            r = {"rmse": m["rmse"], "mae": m["mae"], "rel": m["rel_rmse"], "pixels": m["mask_pixels"]}
            res["mask_pixels"] = m["mask_pixels"]
            res["w"], res["h"] = m["width"], m["height"]
            if far:  # the third of the object's rows nearest the horizon
                f = metrics.compare(specula, p, ref, masks=mask, top_rows="1/3")
                r["far"] = {"rmse": f["rmse"], "mae": f["mae"], "rel": f["rel_rmse"], "pixels": f["mask_pixels"]}
            r["label"] = mdefs[k][0]
            r["seconds_128"] = secs
            if cross_check:  # masked RMSE^2 * mask / frame = full-frame RMSE^2 when nothing outside the mask differs
                r["full_frame_rmse"] = metrics.compare(specula, p, ref)["rmse"]
                r["full_frame_rmse_from_mask"] = r["rmse"] * math.sqrt(m["mask_pixels"] / (m["width"] * m["height"]))
            res["methods"][k] = r
        if images:
            imgs = exr.read([ref] + [paths[k] for k in mids])
            res["ref"] = spec(imgs[0])
            res["mask"] = mask_pixels(imgs[0])
            for k, img in zip(mids, imgs[1:]):
                res["methods"][k]["image"] = spec(img)
        # flicker
        if fids:
            fref = os.path.join(CACHE, f"{sid}_f%02d.exr")
            fmask = [fref + ":coverage"]
            if images:
                frefs = exr.read([fref % t for t in range(FRAMES)])
                res["flicker_mask"] = sorted({i for x in frefs for i in mask_pixels(x)})
            for k in fids:
                for t in range(FRAMES):
                    rnd.render(derive(base, mdefs[k][1]), f"{sid}_{k}_f{t:02d}", shift_px=shift_px(t))
                pattern = os.path.join(workdir, f"{sid}_{k}_f%02d.exr")
                m = metrics.flicker(specula, pattern, fref, FRAMES, masks=fmask)
                res["flicker_mask_pixels"] = m["mask_pixels"]
                res["ref_shimmer"] = m["shimmer_ref"]
                fr = {"flicker": m["flicker"], "label": mdefs[k][0], "shimmer": m["shimmer"]}
                if far:
                    fr["far"] = metrics.flicker(specula, pattern, fref, FRAMES, masks=fmask, top_rows="1/3")["flicker"]
                if images:
                    tests = [spec(x) for x in exr.read([pattern % t for t in range(FRAMES)])]
                    fr["map"] = temporal_std_map(tests, [spec(x) for x in frefs])
                res["flicker"][k] = fr
                if not keep:
                    for t in range(FRAMES):
                        for ext in (".exr", ".png", ".json"):
                            if os.path.exists((pattern % t)[:-4] + ext):
                                os.remove((pattern % t)[:-4] + ext)
        results[sid] = res
    results["_renders"] = rnd.count
    return results


def print_tables(results, file=sys.stdout):
    for sid, res in results.items():
        if sid.startswith("_"):
            continue
        b = res["methods"].get(res["baseline"])
        fb = res["flicker"].get(res["baseline"])
        print(f"\n{SCENES[sid]['title']}  (mask {res['mask_pixels']} px)", file=file)
        print(f"  {'method':52} {'RMSE':>8} {'MAE':>8} {'relRMSE':>8} {'ratio':>6} {'flicker':>8} {'fl.ratio':>8}",
              file=file)
        for k, r in res["methods"].items():
            fl = res["flicker"].get(k)
            rt = ratio(r["rmse"], b["rmse"]) if b else float("nan")
            fs = (f"{fl['flicker']:8.4f} {ratio(fl['flicker'], fb['flicker']) if fb else float('nan'):8.3f}"
                  f"  shimmer {fl['shimmer']:.4f} (refs {res['ref_shimmer']:.4f})") if fl else ""
            print(f"  {r['label']:52} {r['rmse']:8.4f} {r['mae']:8.4f} {r['rel']:8.3f} {rt:6.3f} {fs}", file=file)
            if "far" in r:
                rf = ratio(r["far"]["rmse"], b["far"]["rmse"]) if b else float("nan")
                ff = f"{fl['far']:8.4f} {ratio(fl['far'], fb['far']):8.3f}" if fl and fb else ""
                print(f"  {'   far third of the plane':52} {r['far']['rmse']:8.4f} {r['far']['mae']:8.4f} "
                      f"{r['far']['rel']:8.3f} {rf:6.3f} {ff}", file=file)


# ---- pictures (tools/specula_validation/page.py) -----------------------------------------------------------------
def strip(path, res, ids, S=2, gap=4):
    """Row 1: reference and methods (tone-mapped specular); row 2: |test - ref| (mean over RGB) on one viridis scale
    (99th percentile of the baseline's error inside the mask), with its colour bar under the reference column."""
    w, h = res["w"], res["h"]
    ref = res["ref"]
    mask = res["mask"]
    peak = percentile([max(ref[c][i] for c in range(3)) for i in mask], 0.99)
    exposure = 1.0 / peak if peak > 0 else 1.0
    base = res["methods"][res["baseline"]]["image"]
    scale = percentile([sum(abs(base[c][i] - ref[c][i]) for c in range(3)) / 3 for i in mask], 0.99) or 1.0
    cols = 1 + len(ids)
    cv = Canvas(cols * w * S + (cols - 1) * gap, 2 * h * S + gap)
    cv.blit(tonemap(ref, exposure), w, h, 0, 0, S)
    for j, k in enumerate(ids):
        x = (j + 1) * (w * S + gap)
        img = res["methods"][k]["image"]
        cv.blit(tonemap(img, exposure), w, h, x, 0, S)
        cv.blit(errmap(img, ref, scale), w, h, x, h * S + gap, S)
    colorbar(cv, 8, h * S + gap + h * S // 2 - 12, w * S - 16, 12, scale)
    return cv.save(path), exposure, scale


def flicker_strip(path, res, ids, S=2, gap=4):
    w, h = res["w"], res["h"]
    maps = [res["flicker"][k]["map"] for k in ids]
    base = res["flicker"][res["baseline"]]["map"]
    scale = percentile([base[i] for i in res["mask"]], 0.99) or 1.0
    cols = len(ids)
    cv = Canvas(cols * w * S + (cols - 1) * gap, h * S + 30)
    for j, m in enumerate(maps):
        cv.blit([viridis(v / scale) for v in m], w, h, j * (w * S + gap), 0, S)
    colorbar(cv, 8, h * S + 4, w * S - 16, 10, scale)
    return cv.save(path), scale


# ---- convergence (C21 Fig. 10) -----------------------------------------------------------------------------------------
CONV_RHOS = [0.0, 0.6, -0.9]
CONV_LAMBDAS = [15, 50, 80]  # 80: every cell converged -> exactly Cook-Torrance with the correlated Beckmann P_B
CONV_BLOCKS = [1, 2, 4, 8, 16]


def block_mean(img, w, h, b):
    out = []
    for by in range(0, h - h % b, b):
        for bx in range(0, w - w % b, b):
            out.append(sum(img[(by + y) * w + bx + x] for y in range(b) for x in range(b)) / (b * b))
    return out


def orientation(lum, w, h):
    """Principal-axis angle (degrees, image x right / y up) and axis ratio of the highlight (intensity moments)."""
    s = sx = sy = 0.0
    for i, v in enumerate(lum):
        x, y = i % w, -(i // w)
        s += v
        sx += v * x
        sy += v * y
    mx, my = sx / s, sy / s
    cxx = cyy = cxy = 0.0
    for i, v in enumerate(lum):
        x, y = i % w - mx, -(i // w) - my
        cxx += v * x * x
        cyy += v * y * y
        cxy += v * x * y
    cxx, cyy, cxy = cxx / s, cyy / s, cxy / s
    ang = 0.5 * math.degrees(math.atan2(2 * cxy, cxx - cyy))
    tr, det = cxx + cyy, cxx * cyy - cxy * cxy
    l1 = tr / 2 + math.sqrt(max(tr * tr / 4 - det, 0))
    l2 = tr / 2 - math.sqrt(max(tr * tr / 4 - det, 0))
    return ang, math.sqrt(l1 / l2) if l2 > 0 else float("inf")


def convergence(specula, workdir, verbose=False, picture=None):
    with open(os.path.join(EXAMPLES, "convergence.json")) as f:
        base = json.load(f)
    base.pop("description", None)
    rnd = renderer(specula, workdir, verbose)
    paths = {}
    for rho in CONV_RHOS:
        for lam in CONV_LAMBDAS:
            s = copy.deepcopy(base)
            g = s["materials"]["glint"]["nodes"]["g"]["inputs"]
            g["rho"], g["log_density"] = rho, lam
            paths[(rho, lam)], _ = rnd.render(s, f"conv_{rho}_{lam}")
    keys = list(paths)
    imgs = dict(zip(keys, exr.read([paths[k] for k in keys])))
    w, h = imgs[keys[0]]["w"], imgs[keys[0]]["h"]
    rows = []
    for rho in CONV_RHOS:
        lim = spec(imgs[(rho, 80)])
        lim_l = [sum(lim[c][i] for c in range(3)) / 3 for i in range(w * h)]
        ang_lim, ar_lim = orientation(lim_l, w, h)
        for lam in CONV_LAMBDAS[:-1]:
            im = spec(imgs[(rho, lam)])
            lum = [sum(im[c][i] for c in range(3)) / 3 for i in range(w * h)]
            ang, ar = orientation(lum, w, h)
            errs = []
            for b in CONV_BLOCKS:
                t, r = block_mean(lum, w, h, b), block_mean(lim_l, w, h, b)
                mse = sum((x - y) ** 2 for x, y in zip(t, r)) / len(r)
                errs.append(math.sqrt(mse) / (sum(r) / len(r)))
            g = base["materials"]["glint"]["nodes"]["g"]["inputs"]
            sx, sy = g["sigma_x"], g["sigma_y"]  # principal-axis angle of Sigma (C21 Eq. 16) in slope space
            ang_sigma = 0.5 * math.degrees(math.atan2(2 * rho * sx * sy, sx * sx - sy * sy))
            rows.append({"rho": rho, "lambda": lam, "rel_rmse_blocks": errs, "energy": sum(lum) / sum(lim_l),
                         "angle": ang, "axis_ratio": ar, "angle_limit": ang_lim, "axis_ratio_limit": ar_lim,
                         "angle_sigma": ang_sigma})
    if picture:
        peak = max(max(spec(imgs[(rho, 80)])[1]) for rho in CONV_RHOS)
        S, gap = 1, 4
        cv = Canvas(len(CONV_RHOS) * (w + gap) - gap, len(CONV_LAMBDAS) * (h + gap) - gap)
        for j, rho in enumerate(CONV_RHOS):
            for i, lam in enumerate(CONV_LAMBDAS):
                cv.blit(tonemap(spec(imgs[(rho, lam)]), 1.5 / peak), w, h, j * (w + gap), i * (h + gap), S)
        picture["bytes"] = cv.save(picture["path"])
    return rows


# ---- timings -----------------------------------------------------------------------------------------------------------
def timings(specula, workdir, sid, ids, resolution="512x384", repeats=5):
    """Render seconds (minimum of `repeats`, one thread: the machine is shared) of 1-spp frames at a larger
    resolution, per method."""
    base = load_scene(sid)
    mdefs = {k: m for k, _, m in SCENES[sid]["methods"]}
    rnd = renderer(specula, workdir)
    out = {}
    for k in ids:
        ts = [rnd.render(derive(base, mdefs[k]), f"time_{sid}_{k}", resolution=resolution, threads=1)[1]
              for _ in range(repeats)]
        out[k] = min(ts)
    return out


# ---- docs -----------------------------------------------------------------------------------------------------------------
def write_docs(specula, results, conv_rows, times, pictures, commands):
    def f(x, d=4):
        return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{d}f}"
    lines = ["<!-- BEGIN GENERATED by tools/validate_glint.py --docs: do not edit by hand -->", ""]
    with open(MANIFEST) as fm:
        man = json.load(fm)
    lines.append(f"Renderer: `{man['renderer_version']}` (cache fingerprint: probe renders, "
                 f"tools/specula_validation/manifest.py); "
                 f"references {REF_SPP} spp (flicker frames {FRAME_SPP} spp), 128×96, box filter, GGAA off, "
                 f"GPU-quad derivatives. Tests: 1 spp at the pixel centre. Errors on the specular AOV, linear, inside "
                 f"the object mask, over the three channels.")
    lines.append("")
    lines.append("| scene | method | RMSE | MAE | rel. RMSE | ratio vs baseline | flicker | flicker ratio | "
                 "time / frame (ms, 512×384, 1 thread) |")
    lines.append("|---|---|---|---|---|---|---|---|---|")
    for sid, res in results.items():
        if sid.startswith("_"):
            continue
        b = res["methods"][res["baseline"]]
        fb = res["flicker"].get(res["baseline"])
        for k, r in res["methods"].items():
            fl = res["flicker"].get(k)
            t = times.get(sid, {}).get(k)
            lines.append(f"| {sid} | {r['label']} | {f(r['rmse'])} | {f(r['mae'])} | {f(r['rel'], 3)} | "
                         f"{f(ratio(r['rmse'], b['rmse']), 3)} | {f(fl['flicker']) if fl else '–'} | "
                         f"{f(ratio(fl['flicker'], fb['flicker']), 3) if fl and fb else '–'} | "
                         f"{f(t * 1000, 0) if t else '–'} |")
        if any("far" in r for r in res["methods"].values()):
            for k, r in res["methods"].items():
                fl = res["flicker"].get(k)
                lines.append(f"| {sid}, far third | {r['label']} | {f(r['far']['rmse'])} | {f(r['far']['mae'])} | "
                             f"{f(r['far']['rel'], 3)} | {f(ratio(r['far']['rmse'], b['far']['rmse']), 3)} | "
                             f"{f(fl['far']) if fl else '–'} | "
                             f"{f(ratio(fl['far'], fb['far']), 3) if fl and fb else '–'} | |")
    lines.append("")
    lines.append("Raw temporal variation (\"shimmer\": mean over the mask of the per-pixel std over the 16 frames of "
                 "the image itself, not of its error; the paper's word for what s_K 1 reduces):")
    lines.append("")
    lines.append("| scene | method | shimmer | shimmer of the references |")
    lines.append("|---|---|---|---|")
    for sid, res in results.items():
        if sid.startswith("_"):
            continue
        for k, fl in res["flicker"].items():
            lines.append(f"| {sid} | {fl['label']} | {f(fl['shimmer'])} | {f(res['ref_shimmer'])} |")
    lines.append("")
    worst = max((abs(r["full_frame_rmse"] / r["full_frame_rmse_from_mask"] - 1), sid, k)
                for sid, res in results.items() if not sid.startswith("_")
                for k, r in res["methods"].items() if "full_frame_rmse" in r)
    lines.append(f"Cross-check with `specula compare --aov specular` (whole frame): RMSE_frame = RMSE_mask · "
                 f"√(mask / frame) for every row, largest relative deviation {worst[0]:.1e} ({worst[1]}, {worst[2]}); "
                 f"the ratios are therefore the same over the whole frame.")
    lines.append("")
    lines.append("Reference noise floor of the flicker metric (per-pixel noise std of a 256-spp frame reference, mean "
                 "over the mask): " + ", ".join(f"{sid} {man['scenes'][sid]['extra']['frame_ref_noise']['sigma_estimate']:.4f}"
                                                for sid in results if not sid.startswith("_")) + ".")
    lines.append("")
    lines.append("Convergence (Fig. 10 analogue, σ = (0.12, 0.05), 256×256, 1 spp): relative RMSE of the glinty image "
                 "against the λ = 80 limit after averaging b×b pixel blocks, energy ratio, and the highlight's "
                 "principal-axis angle and axis ratio (in brackets: the λ = 80 limit, and the principal-axis angle "
                 "of the slope covariance Σ itself).")
    lines.append("")
    lines.append("| ρ | λ | " + " | ".join(f"b = {b}" for b in CONV_BLOCKS) +
                 " | energy | angle (limit; Σ) | axis ratio (limit) |")
    lines.append("|---|---|" + "---|" * len(CONV_BLOCKS) + "---|---|---|")
    for r in conv_rows:
        lines.append(f"| {r['rho']} | {r['lambda']} | " + " | ".join(f"{e:.3f}" for e in r["rel_rmse_blocks"]) +
                     f" | {r['energy']:.3f} | {r['angle']:.1f}° ({r['angle_limit']:.1f}°; {r['angle_sigma']:.1f}°) | "
                     f"{r['axis_ratio']:.2f} ({r['axis_ratio_limit']:.2f}) |")
    lines.append("")
    lines.append("Pictures written: " + ", ".join(f"`{os.path.basename(p)}` ({n // 1024} KB)" for p, n in pictures) + ".")
    lines.append("")
    lines.append(f"Tables from {commands} `specula render` runs (plus the timing and convergence renders), made by "
                 f"`python3 tools/validate_glint.py --specula {rel(os.path.abspath(specula))} --docs`.")
    lines.append("")
    lines.append("<!-- END GENERATED -->")
    block = "\n".join(lines)
    text = open(DOC).read() if os.path.exists(DOC) else "# Glint validation\n\n<!-- BEGIN GENERATED -->\n<!-- END GENERATED -->\n"
    a = text.index("<!-- BEGIN GENERATED")
    z = text.index("<!-- END GENERATED -->") + len("<!-- END GENERATED -->")
    with open(DOC, "w") as fd:
        fd.write(text[:a] + block + text[z:])
    print(f"wrote {rel(DOC)}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--specula", default=os.path.join(ROOT, "build", "bin", "specula"))
    ap.add_argument("--refs", action="store_true", help="regenerate the cached references and the manifest")
    ap.add_argument("--docs", action="store_true", help="write docs/validation/img/glint-*.png and the page's tables")
    ap.add_argument("--check-cache", action="store_true", help="only check that the cache is up to date")
    ap.add_argument("--manifest", action="store_true",
                    help="rewrite the manifest for the cached files as they are (after a deliberate, verified change)")
    ap.add_argument("--scenes", default=",".join(SCENES), help="comma-separated subset of " + ",".join(SCENES))
    ap.add_argument("--workdir", help="keep intermediate renders here (default: a temporary folder)")
    ap.add_argument("--json", help="also write the numbers to this JSON file")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every command")
    a = ap.parse_args()
    scenes = [s for s in a.scenes.split(",") if s]
    work = a.workdir or tempfile.mkdtemp(prefix="validate_glint_")
    os.makedirs(work, exist_ok=True)
    if a.refs:
        t0 = time.time()
        build_cache(a.specula, scenes, work, a.verbose)
        print(f"references regenerated in {time.time() - t0:.0f} s")
    if a.manifest:
        write_manifest(a.specula, scenes, work)
        print(f"wrote {rel(MANIFEST)}")
    problems = check_cache(a.specula, scenes)
    if problems:
        print("STALE glint validation cache:\n  " + "\n  ".join(problems) +
              f"\nRegenerate with: {regenerate_command(a.specula)}", file=sys.stderr)
        return 1
    if a.check_cache:
        print("cache up to date")
        return 0
    t0 = time.time()
    results = evaluate(a.specula, work, scenes, verbose=a.verbose, cross_check=a.docs, images=a.docs)
    commands = results.pop("_renders")
    print_tables(results)
    print(f"\n{commands} renders, {time.time() - t0:.0f} s")
    conv_rows, times, pictures = [], {}, []
    if a.docs:
        os.makedirs(IMG, exist_ok=True)
        for sid, res in results.items():
            p = os.path.join(IMG, f"glint-{sid}.png")
            n, _, _ = strip(p, res, [k for k in SCENES[sid]["pictures"] if k in res["methods"]])
            pictures.append((p, n))
            if res["flicker"]:
                p = os.path.join(IMG, f"glint-{sid}-flicker.png")
                n, _ = flicker_strip(p, res, [k for k in SCENES[sid]["flicker"] if k in res["flicker"]])
                pictures.append((p, n))
            times[sid] = timings(a.specula, work, sid, [k for k in res["methods"]])
        pic = {"path": os.path.join(IMG, "glint-convergence.png")}
        conv_rows = convergence(a.specula, work, a.verbose, pic)
        pictures.append((pic["path"], pic["bytes"]))
        for r in conv_rows:
            print(f"rho {r['rho']:5} lambda {r['lambda']}: rel RMSE vs limit by block "
                  + " ".join(f"{e:.3f}" for e in r["rel_rmse_blocks"])
                  + f"  energy {r['energy']:.3f}  angle {r['angle']:.1f} ({r['angle_limit']:.1f})"
                  + f"  axis ratio {r['axis_ratio']:.2f} ({r['axis_ratio_limit']:.2f})")
        for sid, t in times.items():
            print(sid, " ".join(f"{k} {v * 1000:.0f} ms" for k, v in t.items()))
        write_docs(a.specula, results, conv_rows, times, pictures, commands)
    if a.json:
        slim = {sid: {"mask_pixels": r["mask_pixels"],
                      "methods": {k: {x: v for x, v in m.items() if x != "image"} for k, m in r["methods"].items()},
                      "flicker": {k: {x: v for x, v in m.items() if x != "map"} for k, m in r["flicker"].items()}}
                for sid, r in results.items()}
        with open(a.json, "w") as f:
            json.dump({"results": slim, "convergence": conv_rows, "timings": times}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
