#!/usr/bin/env python3
"""Glint validation (issue 6; protocol ../shared/specs/validation.md; page docs/validation/glint.md).

Reproduces the claims of Chermain et al. 2021 (C21) for the `bsdf.glint` node on three small scenes in
examples/glint/ (tubes = Fig. 8, brushed_sphere = Fig. 7, horizon = Fig. 1) and a convergence scene (Fig. 10):

  * references: 1024 spp, box filter, GGAA off, full-resolution normal map, GPU-quad derivatives (so the glint
    footprint/LOD is the 1-pixel one the 1-spp tests use), cached as half-float EXRs (specular AOV + a coverage
    channel) in tests/validation/glint/ with a manifest (commands, SHA-256 of scenes, maps and glint sources,
    renderer version);
  * tests: 1 spp at the pixel centre; RMSE / MAE / relative RMSE of the specular AOV inside the object mask;
  * flicker: 16 frames, camera translated by 1/8 pixel per frame; flicker = mean over the mask of the per-pixel
    standard deviation over t of (test_t - ref_t); frame references 256 spp, cached too.

Usage (run from anywhere; BIN defaults to build/bin/specula):
  tools/validate_glint.py --specula BIN --refs       regenerate the cached references + manifest (~15 min on 2 cores)
  tools/validate_glint.py --specula BIN              evaluate every method against the cached references, print tables
  tools/validate_glint.py --specula BIN --docs       ... and write docs/validation/img/glint-*.png and the generated
                                                     block of docs/validation/glint.md (adds timings, convergence figure)
  tools/validate_glint.py --specula BIN --check-cache   only check that the cache is up to date (exit 1 if stale)
Needs python3 and oiiotool (OpenImageIO tools) to read EXRs; no numpy.
"""
import argparse
import copy
import hashlib
import json
import math
import os
import shlex
import struct
import subprocess
import sys
import tempfile
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLES = os.path.join(ROOT, "examples", "glint")
CACHE = os.path.join(ROOT, "tests", "validation", "glint")
MANIFEST = os.path.join(CACHE, "manifest.json")
DOC = os.path.join(ROOT, "docs", "validation", "glint.md")
IMG = os.path.join(ROOT, "docs", "validation", "img")

# The CPU evaluation of bsdf.glint: a change here changes the references (the test then fails as stale).
GLINT_SOURCES = ["nodes/bsdf/glint/glint_bsdf.h", "nodes/bsdf/glint/glint_bsdf.cpp",
                 "nodes/bsdf/glint/glint_dictionary.h", "nodes/bsdf/glint/glint_dictionary.cpp",
                 "nodes/bsdf/glint/glint.node.cpp"]
REF_SPP = 1024      # main references (C21: 1,024 spp)
FRAME_SPP = 256     # per-frame references of the flicker sequences
FRAMES = 16         # K (validation.md §2)
SHIFT_PX = 0.125    # camera translation per frame, in pixels at the look-at distance
COVER_SPP = 64      # coverage (object mask) renders
CACHE_FORMAT = 1


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
def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def sha256_json(obj):
    return hashlib.sha256(json.dumps(obj, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def rel(path):
    return os.path.relpath(path, ROOT)


def load_scene(sid):
    with open(os.path.join(EXAMPLES, SCENES[sid]["file"])) as f:
        return json.load(f)


def map_files(scene):
    """Relative paths (as written in the scene) of every 'file' input of every node."""
    out = []
    for m in scene.get("materials", {}).values():
        for n in m.get("nodes", {}).values():
            f = n.get("inputs", {}).get("file")
            if isinstance(f, str) and f not in out:
                out.append(f)
    return out


def glint_nodes(scene):
    return [(m, n) for m in scene.get("materials", {}).values() for n in m.get("nodes", {}).values()
            if n.get("type") == "bsdf.glint"]


def specula_version(specula):
    return subprocess.run([specula, "--version"], capture_output=True, text=True, check=True).stdout.strip()


def sources_sha256():
    h = hashlib.sha256()
    for p in GLINT_SOURCES:
        h.update(p.encode() + b"\0")
        with open(os.path.join(ROOT, p), "rb") as f:
            h.update(f.read())
    return h.hexdigest()


# ---- scene variants ---------------------------------------------------------------------------------------------
def camera_shift(scene, frame):
    """Camera translated sideways (along +right) by frame * SHIFT_PX pixels measured at the look-at distance."""
    cam = scene["camera"]
    p, la = cam["position"], cam["look_at"]
    up = cam.get("up", [0, 0, 1])
    f = [la[i] - p[i] for i in range(3)]
    dist = math.sqrt(sum(x * x for x in f))
    f = [x / dist for x in f]
    r = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]]
    rn = math.sqrt(sum(x * x for x in r))
    r = [x / rn for x in r]
    w, h = scene["render"]["width"], scene["render"]["height"]
    fov = math.radians(cam.get("fov", 39.6))
    span = 2 * dist * math.tan(fov / 2)
    px = span / (w if cam.get("fov_axis", "x") == "x" else h)
    d = frame * SHIFT_PX * px
    cam["position"] = [round(p[i] + d * r[i], 9) for i in range(3)]
    cam["look_at"] = [round(la[i] + d * r[i], 9) for i in range(3)]


