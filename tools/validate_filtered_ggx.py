#!/usr/bin/env python3
"""Filtered-GGX validation (issue 4): cached references, measurements, table and pictures.

Protocol: shared/specs/validation.md. Page: docs/validation/filtered-ggx.md. Test: tests/unit/test_validation_filtered_ggx.cpp
(ctest, label cpu), which renders the 1-spp images in-process and compares them with the cached references.

Scenes are examples/filtered-ggx/{sphere,torus,cylinders,plane}.json, each written in its *reference* configuration
(4096 spp, Gaussian pixel filter with sigma^2 = 1/(2 pi), every bsdf.ggx_filtered with filter "none"). The 1-spp test
renders are derived from them by changing only: render.spp = 1, render.pixel_center = true, render.derivatives
(ray | quad) and, in every bsdf.ggx_filtered node, the inputs filter, kernel and derivatives (analytic | quad).

Commands (run from anywhere; paths are relative to the repository root):

  tools/validate_filtered_ggx.py [--build DIR] references [--force] [--scene NAME ...]
      Renders the references that are missing or stale (scene/texture SHA-256 or renderer version changed), or all
      of them with --force: per scene one 4096-spp image and 16 flicker frames (camera moved by (1/8, 1/16) px per
      frame, 1024 spp each). Keeps their specular AOV as half-float ZIP EXRs in tests/validation/filtered_ggx/ and
      writes manifest.json there (command lines, SHA-256 of scene and inputs, renderer version, timings).
  tools/validate_filtered_ggx.py [--build DIR] check
      Verifies the manifest against the scene files and the renderer version, like the test does.
  tools/validate_filtered_ggx.py [--build DIR] report
      Runs the test binary in report mode (every mode, every scene, flicker for every mode), renders the pictures
      with the CLI, cross-checks the CLI numbers against the in-process ones, writes the tables into
      docs/validation/filtered-ggx.md and the pictures to docs/validation/img/filtered-ggx-*.png.
  tools/validate_filtered_ggx.py [--build DIR] all
      references (stale ones only) + report: everything the page shows. Every command line used is printed.

Needs only the Python standard library, a build with the `specula` and `test_validation_filtered_ggx` targets, and
the reference renders.
"""
import argparse
import hashlib
import json
import math
import os
import shlex
import shutil
import struct
import subprocess
import sys
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = ["sphere", "torus", "cylinders", "plane"]
SCENE_DIR = "examples/filtered-ggx"
CACHE_DIR = "tests/validation/filtered_ggx"
MANIFEST = CACHE_DIR + "/manifest.json"
DOC = "docs/validation/filtered-ggx.md"
IMG_DIR = "docs/validation/img"
REF_SPP = 4096
FLICKER_FRAMES = 16
FLICKER_SPP = 1024
SHIFT_PX = (0.125, 0.0625)  # camera motion per frame, in pixels at the look-at distance (screen x right, y down)
NORMAL_MAP = "bumps_normal.png"


def rel(path):
    return os.path.relpath(path, ROOT)


def run(cmd, capture=False, env=None):
    """Runs cmd (a list), printing it first as a shell command line relative to the repository root."""
    print("$ " + " ".join(shlex.quote(c) for c in cmd), flush=True)
    r = subprocess.run(cmd, cwd=ROOT, check=True, text=True, env=env,
                       stdout=subprocess.PIPE if capture else None)
    return r.stdout if capture else None


def sha256(path):
    return hashlib.sha256(open(os.path.join(ROOT, path), "rb").read()).hexdigest()


# ---- Minimal OpenEXR I/O (scanline; none/ZIPS/ZIP; half and float), standard library only -----------------------

def _unpredict(data):
    t = bytearray(data)
    acc = t[0] if t else 0
    for i in range(1, len(t)):
        acc = (acc + t[i] - 128) & 0xFF
        t[i] = acc
    half = (len(t) + 1) // 2
    out = bytearray(len(t))
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return bytes(out)


def _predict(raw):
    half = (len(raw) + 1) // 2
    t = bytearray(len(raw))
    t[:half] = raw[0::2]
    t[half:] = raw[1::2]
    prev = t[0] if t else 0
    for i in range(1, len(t)):
        cur = t[i]
        t[i] = (cur - prev + 384) & 0xFF
        prev = cur
    return bytes(t)


