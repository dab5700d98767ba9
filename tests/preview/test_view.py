#!/usr/bin/env python3
"""`specula view` under Xvfb + Mesa (issue 14 item 2, docs/preview.md): the window's screenshot against `specula
preview`, and the reload that follows the scene file.

Asserted:
  1. Screenshots after two frames, for a Standard-view scene (cornell) and a Filmic-view scene (metals, whose view
     has a 1D LUT): the .exr (AOVs) equals the preview's EXR to 1e-6 on every channel, and the .png, which is the
     window's pixels through OCIO's GPU shader path, is within 1 level of 255 of the preview's PNG (OCIO on the CPU)
     on every pixel and channel.
  2. Reload: view a copy of cornell with --events; once shown, rewrite it with a new camera field of view: a second
     "loaded" and "shown" follow. Then write invalid JSON: a "reload_failed" event whose message names the file, and
     the window keeps the last good scene. SIGTERM then closes it with exit 0 and writes the screenshot, which equals
     `specula preview` of the edited (last good) scene.
  3. Bad input: a screenshot path that is neither .png nor .exr exits 2, a missing scene exits 3, both before any
     window opens, and no file is written.

  test_view.py SPECULA_BIN SOURCE_DIR OUT_DIR   (run under xvfb-run; see tests/CMakeLists.txt)"""
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import OpenImageIO as oiio

SPECULA, SRC, OUT = sys.argv[1], sys.argv[2], sys.argv[3]
RES = "192x108"
failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if r.returncode:
        raise SystemExit("FAILED (exit %d): %s\n%s" % (r.returncode, " ".join(cmd), r.stderr.strip()[-2000:]))
    return r


def pixels(path, fmt=oiio.FLOAT):
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise SystemExit("cannot read %s: %s" % (path, buf.geterror()))
    return buf.get_pixels(fmt).astype(np.float64)


def exr_channels(path):
    buf = oiio.ImageBuf(path)
    return list(buf.spec().channelnames), buf.get_pixels(oiio.FLOAT).astype(np.float64)


def compare_with_preview(scene, tag):
    pre = os.path.join(OUT, tag + ".preview.exr")
    run([SPECULA, "preview", scene, "--resolution", RES, "-o", pre])
    shot_exr = os.path.join(OUT, tag + ".view.exr")
    shot_png = os.path.join(OUT, tag + ".view.png")
    for shot in (shot_exr, shot_png):
        run([SPECULA, "view", scene, "--resolution", RES, "--exit-after", "2", "--screenshot", shot])
    names_a, a = exr_channels(pre)
    names_b, b = exr_channels(shot_exr)
    check(names_a == names_b and a.shape == b.shape, "%s: the view's EXR has the preview's channels %s" % (tag, names_a))
    if a.shape == b.shape:
        d = np.nanmax(np.abs(a - b))
        check(d <= 1e-6, "%s: EXR screenshot equals the preview's EXR (max |diff| %.3g <= 1e-6)" % (tag, d))
    pa = pixels(pre[:-4] + ".png", oiio.UINT8)
    pb = pixels(shot_png, oiio.UINT8)[..., :3]
    check(pa.shape == pb.shape, "%s: PNG sizes %s and %s" % (tag, pa.shape, pb.shape))
    if pa.shape == pb.shape:
        d = np.abs(pa - pb)
        check(d.max() <= 1, "%s: window PNG (OCIO on the GPU) within 1/255 of the preview's PNG (OCIO on the CPU): "
                            "max %d, mean %.4f levels" % (tag, d.max(), d.mean()))
        check(pa.mean() > 10, "%s: the picture is not black (mean level %.1f)" % (tag, pa.mean()))


def read_event(proc, want, timeout=120):
    """The next event named 'want' on the viewer's stdout (earlier events are returned in the list too)."""
    seen = []
    end = time.time() + timeout
    while time.time() < end:
        r, _, _ = select.select([proc.stdout], [], [], 0.5)
        if not r:
            if proc.poll() is not None:
                break
            continue
        line = proc.stdout.readline()
        if not line:
            break
        ev = json.loads(line)
        seen.append(ev)
        if ev["event"] == want:
            return ev, seen
    return None, seen


