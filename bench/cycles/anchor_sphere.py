"""The anchor scene (examples/anchor-sphere.json) built in Blender 3.4 Cycles, for timing comparisons.

Run:  blender -b --factory-startup --python bench/cycles/anchor_sphere.py -- SPP OUT_PREFIX
Prints 'RENDER_SECONDS <t>': the time of bpy.ops.render.render (scene sync, BVH, path tracing, film),
comparable to Specula's in-process render time. CPU, 2 threads, denoiser off (Debian's Blender has no
OpenImageDenoise), adaptive sampling off, roughness 0.2 (Blender squares it: alpha = 0.04).
"""
import os
import sys
import time

import bpy

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
spp = int(argv[0]) if argv else 1
out = argv[1] if len(argv) > 1 else "/tmp/specula_cycles_anchor"

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "blender"))
import anchor_scene  # noqa: E402

scene = anchor_scene.build(512)
r = scene.render
r.engine = "CYCLES"
c = scene.cycles
c.samples = spp
# Same bounce budget as the Specula scene (max_depth 8); Cycles' defaults cap diffuse/glossy at 4 each.
c.max_bounces = 8
scene.view_settings.view_transform = "Standard"
r.image_settings.file_format = "OPEN_EXR"
r.image_settings.color_depth = "32"
r.filepath = out + ".exr"

t0 = time.perf_counter()
bpy.ops.render.render(write_still=True)
print("RENDER_SECONDS %.3f" % (time.perf_counter() - t0))
