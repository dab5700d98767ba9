#!/usr/bin/env python3
"""ctest `validation_toolkit` (label cpu): the shared steps of every validation page (tools/specula_validation/,
docs/validation/README.md) on tiny synthetic scenes, with numbers known in closed form.

  1. Metrics (`specula compare --json --mask/--mask-top-rows/--frames`): a quad of emission 1 against the same quad
     at 0.5 gives RMSE = MAE = 0.5 and rel. RMSE = 1 inside the quad's mask, RMSE = 0.5 sqrt(f) over the frame
     (f = covered fraction); a sequence alternating 1, 2 against 0.5 has flicker 0.5.
  2. Staleness (manifest.py): a fresh manifest checks clean; a different binary with bit-identical output (a stripped
     copy of specula) and another version string check clean too (no regeneration for a refactor); a renderer whose
     output differs, a changed input, a changed derived scene, a changed cached file or a missing one are each
     reported, and the message carries the regenerate command.

Usage: test_validation_toolkit.py SPECULA_BINARY SOURCE_DIR
"""
import copy
import json
import math
import os
import shutil
import stat
import subprocess
import sys
import tempfile

SPECULA, SRC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SRC, "tools"))
from specula_validation import exr, metrics  # noqa: E402
from specula_validation.manifest import Cache  # noqa: E402
from specula_validation.render import Renderer  # noqa: E402

W, H = 32, 24


def scene(strength):
    return {"version": 1,
            "render": {"width": W, "height": H, "spp": 1, "pixel_center": True, "seed": 0, "integrator": "direct",
                       "filter": "box"},
            "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
            "materials": {"m": {"nodes": {"e": {"type": "bsdf.emission",
                                                "inputs": {"color": [1, 1, 1], "strength": strength}}},
                                "output": "@e.bsdf"}},
            "shapes": [{"type": "quad", "size": [1.6, 1.2], "material": "m"}],
            "lights": []}


failed = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failed.append(what)


def close(a, b, tol=1e-6):
    return abs(a - b) <= tol * max(1.0, abs(b))


def test_metrics(work):
    rnd = Renderer(SPECULA, work)
    a, _ = rnd.render(scene(1.0), "a")
    b, _ = rnd.render(scene(0.5), "b")
    m = metrics.compare(SPECULA, a, b, aov="beauty", masks=[a + ":beauty"])
    n = m["mask_pixels"]
    check(0 < n < W * H, f"mask from A's beauty: {n} of {W * H} pixels")
    check(close(m["rmse"], 0.5) and close(m["mae"], 0.5) and close(m["rel_rmse"], 1.0) and close(m["mean_b"], 0.5),
          f"masked: RMSE {m['rmse']}, MAE {m['mae']}, rel. RMSE {m['rel_rmse']}, mean B {m['mean_b']} "
          f"(expected 0.5, 0.5, 1, 0.5)")
    f = metrics.compare(SPECULA, a, b, aov="beauty")
    check(close(f["rmse"], 0.5 * math.sqrt(n / (W * H))) and f["mask_pixels"] == W * H,
          f"whole frame (--mask all): RMSE {f['rmse']:.6f} = 0.5 sqrt({n}/{W * H}) = {0.5 * math.sqrt(n / (W * H)):.6f}")
    plain = json.loads(subprocess.run([SPECULA, "compare", a, b, "--json"], capture_output=True, text=True,
                                      check=True).stdout)
    check(close(plain["rmse"], f["rmse"], 1e-5) and close(plain["mae"], f["mae"], 1e-5),
          f"OpenImageIO's compare agrees: RMSE {plain['rmse']}, MAE {plain['mae']}")
    t = metrics.compare(SPECULA, a, b, aov="beauty", masks=[a + ":beauty"], top_rows="1/3")
    # the quad covers 14 x 10 pixel centres (1.6 x 1.2 units, 0.1137 units per pixel): the top third is 3 rows of 14
    check(n == 140 and t["mask_pixels"] == 42 and close(t["rmse"], 0.5),
          f"--mask-top-rows 1/3: {t['mask_pixels']} of {n} px (expected 42 of 140), RMSE {t['rmse']}")
    for k, s in enumerate([1.0, 2.0, 1.0, 2.0]):
        rnd.render(scene(s), f"t{k}")
        rnd.render(scene(0.5), f"r{k}")
    fl = metrics.flicker(SPECULA, os.path.join(work, "t%d.exr"), os.path.join(work, "r%d.exr"), 4, aov="beauty",
                         masks=[os.path.join(work, "r%d.exr") + ":beauty"])
    check(close(fl["flicker"], 0.5) and close(fl["shimmer"], 0.5) and close(fl["shimmer_ref"], 0.0)
          and fl["mask_pixels"] == n, f"flicker of 1,2,1,2 against 0.5: {fl['flicker']} (expected 0.5), shimmer "
                                      f"{fl['shimmer']}, reference shimmer {fl['shimmer_ref']}")


