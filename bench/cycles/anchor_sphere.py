"""The anchor scene (examples/anchor-sphere.json) built in Blender 3.4 Cycles, for timing comparisons.

Run:  blender -b --factory-startup --python bench/cycles/anchor_sphere.py -- SPP OUT_PREFIX
Prints 'RENDER_SECONDS <t>': the time of bpy.ops.render.render (scene sync, BVH, path tracing, film),
comparable to Specula's in-process render time. CPU, 2 threads, denoiser off (Debian's Blender has no
OpenImageDenoise), adaptive sampling off, roughness 0.2 (Blender squares it: alpha = 0.04).
"""
import math
import sys
import time

import bpy

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
spp = int(argv[0]) if argv else 1
out = argv[1] if len(argv) > 1 else "/tmp/specula_cycles_anchor"

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene

bpy.ops.mesh.primitive_uv_sphere_add(segments=128, ring_count=64, radius=1.0, location=(0, 0, 1))
sphere = bpy.context.object
bpy.ops.object.shade_smooth()
bpy.ops.mesh.primitive_plane_add(size=20.0, location=(0, 0, 0))
plane = bpy.context.object

metal = bpy.data.materials.new("Copper")
metal.use_nodes = True
p = metal.node_tree.nodes["Principled BSDF"]
p.distribution = "GGX"
p.inputs["Base Color"].default_value = (0.95, 0.64, 0.54, 1.0)
p.inputs["Metallic"].default_value = 1.0
p.inputs["Roughness"].default_value = 0.2
sphere.data.materials.append(metal)

grey = bpy.data.materials.new("Grey")
grey.use_nodes = True
nt = grey.node_tree
nt.nodes.remove(nt.nodes["Principled BSDF"])
d = nt.nodes.new("ShaderNodeBsdfDiffuse")
d.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
nt.links.new(d.outputs["BSDF"], nt.nodes["Material Output"].inputs["Surface"])
plane.data.materials.append(grey)

cam_data = bpy.data.cameras.new("Camera")
cam_data.lens = 50.0  # 36 mm sensor: 39.6 degrees horizontal
cam = bpy.data.objects.new("Camera", cam_data)
scene.collection.objects.link(cam)
cam.location = (0.0, -6.0, 2.5)
# look at (0, 0, 1): pitch down by atan(1.5 / 6)
cam.rotation_euler = (math.pi / 2 - math.atan2(1.5, 6.0), 0.0, 0.0)
scene.camera = cam

light_data = bpy.data.lights.new("Point", type="POINT")
light_data.energy = 1500.0
light_data.shadow_soft_size = 0.0
light = bpy.data.objects.new("Point", light_data)
scene.collection.objects.link(light)
light.location = (4.0, -4.0, 6.0)

world = bpy.data.worlds.new("Black")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
scene.world = world

r = scene.render
r.engine = "CYCLES"
r.resolution_x = r.resolution_y = 512
r.resolution_percentage = 100
r.threads_mode = "FIXED"
r.threads = 2
c = scene.cycles
c.device = "CPU"
c.samples = spp
c.use_adaptive_sampling = False
c.use_denoising = False
# Same bounce budget as the Specula scene (max_depth 8); Cycles' defaults cap diffuse/glossy at 4 each.
c.max_bounces = 8
scene.view_settings.view_transform = "Standard"
r.image_settings.file_format = "OPEN_EXR"
r.image_settings.color_depth = "32"
r.filepath = out + ".exr"

t0 = time.perf_counter()
bpy.ops.render.render(write_still=True)
print("RENDER_SECONDS %.3f" % (time.perf_counter() - t0))