def read_exr(path):
    """(width, height, {channel: [floats, row-major, top row first]}) of a scanline EXR."""
    b = open(path, "rb").read()
    if b[:4] != b"\x76\x2f\x31\x01":
        raise ValueError(f"{path}: not an OpenEXR file")
    if struct.unpack_from("<I", b, 4)[0] & 0x1A00:
        raise ValueError(f"{path}: tiled, deep or multi-part EXR not supported")
    pos, hdr = 8, {}
    while b[pos] != 0:
        e = b.index(b"\0", pos); name = b[pos:e].decode(); pos = e + 1
        e = b.index(b"\0", pos); pos = e + 1
        size = struct.unpack_from("<i", b, pos)[0]; pos += 4
        hdr[name] = b[pos:pos + size]; pos += size
    pos += 1
    chans, cl, p = [], hdr["channels"], 0
    while cl[p] != 0:
        e = cl.index(b"\0", p); name = cl[p:e].decode(); p = e + 1
        chans.append((name, struct.unpack_from("<i", cl, p)[0])); p += 16
    comp = hdr["compression"][0]
    x0, y0, x1, y1 = struct.unpack("<4i", hdr["dataWindow"])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    lines = {0: 1, 2: 1, 3: 16}.get(comp)
    if lines is None:
        raise ValueError(f"{path}: compression {comp} not supported (none, zips, zip)")
    size_of, fmt_of = {1: 2, 2: 4}, {1: "e", 2: "f"}
    if any(t not in size_of for _, t in chans):
        raise ValueError(f"{path}: only half and float channels are supported")
    nchunks = (h + lines - 1) // lines
    out = {name: [0.0] * (w * h) for name, _ in chans}
    for off in struct.unpack_from(f"<{nchunks}Q", b, pos):
        y, n = struct.unpack_from("<ii", b, off)
        data = b[off + 8:off + 8 + n]
        nl = min(lines, y1 + 1 - y)
        if comp != 0 and n < nl * w * sum(size_of[t] for _, t in chans):
            data = _unpredict(zlib.decompress(data))
        q = 0
        for line in range(nl):
            row = (y - y0 + line) * w
            for name, t in chans:
                out[name][row:row + w] = struct.unpack_from(f"<{w}{fmt_of[t]}", data, q)
                q += w * size_of[t]
    return w, h, out