def test_reload():
    folder = os.path.join(OUT, "reload")
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    scene = os.path.join(folder, "cornell.json")
    doc = json.load(open(os.path.join(SRC, "examples", "cornell.json")))
    json.dump(doc, open(scene, "w"))
    shot = os.path.join(folder, "shot.exr")
    proc = subprocess.Popen([SPECULA, "view", scene, "--resolution", RES, "--events", "--poll", "0.05",
                             "--screenshot", shot], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        ev, _ = read_event(proc, "shown")
        check(ev is not None and ev["generation"] == 1, "reload: first scene shown (%s)" % ev)
        doc["camera"]["fov"] = doc["camera"].get("fov", 40.0) * 0.8
        tmp = scene + ".tmp"
        json.dump(doc, open(tmp, "w"))
        os.replace(tmp, scene)
        ev, seen = read_event(proc, "shown")
        check(ev is not None and ev["generation"] == 2 and any(e["event"] == "loaded" for e in seen),
              "reload: the edited scene is loaded and shown (%s)" % ev)
        with open(scene, "w") as f:
            f.write('{"version": 1, "camera": ')
        ev, _ = read_event(proc, "reload_failed")
        check(ev is not None and "cornell.json" in ev["message"] and ev["code"] == 1,
              "reload: invalid JSON gives reload_failed naming the file, code 1 (%s)" % ev)
        check(proc.poll() is None, "reload: the window stays open after a failed reload")
        proc.send_signal(signal.SIGTERM)
        ev, _ = read_event(proc, "closed")
        code = proc.wait(timeout=60)
        err = proc.stderr.read().strip().splitlines()
        check(ev is not None and code == 0, "reload: SIGTERM closes the window, exit %s%s" %
              (code, "" if code == 0 else " (stderr: %s)" % " | ".join(err[-3:])))
    finally:
        if proc.poll() is None:
            proc.kill()
    # The last good scene, rendered by the preview, is what the screenshot shows.
    good = os.path.join(folder, "good.json")
    json.dump(doc, open(good, "w"))
    ref = os.path.join(folder, "good.preview.exr")
    run([SPECULA, "preview", good, "--resolution", RES, "-o", ref])
    if os.path.exists(shot):
        d = np.nanmax(np.abs(exr_channels(ref)[1] - exr_channels(shot)[1]))
        check(d <= 1e-6, "reload: the exit screenshot is the last good scene's preview (max |diff| %.3g)" % d)
    else:
        check(False, "reload: the screenshot %s was written at exit" % shot)


def test_bad_input():
    scene = os.path.join(SRC, "examples", "cornell.json")
    bad = os.path.join(OUT, "bad.tiff")
    r = subprocess.run([SPECULA, "view", scene, "--screenshot", bad], capture_output=True, text=True, timeout=60)
    check(r.returncode == 2 and ".png or .exr" in r.stderr and not os.path.exists(bad),
          "bad input: --screenshot x.tiff exits 2 (%d: %s)" % (r.returncode, r.stderr.strip()))
    r = subprocess.run([SPECULA, "view", os.path.join(OUT, "missing.json")], capture_output=True, text=True, timeout=60)
    check(r.returncode == 3 and "missing.json" in r.stderr,
          "bad input: a missing scene exits 3 naming it (%d: %s)" % (r.returncode, r.stderr.strip()))


os.makedirs(OUT, exist_ok=True)
compare_with_preview(os.path.join(SRC, "examples", "cornell.json"), "cornell")
compare_with_preview(os.path.join(SRC, "examples", "metals.json"), "metals")
test_reload()
test_bad_input()
if failures:
    sys.exit("FAILED: %d check(s)\n  " % len(failures) + "\n  ".join(failures))
print("all view checks passed")