def make_cache(work, specula):
    """A one-scene page cache: a reference (16 spp) and two camera-shifted frames."""
    sdir = os.path.join(work, "examples")
    os.makedirs(sdir, exist_ok=True)
    sp = os.path.join(sdir, "quad.json")
    with open(sp, "w") as f:
        json.dump(scene(1.0), f)
    cdir = os.path.join(work, "cache")
    os.makedirs(cdir, exist_ok=True)
    c = Cache(cdir, page="docs/validation/test.md", generator="test_validation_toolkit.py",
              regenerate="python3 tools/validate_test.py --refs")
    c.add_scene("quad", sp)
    variant = dict(scene(1.0), render=dict(scene(1.0)["render"], pixel_center=False, spp=16))
    c.add_variant("quad", "reference", variant)
    c.add_file("quad", "quad_ref.exr", "reference", 16)
    for t in (1, 2):
        c.add_file("quad", f"quad_f{t}.exr", "reference", 16, (0.25 * t, 0.0))
    rnd = Renderer(specula, os.path.join(work, "renders"), scene_dir=sdir)
    for f in c.scenes["quad"]["files"]:
        p, _ = rnd.render(variant, f["file"][:-4], spp=f["spp"], shift_px=f["camera_shift_px"])
        exr.write_cached(p, os.path.join(cdir, f["file"]), ["R", "G", "B"])
    c.write(specula, os.path.join(work, "probe"), {}, "specula test")
    return c, variant


def test_staleness(work):
    c, variant = make_cache(work, SPECULA)
    probe = os.path.join(work, "probe")
    check(c.check(SPECULA, probe) == [], "a fresh manifest checks clean")
    # a different binary, same behaviour: a stripped copy (different bytes; nothing hashes the C++ sources)
    stripped = os.path.join(work, "specula-stripped")
    shutil.copy(SPECULA, stripped)
    if shutil.which("strip"):
        subprocess.run(["strip", stripped], check=True)
    differs = open(stripped, "rb").read() != open(SPECULA, "rb").read()
    p = c.check(stripped, probe)
    check(p == [], f"a binary with other bytes ({'stripped' if differs else 'copied'}) but the same output is not "
                   f"stale: {p}")
    with open(c.path) as f:
        man = json.load(f)
    man["renderer_version"] = "specula 9.9.9"
    with open(c.path, "w") as f:
        json.dump(man, f)
    check(c.check(SPECULA, probe) == [], "another renderer_version string alone is not stale")
    # a renderer whose output differs: a wrapper that renders everything with another seed
    wrapper = os.path.join(work, "specula-changed")
    with open(wrapper, "w") as f:
        f.write(f"#!/bin/sh\nif [ \"$1\" = render ]; then exec {SPECULA} \"$@\" --seed 7; fi\nexec {SPECULA} \"$@\"\n")
    os.chmod(wrapper, os.stat(wrapper).st_mode | stat.S_IXUSR)
    p = c.check(wrapper, probe)
    check(len(p) == 1 and "output changed" in p[0], f"a renderer with different output is stale: {p}")
    msg = c.stale_message(p, "test")
    check("STALE" in msg and "python3 tools/validate_test.py --refs" in msg, "the message names the regenerate command")
    # a changed derived scene
    c2 = copy.deepcopy(c)
    c2.scenes["quad"]["variants"]["reference"]["render"]["spp"] = 32
    p = c2.check(SPECULA, probe)
    check(any("derived reference scene changed" in x for x in p), f"a changed derived scene is stale: {p}")
    # other spp / shift of a cached file
    c3 = copy.deepcopy(c)
    c3.scenes["quad"]["files"][2]["camera_shift_px"] = [0.5, 0.125]
    p = c3.check(SPECULA, probe)
    check(any("camera shifts" in x for x in p), f"a changed camera shift is stale: {p}")
    # a changed input file
    sp = os.path.join(work, "examples", "quad.json")
    keep = open(sp).read()
    with open(sp, "w") as f:
        f.write(keep + "\n")
    p = c.check(SPECULA, probe)
    check(any("input" in x and "quad.json" in x for x in p), f"a changed scene file is stale: {p}")
    with open(sp, "w") as f:
        f.write(keep)
    # a changed or missing cached file
    ref = os.path.join(c.dir, "quad_f1.exr")
    data = open(ref, "rb").read()
    with open(ref, "wb") as f:
        f.write(data[:-1] + bytes([data[-1] ^ 1]))
    p = c.check(SPECULA, probe)
    check(any("quad_f1.exr" in x and "content differs" in x for x in p), f"a modified cached file is stale: {p}")
    os.remove(ref)
    p = c.check(SPECULA, probe)
    check(any("quad_f1.exr" in x and "missing" in x for x in p), f"a missing cached file is stale: {p}")
    os.remove(c.path)
    p = c.check(SPECULA, probe)
    check(any("does not exist" in x for x in p), f"a missing manifest is stale: {p}")


def main():
    exr.require_oiiotool()
    with tempfile.TemporaryDirectory(prefix="validation_toolkit_") as work:
        test_metrics(os.path.join(work, "metrics"))
        test_staleness(os.path.join(work, "staleness"))
    print(f"\n{len(failed)} failed" if failed else "\nall passed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
