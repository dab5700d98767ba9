"""The smooth sphere grid of bench/bench_scaling.py built in Blender 3.4 and rendered with Cycles (64x64, 1 sample, CPU,
2 threads), for the memory-per-triangle comparison: the caller reads the process's peak resident memory.

Run:  blender -b --factory-startup --python bench/cycles/mesh_memory.py -- NU NV
The mesh: NU x (NV - 1) vertices on the unit sphere, 2 NU (NV - 2) triangles, the same rings as sphere_grid() there.
"""
import sys

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
nu, nv = int(argv[0]), int(argv[1])

u = np.linspace(0.0, 2.0 * np.pi, nu, endpoint=False)
v = np.linspace(0.0, np.pi, nv + 1)[1:-1]
uu, vv = np.meshgrid(u, v)
p = np.stack([np.sin(vv) * np.cos(uu), np.sin(vv) * np.sin(uu), np.cos(vv)], axis=-1).reshape(-1, 3)
idx = np.arange(len(v) * nu).reshape(len(v), nu)
a, b = idx[:-1, :], np.roll(idx[:-1, :], -1, axis=1)
c, d = idx[1:, :], np.roll(idx[1:, :], -1, axis=1)
tris = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
mesh = bpy.data.meshes.new("sphere")
mesh.vertices.add(len(p))
mesh.vertices.foreach_set("co", p.astype(np.float32).ravel())
mesh.loops.add(tris.size)
mesh.loops.foreach_set("vertex_index", tris.astype(np.int32).ravel())
mesh.polygons.add(len(tris))
mesh.polygons.foreach_set("loop_start", np.arange(0, tris.size, 3, dtype=np.int32))
mesh.polygons.foreach_set("loop_total", np.full(len(tris), 3, dtype=np.int32))
mesh.polygons.foreach_set("use_smooth", np.ones(len(tris), dtype=bool))
mesh.update()
obj = bpy.data.objects.new("sphere", mesh)
scene.collection.objects.link(obj)
mat = bpy.data.materials.new("m")
mat.use_nodes = True
mesh.materials.append(mat)

cam = bpy.data.cameras.new("cam")
cam_obj = bpy.data.objects.new("cam", cam)
cam_obj.location = (0, -4, 1)
scene.collection.objects.link(cam_obj)
direction = -cam_obj.location
cam_obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
scene.camera = cam_obj
world = bpy.data.worlds.new("w")
world.color = (1, 1, 1)
scene.world = world

r = scene.render
r.engine = "CYCLES"
r.resolution_x = r.resolution_y = 64
r.resolution_percentage = 100
r.threads_mode = "FIXED"
r.threads = 2
scene.cycles.device = "CPU"
scene.cycles.samples = 1
scene.cycles.use_adaptive_sampling = False
scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
scene.cycles.max_bounces = 2
r.filepath = "/tmp/specula_cycles_mesh_memory.exr"
r.image_settings.file_format = "OPEN_EXR"
bpy.ops.render.render(write_still=False)
print("TRIANGLES %d" % len(tris))
