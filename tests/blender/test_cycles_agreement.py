# The anchor scene built in Blender, rendered by Cycles and through the Specula add-on from the same .blend:
# the mean radiance on the sphere and on the floor must agree within 3 % (issue 13), Cycles' indirect clamp off.
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bpy  # noqa: E402
import numpy as np  # noqa: E402

from blender_test_util import (COMBINED, OUT_DIR, anchor_masks, build_anchor_scene, check, finish,  # noqa: E402
                               read_exr, render_to)

SIZE, SPP = 256, 64
scene = build_anchor_scene(SIZE)
blend = os.path.join(OUT_DIR, "anchor.blend")
bpy.ops.wm.save_as_mainfile(filepath=blend)

# Cycles: the reference. Clamps off (both are biased), Filter Glossy off (it widens glossy lobes after a diffuse
# bounce, which Specula does not do), otherwise Blender's defaults (12 bounces, 4 diffuse, 4 glossy).
scene.cycles.samples = SPP
scene.cycles.sample_clamp_indirect = 0.0
scene.cycles.sample_clamp_direct = 0.0
scene.cycles.blur_glossy = 0.0
scene.cycles.seed = 0
cycles_exr = os.path.join(OUT_DIR, "anchor_cycles.exr")
t_cycles = render_to(cycles_exr, "CYCLES")

# Specula through the add-on, the same scene file (reloaded, so nothing Cycles set can leak).
bpy.ops.wm.open_mainfile(filepath=blend)
from blender_test_util import enable_addon  # noqa: E402
specula = enable_addon()
scene = bpy.context.scene
scene.specula.samples = SPP
scene.specula.max_bounces = 8
scene.specula.clamp_indirect = 0.0
specula_exr = os.path.join(OUT_DIR, "anchor_specula.exr")
t_specula = render_to(specula_exr, "SPECULA")
info = specula.engine.last_render
check("Specula render finished", info.get("returncode") == 0, str(info.get("error", "")))

cycles = read_exr(cycles_exr, COMBINED)
ours = read_exr(specula_exr, COMBINED)
sphere, floor = anchor_masks(SIZE)
check("masks cover the sphere and the floor", sphere.sum() > 0.05 * SIZE * SIZE and floor.sum() > 0.3 * SIZE * SIZE,
      "%d sphere px, %d floor px" % (sphere.sum(), floor.sum()))
lum = np.array([0.2126, 0.7152, 0.0722], dtype=np.float64)
for name, mask in (("sphere", sphere), ("floor", floor)):
    c = cycles[mask].astype(np.float64).mean(axis=0)
    s = ours[mask].astype(np.float64).mean(axis=0)
    ratio = float((s @ lum) / (c @ lum))
    per_channel = s / c
    check("mean radiance on the %s within 3%% of Cycles" % name, abs(ratio - 1.0) <= 0.03,
          "Specula %s, Cycles %s, luminance ratio %.4f, per channel %s"
          % (np.round(s, 4).tolist(), np.round(c, 4).tolist(), ratio, np.round(per_channel, 4).tolist()))
print("TIMES cycles_render_s %.2f specula_render_s %.2f (add-on wall, export %.3f s, renderer %.2f s)"
      % (t_cycles, t_specula, info.get("export_seconds", 0.0), info.get("render_seconds", 0.0)))
finish()