def write_exr_half(path, w, h, channels):
    """Writes {name: [floats]} as a half-float, ZIP-compressed scanline EXR (fails on values beyond half range)."""
    names = sorted(channels)

    def attr(name, typ, data):
        return name.encode() + b"\0" + typ.encode() + b"\0" + struct.pack("<i", len(data)) + data
    chl = b"".join(n.encode() + b"\0" + struct.pack("<iB3xii", 1, 0, 1, 1) for n in names) + b"\0"
    hdr = (attr("channels", "chlist", chl) + attr("compression", "compression", bytes([3])) +
           attr("dataWindow", "box2i", struct.pack("<4i", 0, 0, w - 1, h - 1)) +
           attr("displayWindow", "box2i", struct.pack("<4i", 0, 0, w - 1, h - 1)) +
           attr("lineOrder", "lineOrder", bytes([0])) + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0)) +
           attr("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0)) +
           attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    chunks = []
    for c in range((h + 15) // 16):
        raw = bytearray()
        for y in range(c * 16, min(h, c * 16 + 16)):
            for n in names:
                vals = channels[n][y * w:(y + 1) * w]
                if not all(abs(v) <= 65504.0 for v in vals):
                    raise ValueError(f"{path}: a value of {n} does not fit a half float")
                raw += struct.pack(f"<{w}e", *vals)
        comp = zlib.compress(_predict(bytes(raw)), 9)
        if len(comp) >= len(raw):
            comp = bytes(raw)
        chunks.append(struct.pack("<ii", c * 16, len(comp)) + comp)
    head = b"\x76\x2f\x31\x01" + struct.pack("<I", 2) + hdr
    off, table = len(head) + 8 * len(chunks), b""
    for ch in chunks:
        table += struct.pack("<Q", off)
        off += len(ch)
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(head + table + b"".join(chunks))
    os.replace(tmp, path)


# ---- Scenes ---------------------------------------------------------------------------------------------------------

def write_png_rgb8(path, w, h, rows):
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + r for r in rows)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def make_normal_map(path, n=128):
    """The plane's tangent-space normal map (OpenGL convention, 8-bit, periodic): the gradient of the height field
    h = 0.5 sin(8 pi x) sin(8 pi y) + 0.35 sin(2 pi (3x + 5y)) + 0.25 sin(2 pi (11x - 7y)), scaled by 0.012 (slopes up
    to about 0.49). Regenerated only if missing: it is an input of the plane's reference (hashed in the manifest)."""
    tau = 2 * math.pi
    rows = []
    for j in range(n):
        y = (j + 0.5) / n
        row = bytearray()
        for i in range(n):
            x = (i + 0.5) / n
            a, b = tau * (3 * x + 5 * y), tau * (11 * x - 7 * y)
            hx = 2 * tau * math.cos(4 * tau * x) * math.sin(4 * tau * y) + 1.05 * tau * math.cos(a) + 2.75 * tau * math.cos(b)
            hy = 2 * tau * math.sin(4 * tau * x) * math.cos(4 * tau * y) + 1.75 * tau * math.cos(a) - 1.75 * tau * math.cos(b)
            v = (-0.012 * hx, -0.012 * hy, 1.0)
            ln = math.sqrt(sum(c * c for c in v))
            row += bytes(max(0, min(255, round((c / ln * 0.5 + 0.5) * 255))) for c in v)
        rows.append(bytes(row))
    write_png_rgb8(path, n, n, rows)


def load_scene(name):
    with open(os.path.join(ROOT, SCENE_DIR, name + ".json")) as f:
        return json.load(f)


def scene_inputs(scene):
    """Files a scene reads (texture.image files), relative to the repository root."""
    out = []
    for m in scene.get("materials", {}).values():
        for node in m["nodes"].values():
            if node["type"] == "texture.image":
                out.append(os.path.normpath(os.path.join(SCENE_DIR, node["inputs"]["file"])))
    return sorted(set(out))


def rebase_files(scene, src_dir, dst_dir):
    """Rewrites relative texture.image paths of a scene copied from src_dir to dst_dir."""
    for m in scene.get("materials", {}).values():
        for node in m["nodes"].values():
            if node["type"] == "texture.image" and not os.path.isabs(node["inputs"]["file"]):
                node["inputs"]["file"] = os.path.relpath(os.path.join(src_dir, node["inputs"]["file"]), dst_dir)


def camera_basis(cam, width, height):
    """(right, image_up, pixel size at the look-at distance) of the scene's camera (docs/scene-format.md#camera)."""
    p, la = cam["position"], cam["look_at"]
    up = cam.get("up", [0, 0, 1])
    f = [la[i] - p[i] for i in range(3)]
    dist = math.sqrt(sum(c * c for c in f))
    f = [c / dist for c in f]
    r = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]]
    rl = math.sqrt(sum(c * c for c in r))
    r = [c / rl for c in r]
    u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
    t = math.tan(math.radians(cam.get("fov", 39.6)) / 2)
    if cam.get("fov_axis", "x") == "x":
        px = 2 * dist * t / width
    else:
        px = 2 * dist * t / height
    return r, u, px


def frame_cameras(scene):
    """Camera position and look_at of the 16 flicker frames: frame t moves both by t (1/8, 1/16) px along
    (right, -image_up), the pixel measured at the look-at distance (nearer surfaces move more, farther ones less)."""
    cam, rs = scene["camera"], scene["render"]
    r, u, px = camera_basis(cam, rs["width"], rs["height"])
    d = [px * (SHIFT_PX[0] * r[i] - SHIFT_PX[1] * u[i]) for i in range(3)]
    frames = []
    for t in range(FLICKER_FRAMES):
        frames.append({"camera_position": [cam["position"][i] + t * d[i] for i in range(3)],
                       "camera_look_at": [cam["look_at"][i] + t * d[i] for i in range(3)]})
    return d, frames


# ---- references ---------------------------------------------------------------------------------------------------

def specula_version(specula):
    return subprocess.run([specula, "--version"], check=True, capture_output=True, text=True).stdout.strip()


