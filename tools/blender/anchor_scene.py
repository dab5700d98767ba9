"""The anchor scene (examples/anchor-sphere.json, shared/anchors) built in Blender: a GGX copper sphere (Principled,
metallic 1, roughness 0.2, so alpha = 0.04) on a 20 x 20 grey Diffuse plane, one 1500 W point light of radius 0, a
black world, a 50 mm camera at (0, -6, 2.5) looking at the sphere's centre. Imported by bench/cycles/anchor_sphere.py
(timings) and tests/blender (the add-on against Cycles)."""
import math

import bpy


def build(size=512):
    """Replaces the open file with the anchor scene at size x size; returns the scene (Cycles CPU, 2 threads,
    adaptive sampling and the denoiser off: Debian's Blender has no OpenImageDenoise)."""
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
    cam.rotation_euler = (math.pi / 2 - math.atan2(1.5, 6.0), 0.0, 0.0)  # look at (0, 0, 1)
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
    r.resolution_x = r.resolution_y = size
    r.resolution_percentage = 100
    r.threads_mode = "FIXED"
    r.threads = 2
    c = scene.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    scene.view_settings.view_transform = "Standard"
    return scene