def derive(base, method, frame=None):
    """The scene of one method (M(...)) or of the reference, optionally at a flicker frame. Paths stay relative to
    examples/glint/ (so the hash does not depend on the checkout); absolutize() before writing it elsewhere."""
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
    if frame is not None:
        camera_shift(s, frame)
    return s


def coverage_scene(base, frame=None):
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
    if frame is not None:
        camera_shift(s, frame)
    return s


def absolutize(scene):
    s = copy.deepcopy(scene)
    for m in s.get("materials", {}).values():
        for n in m.get("nodes", {}).values():
            f = n.get("inputs", {}).get("file")
            if isinstance(f, str) and not os.path.isabs(f):
                n["inputs"]["file"] = os.path.normpath(os.path.join(EXAMPLES, f))
    return s


# ---- rendering and image I/O -------------------------------------------------------------------------------------
class Renderer:
    def __init__(self, specula, workdir, verbose=False):
        self.specula = os.path.abspath(specula)
        self.work = workdir
        self.verbose = verbose
        self.commands = []
        self.count = 0

    def render(self, scene, name, extra=()):
        """Renders 'scene' to WORK/name.exr; returns (exr path, render seconds reported by specula)."""
        js = os.path.join(self.work, name + ".json")
        exr = os.path.join(self.work, name + ".exr")
        with open(js, "w") as f:
            json.dump(absolutize(scene), f, indent=1)
        cmd = [self.specula, "render", js, "-o", exr, "--progress", "json", *extra]
        self.commands.append(" ".join(shlex.quote(c) for c in cmd))
        if self.verbose:
            print("  $", self.commands[-1], flush=True)
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            raise RuntimeError(f"render failed ({out.returncode}): {self.commands[-1]}\n{out.stderr}")
        secs = None
        for line in out.stdout.splitlines():
            if '"event":"done"' in line:
                secs = json.loads(line)["seconds"]
        self.count += 1
        return exr, secs


def read_exrs(paths):
    """Reads EXRs through `oiiotool --info -v --dumpdata` (one process per batch). Returns a list of
    {"w", "h", "ch": {name: [floats, row-major]}}."""
    out = []
    for i in range(0, len(paths), 64):
        batch = paths[i:i + 64]
        res = subprocess.run(["oiiotool", "--info", "-v", "--dumpdata", *batch], capture_output=True, text=True)
        if res.returncode != 0:
            raise RuntimeError("oiiotool failed: " + res.stderr)
        cur = None
        for line in res.stdout.splitlines():
            s = line.strip()
            if s.startswith("Pixel ("):
                a, b = s.split(":", 1)
                x, y = a[a.index("(") + 1:a.index(")")].split(",")
                k = int(y) * cur["w"] + int(x)
                for name, v in zip(cur["names"], b.split()):
                    cur["ch"][name][k] = float(v)
            elif s.startswith("channel list:"):
                cur["names"] = [c.strip() for c in s[len("channel list:"):].split(",")]
                cur["ch"] = {n: [0.0] * (cur["w"] * cur["h"]) for n in cur["names"]}
            elif " x " in s and "channel" in s and ":" in s and not line.startswith(" "):
                dims = s.split(":", 1)[1].split(",")[0].split("x")
                cur = {"w": int(dims[0]), "h": int(dims[1])}
                out.append(cur)
    if len(out) != len(paths):
        raise RuntimeError(f"read {len(out)} images from {len(paths)} files")
    for img in out:
        img.pop("names", None)
    return out