def render(specula, scene_path, out_exr, spp):
    """Renders with the CLI (progress as JSON), returns (command line, seconds)."""
    cmd = [rel(specula), "render", rel(scene_path), "-o", rel(out_exr), "--spp", str(spp), "--progress", "json"]
    t0 = time.time()
    out = run(cmd, capture=True)
    seconds = time.time() - t0
    for line in out.splitlines():
        try:
            ev = json.loads(line)
        except ValueError:
            continue
        if ev.get("event") == "done":
            seconds = ev["seconds"]
    return " ".join(shlex.quote(c) for c in cmd[:-2]), seconds


def cache_specular(src_exr, dst_exr):
    w, h, ch = read_exr(src_exr)
    write_exr_half(dst_exr, w, h, {k: v for k, v in ch.items() if k.startswith("specular.")})


def load_manifest():
    p = os.path.join(ROOT, MANIFEST)
    if not os.path.exists(p):
        return None
    with open(p) as f:
        return json.load(f)


def staleness(manifest, name, version):
    """Why the cached references of scene 'name' are unusable, or None."""
    if manifest is None:
        return f"{MANIFEST} is missing"
    e = manifest.get("scenes", {}).get(name)
    if e is None:
        return f"{name} is not in {MANIFEST}"
    if manifest.get("renderer_version") != version:
        return f"renderer version {version!r} != manifest {manifest.get('renderer_version')!r}"
    if sha256(e["scene"]) != e["scene_sha256"]:
        return f"{e['scene']} changed (SHA-256 differs from the manifest)"
    for path, digest in e["inputs_sha256"].items():
        if not os.path.exists(os.path.join(ROOT, path)) or sha256(path) != digest:
            return f"{path} changed or is missing"
    files = [e["reference"]["file"]] + [f["file"] for f in e["flicker"]["frames"]]
    for f in files:
        if not os.path.exists(os.path.join(ROOT, CACHE_DIR, f)):
            return f"{CACHE_DIR}/{f} is missing"
    return None


def cmd_references(args):
    specula = args.specula
    version = specula_version(specula)
    work = os.path.join(args.work, "references")
    os.makedirs(work, exist_ok=True)
    os.makedirs(os.path.join(ROOT, CACHE_DIR), exist_ok=True)
    nm = os.path.join(ROOT, SCENE_DIR, NORMAL_MAP)
    if not os.path.exists(nm):
        make_normal_map(nm)
        print(f"wrote {rel(nm)}")
    manifest = load_manifest() or {}
    manifest.update({
        "generator": "tools/validate_filtered_ggx.py",
        "regenerate": "tools/validate_filtered_ggx.py --build BUILD references --force",
        "renderer_version": version,
        "aov": "specular",
        "storage": "specular AOV only (specular.R/G/B), half-float, ZIP; written by tools/validate_filtered_ggx.py "
                   "from the full EXR the command line renders (half rounding: relative error <= 4.9e-4)",
        "reference_filter": "gaussian, sigma^2 = 1/(2 pi) (render.filter of the scene files)",
        "flicker_shift_px_per_frame": list(SHIFT_PX),
    })
    manifest.setdefault("scenes", {})
    for name in (args.scene or SCENES):
        why = "--force" if args.force else staleness(manifest, name, version)
        if why is None:
            print(f"{name}: references are up to date")
            continue
        print(f"{name}: rendering references ({why})")
        scene = load_scene(name)
        scene_path = os.path.join(ROOT, SCENE_DIR, name + ".json")
        full = os.path.join(work, f"{name}_ref.exr")
        command, seconds = render(specula, scene_path, full, REF_SPP)
        cache_specular(full, os.path.join(ROOT, CACHE_DIR, f"{name}_ref.exr"))
        os.makedirs(os.path.join(ROOT, IMG_DIR), exist_ok=True)
        shutil.copyfile(full[:-4] + ".png", os.path.join(ROOT, IMG_DIR, f"filtered-ggx-{name}-reference.png"))
        entry = {
            "scene": f"{SCENE_DIR}/{name}.json",
            "scene_sha256": sha256(f"{SCENE_DIR}/{name}.json"),
            "inputs_sha256": {p: sha256(p) for p in scene_inputs(scene)},
            "reference": {"file": f"{name}_ref.exr", "spp": REF_SPP, "command": command, "seconds": round(seconds, 2)},
        }
        shift, frames = frame_cameras(scene)
        fl = {"frames_count": FLICKER_FRAMES, "spp": FLICKER_SPP, "camera_shift_world_per_frame": shift,
              "scene_change": "the scene file with camera.position and camera.look_at replaced by the frame's values "
                              "(and texture paths re-rooted to the frame scene's folder)", "frames": []}
        for t, fr in enumerate(frames):
            s = json.loads(json.dumps(scene))
            s["camera"]["position"] = fr["camera_position"]
            s["camera"]["look_at"] = fr["camera_look_at"]
            fdir = os.path.join(work, "frames")
            os.makedirs(fdir, exist_ok=True)
            rebase_files(s, os.path.join(ROOT, SCENE_DIR), fdir)
            fpath = os.path.join(fdir, f"{name}_f{t:02d}.json")
            with open(fpath, "w") as f:
                json.dump(s, f, indent=1)
            ffull = os.path.join(work, f"{name}_f{t:02d}.exr")
            command, seconds = render(specula, fpath, ffull, FLICKER_SPP)
            cache_specular(ffull, os.path.join(ROOT, CACHE_DIR, f"{name}_f{t:02d}.exr"))
            fl["frames"].append(dict(fr, file=f"{name}_f{t:02d}.exr", command=command, seconds=round(seconds, 2)))
        entry["flicker"] = fl
        manifest["scenes"][name] = entry
        manifest["scenes"] = {k: manifest["scenes"][k] for k in SCENES if k in manifest["scenes"]}
        with open(os.path.join(ROOT, MANIFEST), "w") as f:  # after every scene, so an interrupted run keeps its work
            json.dump(manifest, f, indent=1)
            f.write("\n")
    total = sum(os.path.getsize(os.path.join(ROOT, CACHE_DIR, f)) for f in os.listdir(os.path.join(ROOT, CACHE_DIR)))
    print(f"{CACHE_DIR}: {total / 1e6:.2f} MB")


