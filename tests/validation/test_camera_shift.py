#!/usr/bin/env python3
"""ctest `camera_shift_px` (label cpu): `specula render --camera-shift-px DX,DY` (docs/cli.md) on a plane seen
head-on, painted with its world position (emission = P + const, so every pixel has a distinct, smooth value):

  * a shift of (1, 0) px equals the unshifted image translated left by exactly one pixel, and (0, 1) px up by
    one pixel (camera moves right / down, the picture moves the other way), to float precision;
  * a shift of (0.5, 0) px is half a pixel's emission step away from that translation (so the test can tell a pixel
    from half a pixel);
  * --print-camera reports position and look_at moved by DX * pixel size along the camera's right, where the pixel
    size at the look-at distance is 2 d tan(fov / 2) / width (here d = 5, fov 40°, 64 px);
  * bad values are usage errors (exit 2).

Usage: test_camera_shift.py SPECULA_BINARY SOURCE_DIR
"""
import math
import os
import subprocess
import sys
import tempfile

SPECULA, SRC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SRC, "tools"))
from specula_validation import exr  # noqa: E402
from specula_validation.render import Renderer  # noqa: E402

W, H = 64, 48
SCENE = {
    "version": 1,
    "render": {"width": W, "height": H, "spp": 1, "pixel_center": True, "seed": 0, "integrator": "direct",
               "filter": "box"},
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
    "materials": {"m": {"nodes": {
        "p": {"type": "geometry.position"},
        "o": {"type": "math.add.vector3", "inputs": {"a": "@p.P", "b": [4, 4, 1]}},
        "c": {"type": "convert.vector3_to_color3", "inputs": {"in": "@o.out"}},
        "e": {"type": "bsdf.emission", "inputs": {"color": "@c.out"}}}, "output": "@e.bsdf"}},
    "shapes": [{"type": "quad", "size": [40, 40], "material": "m"}],
    "lights": [],
}


def beauty(rnd, name, shift):
    p, _ = rnd.render(SCENE, name, shift_px=shift)
    return exr.layer(exr.read([p])[0], "beauty")


def max_diff(a, b, dx, dy):
    """Largest |a(x + dx, y + dy) - b(x, y)| over the pixels where both exist, and every channel."""
    worst = 0.0
    for y in range(H - dy):
        for x in range(W - dx):
            i, j = (y + dy) * W + x + dx, y * W + x
            worst = max(worst, max(abs(a[c][i] - b[c][j]) for c in range(3)))
    return worst


def main():
    exr.require_oiiotool()
    failed = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failed.append(what)

    with tempfile.TemporaryDirectory(prefix="camera_shift_") as work:
        rnd = Renderer(SPECULA, work)
        base = beauty(rnd, "base", None)
        px = 2 * 5 * math.tan(math.radians(40) / 2) / W  # pixel size at the look-at distance (on the plane)
        # neighbouring pixels differ by px in emission: the tolerance is a thousandth of that (float precision)
        tol = 1e-3 * px
        d = max_diff(base, beauty(rnd, "x1", (1, 0)), 1, 0)
        check(d <= tol, f"shift (1, 0) px == image translated left by 1 px: max |difference| {d:.2e} <= {tol:.1e}")
        d = max_diff(base, beauty(rnd, "y1", (0, 1)), 0, 1)
        check(d <= tol, f"shift (0, 1) px == image translated up by 1 px: max |difference| {d:.2e} <= {tol:.1e}")
        d = max_diff(base, beauty(rnd, "xh", (0.5, 0)), 1, 0)
        check(abs(d - px / 2) < 100 * tol, f"shift (0.5, 0) px is half a pixel from the 1-px translation: max "
                                           f"|difference| {d:.4e} = px / 2 = {px / 2:.4e}")
        d = max_diff(beauty(rnd, "xm", (-1, 0)), base, 1, 0)
        check(d <= tol, f"shift (-1, 0) px == image translated right by 1 px: max |difference| {d:.2e} <= {tol:.1e}")
        cam = rnd.camera(SCENE, "cam", shift_px=(2.5, -1.0))
        want_p, want_l = [2.5 * px, 1.0 * px, 5.0], [2.5 * px, 1.0 * px, 0.0]
        err = max(abs(a - b) for a, b in zip(cam["position"] + cam["look_at"], want_p + want_l))
        check(err < 1e-6, f"--print-camera for (2.5, -1) px: position {cam['position']}, look_at {cam['look_at']} "
                          f"(expected x = 2.5 px = {2.5 * px:.6f}, y = +1 px = {px:.6f} since +y is down the image; "
                          f"largest error {err:.1e})")
        cam = rnd.camera(SCENE, "cam", resolution=(128, 96), shift_px=(1, 0))
        check(abs(cam["position"][0] - px / 2) < 1e-6, f"with --resolution 128x96 a pixel is half as wide: "
                                                     f"x = {cam['position'][0]:.6f} (expected {px / 2:.6f})")
        js = os.path.join(work, "base.json")
        for bad in ("1", "1,x", "1,2,3", "nan,0"):
            rc = subprocess.run([SPECULA, "render", js, "-o", os.path.join(work, "bad.exr"), "--camera-shift-px", bad],
                                capture_output=True).returncode
            check(rc == 2, f"--camera-shift-px {bad!r} is a usage error: exit code {rc}")
    print(f"\n{len(failed)} failed" if failed else "\nall passed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