def spec(img):
    return [img["ch"]["specular.R"], img["ch"]["specular.G"], img["ch"]["specular.B"]]


def cache_ref(renderer, scene, cover, out_path, name):
    """Renders the reference and its coverage and writes the cached half EXR (specular.RGB + coverage.Y)."""
    full, secs = renderer.render(scene, name)
    cov, _ = renderer.render(cover, name + "_cov")
    subprocess.run(["oiiotool", "--nosoftwareattrib", full, "--ch", "specular.R,specular.G,specular.B", cov,
                    "--ch", "R", "--chnames", "coverage.Y", "--chappend", "--eraseattrib", "DateTime",
                    "-d", "half", "--compression", "zip", "-o", out_path], check=True)
    return secs


# ---- metrics ------------------------------------------------------------------------------------------------------
def metrics(test, ref, mask):
    """RMSE, MAE and relative RMSE (RMSE / mean reference) over the mask and the 3 channels."""
    se = ae = sr = 0.0
    n = 0
    for c in range(3):
        t, r = test[c], ref[c]
        for i in mask:
            e = t[i] - r[i]
            se += e * e
            ae += abs(e)
            sr += r[i]
            n += 1
    rmse = math.sqrt(se / n)
    return {"rmse": rmse, "mae": ae / n, "rel": rmse / (sr / n) if sr > 0 else float("nan"), "pixels": n // 3}


def flicker(tests, refs, mask):
    """validation.md §2: mean over the mask (and channels) of the std over t of E_t = test_t - ref_t."""
    K = len(tests)
    acc = 0.0
    n = 0
    for c in range(3):
        for i in mask:
            es = [tests[t][c][i] - refs[t][c][i] for t in range(K)]
            mu = sum(es) / K
            acc += math.sqrt(sum((e - mu) ** 2 for e in es) / K)
            n += 1
    return acc / n


def flicker_map(tests, refs, w, h):
    K = len(tests)
    out = [0.0] * (w * h)
    for i in range(w * h):
        s = 0.0
        for c in range(3):
            es = [tests[t][c][i] - refs[t][c][i] for t in range(K)]
            mu = sum(es) / K
            s += math.sqrt(sum((e - mu) ** 2 for e in es) / K)
        out[i] = s / 3
    return out


def mask_of(img_list, far_rows=False):
    """Pixels with any coverage in any of the given cached references (union over the frames)."""
    w, h = img_list[0]["w"], img_list[0]["h"]
    m = [False] * (w * h)
    for img in img_list:
        cov = img["ch"]["coverage.Y"]
        for i in range(w * h):
            if cov[i] > 0:
                m[i] = True
    idx = [i for i in range(w * h) if m[i]]
    far = None
    if far_rows:  # the third of the object's rows nearest the horizon
        rows = sorted({i // w for i in idx})
        cut = rows[0] + (rows[-1] - rows[0] + 1) // 3
        far = [i for i in idx if i // w < cut]
    return idx, far


# ---- the cache -----------------------------------------------------------------------------------------------------
def ref_name(sid, frame=None):
    return f"{sid}_ref.exr" if frame is None else f"{sid}_f{frame:02d}.exr"


def expected_entries(sid):
    """(file name, frame or None, variant scene, coverage scene, spp) of every cached file of a scene."""
    base = load_scene(sid)
    out = [(ref_name(sid), None, derive(base, REF), coverage_scene(base), REF_SPP)]
    fm = dict(REF, spp=FRAME_SPP)
    for t in range(FRAMES):
        out.append((ref_name(sid, t), t, derive(base, fm, t), coverage_scene(base, t), FRAME_SPP))
    return out


def fingerprint(specula):
    return {"renderer_version": specula_version(specula), "glint_sources_sha256": sources_sha256(),
            "cache_format": CACHE_FORMAT}


def regenerate_command(specula):
    return f"python3 tools/validate_glint.py --specula {rel(os.path.abspath(specula))} --refs"


def check_cache(specula, scenes):
    """Returns a list of human-readable problems (empty = the cache matches scenes, maps, sources, renderer)."""
    problems = []
    if not os.path.exists(MANIFEST):
        return [f"{rel(MANIFEST)} does not exist"]
    with open(MANIFEST) as f:
        man = json.load(f)
    fp = fingerprint(specula)
    for k, v in fp.items():
        if man.get(k) != v:
            problems.append(f"{k}: cached {man.get(k)!r}, now {v!r}")
    for sid in scenes:
        ms = man.get("scenes", {}).get(sid)
        if ms is None:
            problems.append(f"scene {sid}: not in the manifest")
            continue
        sp = os.path.join(EXAMPLES, SCENES[sid]["file"])
        if ms.get("scene_sha256") != sha256_file(sp):
            problems.append(f"scene {sid}: {rel(sp)} changed (SHA-256 differs from the manifest)")
        base = load_scene(sid)
        for m in map_files(base):
            p = os.path.normpath(os.path.join(EXAMPLES, m))
            if ms.get("maps", {}).get(m) != (sha256_file(p) if os.path.exists(p) else None):
                problems.append(f"scene {sid}: map {rel(p)} changed or missing")
        files = {e["file"]: e for e in ms.get("files", [])}
        for name, frame, sc, cov, spp in expected_entries(sid):
            e = files.get(name)
            path = os.path.join(CACHE, name)
            if e is None:
                problems.append(f"{name}: not in the manifest")
            elif e.get("variant_sha256") != sha256_json(sc) or e.get("coverage_sha256") != sha256_json(cov):
                problems.append(f"{name}: the derived reference scene changed (tools/validate_glint.py or the scene)")
            elif not os.path.exists(path):
                problems.append(f"{name}: missing from {rel(CACHE)}")
            elif e.get("file_sha256") != sha256_file(path):
                problems.append(f"{name}: file content differs from the manifest")
    return problems


def build_cache(specula, scenes, workdir, verbose):
    os.makedirs(CACHE, exist_ok=True)
    man = {}
    if os.path.exists(MANIFEST):
        with open(MANIFEST) as f:
            man = json.load(f)
    man.update({"what": "Cached references of the glint validation (docs/validation/glint.md). Generated files: "
                        "do not edit. Each EXR holds the specular AOV (half) and the object coverage.",
                "regenerate": regenerate_command(specula), **fingerprint(specula),
                "paths": "file paths inside scene_json / coverage_json are relative to examples/glint/ (write the "
                         "JSON there, or make them absolute); frames differ from the main reference only by 'camera' "
                         "and render.spp",
                "protocol": {"ref_spp": REF_SPP, "frame_spp": FRAME_SPP, "frames": FRAMES, "shift_px": SHIFT_PX,
                             "coverage_spp": COVER_SPP, "filter": "box", "ggaa": "off", "derivatives": "quad",
                             "normal_map": "full resolution (texture.image with zero footprint)"}})
    man.setdefault("scenes", {})
    rnd = Renderer(specula, workdir, verbose)
    for sid in scenes:
        base = load_scene(sid)
        entry = {"scene": rel(os.path.join(EXAMPLES, SCENES[sid]["file"])),
                 "scene_sha256": sha256_file(os.path.join(EXAMPLES, SCENES[sid]["file"])),
                 "maps": {m: sha256_file(os.path.normpath(os.path.join(EXAMPLES, m))) for m in map_files(base)},
                 "files": []}
        for name, frame, sc, cov, spp in expected_entries(sid):
            t0 = time.time()
            path = os.path.join(CACHE, name)
            secs = cache_ref(rnd, sc, cov, path, name[:-4])
            e = {"file": name, "frame": frame, "spp": spp, "variant_sha256": sha256_json(sc),
                 "coverage_sha256": sha256_json(cov), "file_sha256": sha256_file(path), "render_seconds": secs,
                 "command": f"specula render {name[:-4]}.json -o {name[:-4]}_full.exr  &&  specula render "
                            f"{name[:-4]}_cov.json -o {name[:-4]}_cov.exr  &&  oiiotool {name[:-4]}_full.exr --ch "
                            f"specular.R,specular.G,specular.B {name[:-4]}_cov.exr --ch R --chnames coverage.Y "
                            f"--chappend -d half --compression zip -o {name}"}
            if frame is None:  # the full derived scenes of the main reference (frames differ only by the camera)
                e["scene_json"] = sc
                e["coverage_json"] = cov
            else:
                e["camera"] = {"position": sc["camera"]["position"], "look_at": sc["camera"]["look_at"]}
            entry["files"].append(e)
            print(f"  {name}: {spp} spp, render {secs:.1f} s (wall {time.time() - t0:.1f} s)", flush=True)
        # Reference noise floor of the flicker metric: a second frame-0 reference with another seed.
        sc = expected_entries(sid)[1][2]
        sc2 = copy.deepcopy(sc)
        sc2["render"]["seed"] = 1
        a, _ = rnd.render(sc, f"{sid}_noise0")
        b, _ = rnd.render(sc2, f"{sid}_noise1")
        ia, ib, ic = read_exrs([a, b, os.path.join(CACHE, ref_name(sid, 0))])
        idx, _ = mask_of([ic])
        d = sum(abs(spec(ia)[c][i] - spec(ib)[c][i]) for c in range(3) for i in idx) / (3 * len(idx))
        entry["frame_ref_noise"] = {"mean_abs_diff_seed0_seed1": d, "sigma_estimate": d * math.sqrt(math.pi) / 2,
                                    "note": "per-pixel noise std of a 256-spp frame reference, mean over the mask "
                                            "(sqrt(pi)/2 E|X-Y|); the flicker metric cannot go below about this"}
        man["scenes"][sid] = entry
        with open(MANIFEST, "w") as f:
            json.dump(man, f, indent=1)
            f.write("\n")
    total = sum(os.path.getsize(os.path.join(CACHE, f)) for f in os.listdir(CACHE) if f.endswith(".exr"))
    print(f"cache: {rel(CACHE)} ({total / 1e6:.2f} MB of EXRs), manifest {rel(MANIFEST)}")


# ---- evaluation --------------------------------------------------------------------------------------------------
def compare_rmse(specula, test, ref):
    """Full-frame RMSE of the specular AOV by `specula compare` (cross-check of the masked numbers)."""
    out = subprocess.run([specula, "compare", test, ref, "--aov", "specular", "--json"], capture_output=True,
                         text=True, check=True).stdout
    return json.loads(out)["rmse"]


def evaluate(specula, workdir, scenes, methods=None, flicker_methods=None, verbose=False, keep=False,
             cross_check=False):
    """Renders the 1-spp tests and compares them with the cached references. methods / flicker_methods: dict
    scene -> list of method ids (None = all of the scene's). Returns {scene: {...}}."""
    rnd = Renderer(specula, workdir, verbose)
    results = {}
    for sid in scenes:
        cfg = SCENES[sid]
        base = load_scene(sid)
        mdefs = {k: (label, m) for k, label, m in cfg["methods"]}
        mids = [k for k, _, _ in cfg["methods"]] if methods is None else methods.get(sid, [])
        fids = cfg["flicker"] if flicker_methods is None else flicker_methods.get(sid, [])
        res = {"methods": {}, "flicker": {}, "baseline": cfg["baseline"]}
        # main comparison
        paths = [os.path.join(CACHE, ref_name(sid))]
        times = {}
        for k in mids:
            p, secs = rnd.render(derive(base, mdefs[k][1]), f"{sid}_{k}")
            paths.append(p)
            times[k] = secs
        imgs = read_exrs(paths)
        ref = imgs[0]
        idx, far = mask_of([ref], cfg.get("far_rows", False))
        res["w"], res["h"] = ref["w"], ref["h"]
        res["mask_pixels"] = len(idx)
        res["ref"] = spec(ref)
        res["coverage"] = ref["ch"]["coverage.Y"]
        res["mask"] = idx
        for k, img in zip(mids, imgs[1:]):
            r = metrics(spec(img), spec(ref), idx)
            if far:
                r["far"] = metrics(spec(img), spec(ref), far)
            r["label"] = mdefs[k][0]
            r["seconds_128"] = times[k]
            r["image"] = spec(img)
            if cross_check:  # masked RMSE^2 * mask / frame = full-frame RMSE^2 when nothing outside the mask differs
                full = compare_rmse(specula, paths[1 + mids.index(k)], paths[0])
                r["full_frame_rmse"] = full
                r["full_frame_rmse_from_mask"] = r["rmse"] * math.sqrt(len(idx) / (ref["w"] * ref["h"]))
            res["methods"][k] = r
        # flicker
        if fids:
            fref_paths = [os.path.join(CACHE, ref_name(sid, t)) for t in range(FRAMES)]
            frefs = read_exrs(fref_paths)
            fidx, ffar = mask_of(frefs, cfg.get("far_rows", False))
            rspec = [spec(x) for x in frefs]
            res["flicker_mask_pixels"] = len(fidx)
            res["ref_shimmer"] = flicker(rspec, [[[0.0] * len(x[0]) for _ in range(3)] for x in rspec], fidx)
            for k in fids:
                tp = []
                for t in range(FRAMES):
                    p, _ = rnd.render(derive(base, mdefs[k][1], t), f"{sid}_{k}_f{t:02d}")
                    tp.append(p)
                tspec = [spec(x) for x in read_exrs(tp)]
                zero = [[[0.0] * len(x[0]) for _ in range(3)] for x in tspec]
                fr = {"flicker": flicker(tspec, rspec, fidx), "label": mdefs[k][0],
                      "shimmer": flicker(tspec, zero, fidx)}  # raw temporal std of the test itself
                if ffar:
                    fr["far"] = flicker(tspec, rspec, ffar)
                fr["map"] = flicker_map(tspec, rspec, frefs[0]["w"], frefs[0]["h"])
                res["flicker"][k] = fr
                if not keep:
                    for p in tp:
                        os.remove(p)
        results[sid] = res
    results["_renders"] = rnd.count
    return results


def ratio(a, b):
    return a / b if b > 0 else float("nan")


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


# ---- pictures (pure-Python PNG writer, viridis, 3x5 digit font) -----------------------------------------------------
VIRIDIS = [(68, 1, 84), (71, 44, 122), (59, 81, 139), (44, 113, 142), (33, 144, 141), (39, 173, 129), (92, 200, 99),
           (170, 220, 50), (253, 231, 37)]
FONT = {"0": "111101101101111", "1": "010110010010111", "2": "111001111100111", "3": "111001111001111",
        "4": "101101111001001", "5": "111100111001111", "6": "111100111101111", "7": "111001001001001",
        "8": "111101111101111", "9": "111101111001111", ".": "000000000000010", "e": "000111111100111",
        "-": "000000111000000", "+": "000010111010000", " ": "000000000000000"}


def viridis(t):
    t = min(max(t, 0.0), 1.0) * (len(VIRIDIS) - 1)
    i = min(int(t), len(VIRIDIS) - 2)
    f = t - i
    a, b = VIRIDIS[i], VIRIDIS[i + 1]
    return tuple(int(round(a[k] + (b[k] - a[k]) * f)) for k in range(3))


def srgb8(x):
    x = min(max(x, 0.0), 1.0)
    y = 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055
    return int(round(255 * y))


class Canvas:
    def __init__(self, w, h, bg=(24, 24, 24)):
        self.w, self.h = w, h
        self.px = [list(bg) for _ in range(w * h)]

    def put(self, x, y, c):
        if 0 <= x < self.w and 0 <= y < self.h:
            self.px[y * self.w + x] = list(c)

    def blit(self, rgb, w, h, x0, y0, scale):
        for y in range(h * scale):
            for x in range(w * scale):
                self.put(x0 + x, y0 + y, rgb[(y // scale) * w + x // scale])

    def text(self, s, x0, y0, scale=2, color=(230, 230, 230)):
        x = x0
        for ch in s:
            g = FONT.get(ch, FONT[" "])
            for j in range(5):
                for i in range(3):
                    if g[j * 3 + i] == "1":
                        for a in range(scale):
                            for b in range(scale):
                                self.put(x + i * scale + a, y0 + j * scale + b, color)
            x += 4 * scale

    def save(self, path):
        raw = b"".join(b"\0" + bytes(v for p in self.px[y * self.w:(y + 1) * self.w] for v in p)
                       for y in range(self.h))

        def chunk(t, d):
            c = struct.pack(">I", len(d)) + t + d
            return c + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
        data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", self.w, self.h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
        with open(path, "wb") as f:
            f.write(data)
        return len(data)


def tonemap(img, exposure):
    """Specular AOV -> sRGB 8-bit with exposure and Reinhard x/(1+x) per channel."""
    n = len(img[0])
    return [tuple(srgb8((v := img[c][i] * exposure) / (1 + v)) for c in range(3)) for i in range(n)]


def percentile(vals, q):
    s = sorted(vals)
    return s[min(len(s) - 1, int(q * (len(s) - 1)))] if s else 0.0


def errmap(test, ref, scale):
    n = len(ref[0])
    return [viridis((sum(abs(test[c][i] - ref[c][i]) for c in range(3)) / 3) / scale) for i in range(n)]


def fmt_num(x):
    return f"{x:.3g}" if x >= 0.001 else f"{x:.1e}"


def colorbar(cv, x0, y0, w, h, scale):
    for x in range(w):
        c = viridis(x / (w - 1))
        for y in range(h):
            cv.put(x0 + x, y0 + y, c)
    cv.text("0", x0, y0 + h + 3)
    s = fmt_num(scale)
    cv.text(s, x0 + w - 8 * len(s), y0 + h + 3)


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
    rnd = Renderer(specula, workdir, verbose)
    paths = {}
    for rho in CONV_RHOS:
        for lam in CONV_LAMBDAS:
            s = copy.deepcopy(base)
            g = s["materials"]["glint"]["nodes"]["g"]["inputs"]
            g["rho"], g["log_density"] = rho, lam
            paths[(rho, lam)], _ = rnd.render(s, f"conv_{rho}_{lam}")
    keys = list(paths)
    imgs = dict(zip(keys, read_exrs([paths[k] for k in keys])))
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
    rnd = Renderer(specula, workdir)
    out = {}
    for k in ids:
        ts = [rnd.render(derive(base, mdefs[k]), f"time_{sid}_{k}", ["--resolution", resolution, "--threads", "1"])[1]
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
    lines.append(f"Renderer: `{man['renderer_version']}`; glint sources SHA-256 `{man['glint_sources_sha256'][:16]}…`; "
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
                 "over the mask): " + ", ".join(f"{sid} {man['scenes'][sid]['frame_ref_noise']['sigma_estimate']:.4f}"
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
    problems = check_cache(a.specula, scenes)
    if problems:
        print("STALE glint validation cache:\n  " + "\n  ".join(problems) +
              f"\nRegenerate with: {regenerate_command(a.specula)}", file=sys.stderr)
        return 1
    if a.check_cache:
        print("cache up to date")
        return 0
    t0 = time.time()
    results = evaluate(a.specula, work, scenes, verbose=a.verbose, cross_check=a.docs)
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
