# Shared helpers of the headless Blender tests (ctest label blender): enable the add-on from plugin/blender, count
# PASS/FAIL checks, build the anchor scene, and read EXRs with OpenImageIO.
#   blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_X.py -- SPECULA_BIN OUT_DIR
import math
import os
import sys
import time

import addon_utils
import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
SPECULA_BIN = ARGS[0] if ARGS else os.path.join(ROOT, "build", "bin", "specula")
OUT_DIR = ARGS[1] if len(ARGS) > 1 else os.path.join(ROOT, "build", "blender-tests")
os.makedirs(OUT_DIR, exist_ok=True)
os.environ.setdefault("SPECULA_CACHE_DIR", os.path.join(OUT_DIR, "cache"))

_results = []


def enable_addon():
    # The source add-on has no node_catalog.json (the build stages one): it asks this binary for the catalogue.
    os.environ["SPECULA_BIN"] = SPECULA_BIN
    if not addon_utils.check("specula")[1]:
        sys.path.insert(0, os.path.join(ROOT, "plugin", "blender"))
        addon_utils.enable("specula", default_set=True, handle_error=None)
    import specula  # noqa: F401 (the add-on package)
    prefs = bpy.context.preferences.addons["specula"].preferences
    prefs.binary_path = SPECULA_BIN
    return sys.modules["specula"]


def check(name, ok, detail=""):
    _results.append(bool(ok))
    print(("PASS " if ok else "FAIL ") + name + ((": " + detail) if detail else ""), flush=True)
    return ok


def finish():
    print("%d passed, %d failed" % (_results.count(True), _results.count(False)), flush=True)
    sys.exit(0 if _results and all(_results) else 1)


def read_exr(path, channels):
    """float32 (h, w, len(channels)), top row first."""
    import OpenImageIO as oiio
    image = oiio.ImageInput.open(path)
    if image is None:
        raise OSError(oiio.geterror())
    spec = image.spec()
    pixels = np.asarray(image.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT), dtype=np.float32)
    image.close()
    pixels = pixels.reshape(spec.height, spec.width, spec.nchannels)
    names = list(spec.channelnames)
    return pixels[:, :, [names.index(c) for c in channels]]


COMBINED = ("ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B")


def render_to(path, engine):
    """Renders the current scene with `engine` into a 32-bit multilayer EXR; returns the seconds taken."""
    scene = bpy.context.scene
    scene.render.engine = engine
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "ZIP"
    scene.render.filepath = path
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - t0


def build_anchor_scene(size):
    """tools/blender/anchor_scene.py (the scene of examples/anchor-sphere.json and shared/anchors), with the add-on."""
    sys.path.insert(0, os.path.join(ROOT, "tools", "blender"))
    import anchor_scene
    scene = anchor_scene.build(size)
    enable_addon()
    return scene


def anchor_masks(size):
    """Pixels whose four corners all see the sphere, or all see the plane (camera rays intersected with the
    analytic sphere and plane: the edges, where the pixel filters differ, are left out)."""
    cam = bpy.context.scene.camera
    m = cam.matrix_world
    origin = np.array(m.translation)
    forward = -np.array(m.col[2][:3])
    up = np.array(m.col[1][:3])
    right = np.cross(forward, up)
    t = math.tan(cam.data.angle_x / 2.0)
    c = (np.arange(size + 1) / size) * 2.0 - 1.0
    x, y = np.meshgrid(c * t, -c * t)  # corner grid, top row first
    d = forward[None, None] + x[..., None] * right[None, None] + y[..., None] * up[None, None]
    d /= np.linalg.norm(d, axis=2, keepdims=True)
    oc = origin - np.array([0.0, 0.0, 1.0])
    b = (d * oc).sum(axis=2)
    disc = b * b - (oc @ oc - 1.0)
    hit_sphere = (disc > 0) & (-b - np.sqrt(np.maximum(disc, 0)) > 0)
    tp = -origin[2] / np.minimum(d[..., 2], -1e-9)
    p = origin[None, None] + tp[..., None] * d
    hit_plane = (d[..., 2] < 0) & (np.abs(p[..., 0]) < 10) & (np.abs(p[..., 1]) < 10) & ~hit_sphere

    def all4(a):
        return a[:-1, :-1] & a[1:, :-1] & a[:-1, 1:] & a[1:, 1:]
    return all4(hit_sphere), all4(hit_plane)