# ---- report ---------------------------------------------------------------------------------------------------------

MODES = ([("none", "-")] + [(f, k) for f in ("slope", "projected", "projected_approx") for k in ("full", "axis_aligned")] +
         [(f, "-") for f in ("iso_max", "iso_sum", "iso_mean", "iso_rect")])
DERIVS = ("ray", "quad")
# Pictures on the page: the 1-spp renders of these modes (with 2x2-quad derivatives, as a GPU shades) and their errors.
PICTURE_MODES = [("none", "-", "quad"), ("slope", "full", "quad"), ("projected", "full", "quad"),
                 ("projected_approx", "axis_aligned", "quad"), ("iso_mean", "-", "quad")]
METHOD = {"none": "unfiltered", "slope": "slope (K16)", "projected": "projected (exact)",
          "projected_approx": "projected approx.", "iso_max": "iso_max", "iso_sum": "iso_sum", "iso_mean": "iso_mean",
          "iso_rect": "iso_rect (K16)"}


def picture_tag(scene, filt, kernel, deriv):
    parts = [scene, filt] + ([] if kernel == "-" else [kernel]) + [deriv]
    return "-".join(p.replace("_", "-") for p in parts)


def derive_scene(base, filt, kernel, deriv):
    """The 1-spp test scene (the twin of deriveScene in tests/unit/test_validation_filtered_ggx.cpp)."""
    s = json.loads(json.dumps(base))
    s["render"].update({"spp": 1, "pixel_center": True, "derivatives": deriv})
    for m in s["materials"].values():
        for node in m["nodes"].values():
            if node["type"] == "bsdf.ggx_filtered":
                node["inputs"].update({"filter": filt, "kernel": "full" if kernel == "full" else "axis_aligned",
                                       "derivatives": "quad" if deriv == "quad" else "analytic"})
    return s


def fmt(x, digits=4):
    if x is None:
        return "–"
    if x == 0 or 1e-3 <= abs(x) < 1e4:
        return f"{x:.{digits}g}"
    return f"{x:.3e}"


def ratio(x):
    return "–" if x is None else f"{x:.3f}"


def replace_block(text, name, body):
    begin, end = f"<!-- BEGIN generated: {name} -->", f"<!-- END generated: {name} -->"
    if begin not in text or end not in text:
        raise SystemExit(f"{DOC}: markers for '{name}' are missing")
    a, b = text.index(begin) + len(begin), text.index(end)
    return text[:a] + "\n" + body.rstrip() + "\n" + text[b:]


def cmd_report(args):
    version = specula_version(args.specula)
    manifest = load_manifest()
    stale = [(n, staleness(manifest, n, version)) for n in SCENES]
    stale = [(n, w) for n, w in stale if w]
    if stale:
        raise SystemExit("stale references: " + "; ".join(f"{n}: {w}" for n, w in stale) +
                         f"\nregenerate with: tools/validate_filtered_ggx.py --build {rel(args.build)} references")
    report_dir = os.path.join(args.work, "report")
    shutil.rmtree(report_dir, ignore_errors=True)
    os.makedirs(report_dir)
    commands = []
    env = dict(os.environ, SPECULA_FGGX_REPORT_DIR=report_dir)
    cmd = [rel(args.test_bin), "--gtest_filter=FilteredGgxValidation.*"]
    commands.append("SPECULA_FGGX_REPORT_DIR=" + rel(report_dir) + " " + " ".join(cmd))
    print("$ " + commands[-1], flush=True)
    t0 = time.time()
    test_rc = subprocess.run(cmd, cwd=ROOT, env=env).returncode
    print(f"test binary (report mode, flicker for every mode): {time.time() - t0:.0f} s, exit code {test_rc}")
    data = {}
    for n in SCENES:
        with open(os.path.join(report_dir, n + ".json")) as f:
            data[n] = json.load(f)

    # Pictures: CLI renders of the picture modes, cross-checked against the in-process numbers.
    img_dir = os.path.join(ROOT, IMG_DIR)
    os.makedirs(img_dir, exist_ok=True)
    pics = os.path.join(args.work, "pictures")
    os.makedirs(pics, exist_ok=True)
    worst = 0.0
    for n in SCENES:
        refpng = os.path.join(args.work, "references", f"{n}_ref.png")
        if os.path.exists(refpng):  # also copied when the reference is rendered
            shutil.copyfile(refpng, os.path.join(img_dir, f"filtered-ggx-{n}-reference.png"))
        base = load_scene(n)
        ref = os.path.join(ROOT, CACHE_DIR, manifest["scenes"][n]["reference"]["file"])
        for filt, kernel, deriv in PICTURE_MODES:
            tag = picture_tag(n, filt, kernel, deriv)
            s = derive_scene(base, filt, kernel, deriv)
            rebase_files(s, os.path.join(ROOT, SCENE_DIR), pics)
            sp = os.path.join(pics, tag + ".json")
            with open(sp, "w") as f:
                json.dump(s, f, indent=1)
            exr = os.path.join(pics, tag + ".exr")
            c = [rel(args.specula), "render", rel(sp), "-o", rel(exr), "--progress", "none"]
            commands.append(" ".join(c))
            run(c)
            shutil.copyfile(exr[:-4] + ".png", os.path.join(img_dir, f"filtered-ggx-{tag}.png"))
            c = [rel(args.specula), "compare", rel(exr), rel(ref), "--aov", "specular", "--json",
                 "--diff", rel(os.path.join(img_dir, f"filtered-ggx-{tag}-diff.png"))]
            commands.append(" ".join(c))
            r = json.loads(run(c, capture=True))
            m = data[n]["modes"][f"{filt}/{kernel}/{deriv}"]
            for key in ("rmse", "mae"):
                d = abs(r[key] - m[key]) / max(m[key], 1e-12)
                worst = max(worst, d)
                if d > 1e-3:
                    raise SystemExit(f"{tag}: CLI {key} {r[key]} != in-process {m[key]}: the two paths disagree")
    print(f"CLI renders reproduce the in-process RMSE/MAE (largest relative difference {worst:.1e})")

    # Tables.
    lines = []
    for n in SCENES:
        d = data[n]
        lines.append(f"**{n}** ({d['width']}×{d['height']}; mean reference specular {fmt(d['reference_mean'])}; "
                     f"grazing mask {d['grazing_pixels']} px; flicker mask {d.get('object_pixels', '–')} px)\n")
        lines.append("| method | kernel | derivatives | RMSE | MAE | rel. RMSE | RMSE ratio | MAE ratio | grazing MAE "
                     "ratio | flicker ratio | grazing flicker ratio | ms / frame |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for deriv in DERIVS:
            for filt, kernel in MODES:
                m = d["modes"][f"{filt}/{kernel}/{deriv}"]
                lines.append(f"| {METHOD[filt]} | {kernel.replace('_', '-')} | {deriv} | {fmt(m['rmse'])} | "
                             f"{fmt(m['mae'])} | {m['rel_rmse']:.2f} | {ratio(m['rmse_ratio'])} | {ratio(m['mae_ratio'])} | "
                             f"{ratio(m.get('grazing_mae_ratio'))} | {ratio(m.get('flicker_ratio'))} | "
                             f"{ratio(m.get('grazing_flicker_ratio'))} | {m['ms_per_frame']:.1f} |")
        lines.append("")
    table = "\n".join(lines)

    # Projected vs slope in the grazing region, every scene.
    g = ["| scene | kernel | derivatives | slope grazing MAE | projected / slope | projected approx. / slope |",
         "|---|---|---|---|---|---|"]
    for n in SCENES:
        for deriv in DERIVS:
            for kernel in ("full", "axis_aligned"):
                ms = data[n]["modes"]
                s_ = ms[f"slope/{kernel}/{deriv}"]["grazing_mae"]
                p_ = ms[f"projected/{kernel}/{deriv}"]["grazing_mae"]
                a_ = ms[f"projected_approx/{kernel}/{deriv}"]["grazing_mae"]
                g.append(f"| {n} | {kernel.replace('_', '-')} | {deriv} | {fmt(s_)} | "
                         f"{(p_ / s_ if s_ else float('nan')):.3f} | {(a_ / s_ if s_ else float('nan')):.3f} |")
    grazing = "\n".join(g)

    # TK21's other statements, measured: one column per scene and derivative mode.
    cols = [(n, d) for n in SCENES for d in DERIVS]
    def mv(n, d, key, field):
        return data[n]["modes"][f"{key}/{d}"].get(field)
    def row(label, f):
        return "| " + label + " | " + " | ".join(f(n, d) for n, d in cols) + " |"
    def iso_best(field):
        def f(n, d):
            v = {k: mv(n, d, f"{k}/-", field) for k in ("iso_max", "iso_sum", "iso_mean", "iso_rect")}
            return "all equal" if max(v.values()) == min(v.values()) else min(v, key=v.get)
        return f
    t = ["| statement (TK21) | " + " | ".join(f"{n} {d}" for n, d in cols) + " |", "|---" * (len(cols) + 1) + "|"]
    for kern in ("full", "axis_aligned"):
        for field, name in (("rmse", "RMSE"), ("mae", "MAE")):
            t.append(row(f"{kern.replace('_', '-')} kernel: {name} projected / slope (Figs. 13, 14)",
                         lambda n, d, k=kern, fl=field: ratio(mv(n, d, f"projected/{k}", fl) / mv(n, d, f"slope/{k}", fl))))
    t.append(row("projected approx. vs exact: largest difference of RMSE ratios (Fig. 7)",
                 lambda n, d: f"{max(abs(mv(n, d, f'projected_approx/{k}', 'rmse_ratio') - mv(n, d, f'projected/{k}', 'rmse_ratio')) for k in ('full', 'axis_aligned')):.3f}"))
    for field, name in (("rmse", "RMSE"), ("mae", "MAE")):
        t.append(row(f"projected: {name} full / axis-aligned kernel (§6: full is lower)",
                     lambda n, d, fl=field: ratio(mv(n, d, "projected/full", fl) / mv(n, d, "projected/axis_aligned", fl))))
    t.append(row("projected: flicker full / axis-aligned kernel (§6: full flickers more)",
                 lambda n, d: ratio(mv(n, d, "projected/full", "flicker") / mv(n, d, "projected/axis_aligned", "flicker"))))
    t.append(row("isotropic filter with the lowest RMSE (Fig. 15: iso_mean)", iso_best("rmse")))
    t.append(row("isotropic filter with the lowest MAE (Fig. 15: iso_mean)", iso_best("mae")))
    t.append(row("RMSE iso_sum / iso_rect (Fig. 15: iso_sum slightly lower)",
                 lambda n, d: ratio(mv(n, d, "iso_sum/-", "rmse") / mv(n, d, "iso_rect/-", "rmse"))))
    t.append(row("RMSE iso_max / iso_sum (§5: iso_max the lowest conservative)",
                 lambda n, d: ratio(mv(n, d, "iso_max/-", "rmse") / mv(n, d, "iso_sum/-", "rmse"))))
    paper = "\n".join(t)

    # Pictures.
    p = []
    for n in SCENES:
        head = ["reference (4096 spp)"] + [f"{METHOD[f]}{'' if k == '-' else ', ' + k.replace('_', '-')}"
                                            for f, k, _ in PICTURE_MODES]
        p.append(f"**{n}** (1 spp at the pixel centre, 2×2-quad derivatives; error maps: |test − reference| of the "
                 "specular AOV, viridis, scaled to each map's 99th percentile, colour bar below each map)\n")
        p.append("| " + " | ".join(head) + " |")
        p.append("|" + "---|" * len(head))
        row = [f"![](img/filtered-ggx-{n}-reference.png)"]
        row2 = ["error maps →"]
        for filt, kernel, deriv in PICTURE_MODES:
            tag = picture_tag(n, filt, kernel, deriv)
            row.append(f"![](img/filtered-ggx-{tag}.png)")
            row2.append(f"![](img/filtered-ggx-{tag}-diff.png)")
        p.append("| " + " | ".join(row) + " |")
        p.append("| " + " | ".join(row2) + " |")
        p.append("")
    pictures = "\n".join(p)

    refcmds = []
    for n in SCENES:
        e = manifest["scenes"][n]
        refcmds.append(f"{e['reference']['command']}    # {e['reference']['seconds']} s")
        fr = e["flicker"]["frames"]
        refcmds.append(f"{fr[0]['command']}    # ... 16 frames, {fr[0]['seconds']} s each")
    cmds = "```\n" + "\n".join(refcmds + commands) + "\n```"

    doc_path = os.path.join(ROOT, DOC)
    with open(doc_path) as f:
        text = f.read()
    text = replace_block(text, "table", table)
    text = replace_block(text, "grazing", grazing)
    text = replace_block(text, "paper", paper)
    text = replace_block(text, "pictures", pictures)
    text = replace_block(text, "commands", cmds)
    with open(doc_path, "w") as f:
        f.write(text)
    print(f"wrote {DOC} and {IMG_DIR}/filtered-ggx-*.png")
    big = [f for f in os.listdir(img_dir) if f.startswith("filtered-ggx-") and os.path.getsize(os.path.join(img_dir, f)) > 300e3]
    if big:
        print("warning: pictures over 300 KB: " + ", ".join(big))
    if test_rc != 0:
        print("warning: the test binary failed (see above): the page shows the measured numbers anyway")
    return 0


def cmd_check(args):
    version = specula_version(args.specula)
    manifest = load_manifest()
    bad = 0
    for name in SCENES:
        why = staleness(manifest, name, version)
        print(f"{name}: {'ok' if why is None else 'STALE: ' + why}")
        bad += why is not None
    if bad:
        print(f"regenerate with: tools/validate_filtered_ggx.py --build {rel(args.build)} references")
    return 1 if bad else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="CMake build folder (default: build)")
    ap.add_argument("--work", default=os.path.join(ROOT, "out", "validation", "filtered-ggx"),
                    help="scratch folder for full renders (default: out/validation/filtered-ggx)")
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("references", help="render missing/stale references (all with --force)")
    r.add_argument("--force", action="store_true")
    r.add_argument("--scene", action="append", choices=SCENES)
    sub.add_parser("check", help="verify the manifest like the test does")
    sub.add_parser("report", help="measure every mode, write the page's tables and pictures")
    sub.add_parser("all", help="references (stale only) + report")
    args = ap.parse_args()
    args.build = os.path.abspath(args.build)
    args.work = os.path.abspath(args.work)
    args.specula = os.path.join(args.build, "bin", "specula")
    args.test_bin = os.path.join(args.build, "tests", "test_validation_filtered_ggx")
    if args.command == "references":
        cmd_references(args)
    elif args.command == "check":
        return cmd_check(args)
    elif args.command == "report":
        cmd_report(args)
    else:
        args.force, args.scene = False, None
        cmd_references(args)
        cmd_report(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
