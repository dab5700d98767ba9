# The evaluated depsgraph -> a Specula scene (docs/scene-format.md): meshes (modifiers and instances applied) as
# glTF files next to the JSON, the camera, point/spot/sun/area lights in Blender's units, the world and materials.
# Used by the render engine (into a temporary folder) and by File > Export > Specula Scene.
import json
import math
import os
import re

import bpy
import numpy as np
from mathutils import Vector

from . import gltf
from .materials import ExportError, ImageFiles, MaterialTranslator, blender_colorspace

MESH_TYPES = {"MESH", "CURVE", "SURFACE", "META", "FONT"}
DEFAULT_MATERIAL = "__specula_default"
VIEWS = {"Standard", "Filmic", "Raw"}


def _vec(v):
    return [float(x) for x in v[:3]]


def _row_major(m):
    return [float(m[i][j]) for i in range(4) for j in range(4)]


def render_size(scene):
    r = scene.render
    return (max(1, int(r.resolution_x * r.resolution_percentage / 100)),
            max(1, int(r.resolution_y * r.resolution_percentage / 100)))


class SceneExporter:
    """export() returns (scene dict, warnings) and writes mesh and image assets under <stem>_assets/."""

    def __init__(self, depsgraph, scene_path, width=None, height=None):
        self.depsgraph = depsgraph
        self.scene = depsgraph.scene_eval if hasattr(depsgraph, "scene_eval") else depsgraph.scene
        self.scene_dir = os.path.dirname(os.path.abspath(scene_path))
        stem = os.path.splitext(os.path.basename(scene_path))[0]
        self.asset_rel = stem + "_assets"
        self.asset_dir = os.path.join(self.scene_dir, self.asset_rel)
        size = render_size(self.scene)
        self.width, self.height = width or size[0], height or size[1]
        self.warnings = []
        self.images = ImageFiles(self.asset_dir)
        self.materials = {}
        self.mesh_files = {}   # ("data"|"object", name) -> [(material index, relative file)]

    def warn(self, message):
        if message not in self.warnings:
            self.warnings.append(message)

    # ---- top level -----------------------------------------------------------------------------------------
    def export(self):
        os.makedirs(self.asset_dir, exist_ok=True)
        shapes, lights = [], []
        for inst in self.depsgraph.object_instances:
            obj = inst.object
            if obj.type in MESH_TYPES:
                shapes.extend(self._shapes(inst))
            elif obj.type == "LIGHT":
                light = self._light(obj, inst.matrix_world)
                if light:
                    lights.append(light)
        lights.extend(self._world())
        if DEFAULT_MATERIAL in self._used_materials(shapes):
            self.materials[DEFAULT_MATERIAL] = {
                "doc": "Blender's default surface (no material)",
                "nodes": {"surface": {"type": "bsdf.diffuse", "inputs": {"color": 0.8}}},
                "output": "@surface.bsdf"}
        scene = {
            "version": 1,
            "description": "Exported from Blender %s by the Specula add-on" % bpy.app.version_string,
            "render": self._render_settings(),
            "color": self._color(),
            "camera": self._camera(),
            "materials": self.materials,
            "shapes": shapes,
            "lights": lights,
        }
        return scene, self.warnings

    @staticmethod
    def _used_materials(shapes):
        return {s["material"] for s in shapes}

    def _render_settings(self):
        s = self.scene.specula
        return {"width": self.width, "height": self.height, "spp": s.samples, "seed": s.seed,
                "integrator": s.integrator, "max_depth": s.max_bounces, "filter": s.pixel_filter,
                "clamp_indirect": s.clamp_indirect, "area_lights": s.area_lights, "tile": s.tile_size}

    def _color(self):
        view = self.scene.view_settings
        out = {"exposure": max(-30.0, min(30.0, float(view.exposure)))}
        if view.view_transform in VIEWS:
            out["view"] = view.view_transform
        return out

    # ---- camera --------------------------------------------------------------------------------------------
    def _camera(self):
        cam_obj = self.scene.camera
        if cam_obj is None:
            raise ExportError("the scene has no camera")
        cam_obj = cam_obj.evaluated_get(self.depsgraph)
        cam = cam_obj.data
        if cam.type != "PERSP":
            raise ExportError("camera '%s': only perspective cameras are supported (it is %s)"
                              % (cam_obj.name, cam.type))
        if abs(cam.shift_x) > 1e-6 or abs(cam.shift_y) > 1e-6:
            self.warn("camera '%s': lens shift is not supported; ignored" % cam_obj.name)
        r = self.scene.render
        proj = cam_obj.calc_matrix_camera(self.depsgraph, x=self.width, y=self.height,
                                          scale_x=r.pixel_aspect_x, scale_y=r.pixel_aspect_y)
        m = cam_obj.matrix_world
        position = m.translation
        forward = -Vector(m.col[2][:3]).normalized()   # Blender cameras look down their -Z
        up = Vector(m.col[1][:3]).normalized()
        out = {"position": _vec(position), "up": _vec(up), "fov": math.degrees(2.0 * math.atan(1.0 / proj[0][0])),
               "fov_axis": "x"}
        focus = 1.0
        if cam.dof.use_dof:
            if cam.dof.focus_object is not None:
                target = cam.dof.focus_object.evaluated_get(self.depsgraph).matrix_world.translation
                focus = max((target - position).dot(forward), 1e-4)
            else:
                focus = max(cam.dof.focus_distance, 1e-4)
            unit = self.scene.unit_settings.scale_length or 1.0
            # Cycles: aperture radius = focal length / (2 f-stop), the lens in mm, scene units in metres x unit.
            out["aperture_radius"] = (cam.lens * 1e-3) / (2.0 * max(cam.dof.aperture_fstop, 1e-3)) / unit
            out["focus_distance"] = focus
        out["look_at"] = _vec(position + forward * focus)
        return out

    # ---- meshes --------------------------------------------------------------------------------------------
    def _shapes(self, inst):
        obj = inst.object
        # Objects without modifiers that share mesh data (linked duplicates) share one file; instances of one
        # object share its evaluated mesh.
        if obj.type == "MESH" and len(obj.modifiers) == 0 and obj.data is not None:
            key = ("data", obj.data.original.name)
        else:
            key = ("object", obj.name)
        if key not in self.mesh_files:
            self.mesh_files[key] = self._write_mesh(obj)
        matrix = _row_major(inst.matrix_world)
        # Materials per object: slots linked to the object differ between objects sharing one mesh.
        return [{"type": "mesh", "name": obj.name, "file": rel, "material": self._material_name(obj, index),
                 "transform": {"matrix": matrix}} for index, rel in self.mesh_files[key]]

    def _material_name(self, obj, index):
        slots = obj.material_slots
        material = slots[index].material if index < len(slots) else None
        if material is None:
            return DEFAULT_MATERIAL
        if material.name not in self.materials:
            translator = MaterialTranslator(material, self.images, self.warnings)
            self.materials[material.name] = translator.translate()
        return material.name

    def _write_mesh(self, obj):
        try:
            mesh = obj.to_mesh()
        except RuntimeError:
            return []
        if mesh is None:
            return []
        try:
            return self._write_mesh_data(obj, mesh)
        finally:
            obj.to_mesh_clear()

    def _write_mesh_data(self, obj, mesh):
        mesh.calc_loop_triangles()
        n_tri, n_loop = len(mesh.loop_triangles), len(mesh.loops)
        if n_tri == 0:
            return []
        if hasattr(mesh, "calc_normals_split"):   # Blender < 4.1; later versions keep corner normals up to date
            mesh.calc_normals_split()
        vertex_index = np.empty(n_loop, dtype=np.int32)
        mesh.loops.foreach_get("vertex_index", vertex_index)
        co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        positions = co.reshape(-1, 3)[vertex_index]
        normals = np.empty(n_loop * 3, dtype=np.float32)
        mesh.loops.foreach_get("normal", normals)
        normals = normals.reshape(-1, 3)
        uvs = tangents = None
        uv_layer = mesh.uv_layers.active
        if uv_layer is not None:
            uvs = np.empty(n_loop * 2, dtype=np.float32)
            uv_layer.data.foreach_get("uv", uvs)
            uvs = uvs.reshape(-1, 2)
            try:
                mesh.calc_tangents(uvmap=uv_layer.name)   # MikkTSpace, as Cycles and EEVEE
                t = np.empty(n_loop * 3, dtype=np.float32)
                mesh.loops.foreach_get("tangent", t)
                sign = np.empty(n_loop, dtype=np.float32)
                mesh.loops.foreach_get("bitangent_sign", sign)
                tangents = np.concatenate([t.reshape(-1, 3), sign.reshape(-1, 1)], axis=1)
            except RuntimeError as e:  # n-gons: Specula derives tangents from the uvs
                self.warn("object '%s': no MikkTSpace tangents (%s); Specula derives them from the uvs"
                          % (obj.name, e))
        tri_loops = np.empty(n_tri * 3, dtype=np.int32)
        mesh.loop_triangles.foreach_get("loops", tri_loops)
        tri_loops = tri_loops.reshape(-1, 3)
        material_index = np.empty(n_tri, dtype=np.int32)
        mesh.loop_triangles.foreach_get("material_index", material_index)

        out = []
        base = re.sub(r"[^A-Za-z0-9_.-]", "_", obj.name) or "mesh"
        for index in np.unique(material_index):
            tris = tri_loops[material_index == index]
            used, remap = np.unique(tris.reshape(-1), return_inverse=True)
            name = "%s_%d_m%d.gltf" % (base, len(self.mesh_files), int(index))
            gltf.write_gltf(os.path.join(self.asset_dir, name), positions[used], remap.reshape(-1, 3),
                            normals=normals[used], uvs=None if uvs is None else uvs[used],
                            tangents=None if tangents is None else tangents[used])
            out.append((int(index), self.asset_rel + "/" + name))
        return out

    # ---- lights --------------------------------------------------------------------------------------------
    def _light(self, obj, m):
        light = obj.data
        position = m.translation
        direction = -(m.to_3x3() @ Vector((0.0, 0.0, 1.0))).normalized()  # lights shine down their -Z
        common = {"name": obj.name, "color": _vec(light.color)}
        if light.type == "POINT":
            if light.shadow_soft_size > 0.0:
                self.warn("light '%s': soft point lights (radius %.3g) are rendered as point lights"
                          % (obj.name, light.shadow_soft_size))
            return dict(common, type="point", position=_vec(position), power=float(light.energy))
        if light.type == "SPOT":
            if light.shadow_soft_size > 0.0:
                self.warn("light '%s': soft spot lights (radius %.3g) are rendered as point spots"
                          % (obj.name, light.shadow_soft_size))
            return dict(common, type="spot", position=_vec(position), look_at=_vec(position + direction),
                        cone_angle=min(max(math.degrees(light.spot_size), 0.01), 180.0),
                        blend=float(light.spot_blend), power=float(light.energy))
        if light.type == "SUN":
            return dict(common, type="directional", direction=_vec(direction), irradiance=float(light.energy))
        if light.type == "AREA":
            sx, sy = m.to_3x3().col[0].length, m.to_3x3().col[1].length
            if light.shape in ("SQUARE", "DISK"):
                size = [light.size * sx, light.size * sy]
            else:
                size = [light.size * sx, light.size_y * sy]
            if light.shape in ("DISK", "ELLIPSE"):
                # A quad of the same area: the same power and a similar penumbra.
                size = [s * math.sqrt(math.pi) / 2.0 for s in size]
                self.warn("light '%s': %s area lights are rendered as rectangles of the same area"
                          % (obj.name, light.shape.lower()))
            if getattr(light, "spread", math.pi) < math.pi - 1e-4:
                self.warn("light '%s': area light spread is not supported; ignored" % obj.name)
            up = Vector(m.to_3x3().col[1][:3]).normalized()
            return dict(common, type="quad", position=_vec(position), look_at=_vec(position + direction),
                        up=_vec(up), size=[max(s, 1e-6) for s in size], power=float(light.energy))
        self.warn("light '%s': type %s is not supported; skipped" % (obj.name, light.type))
        return None

    # ---- world ---------------------------------------------------------------------------------------------
    def _world(self):
        world = self.scene.world
        if world is None:
            return []
        if not world.use_nodes or world.node_tree is None:
            color = _vec(world.color)
            return [{"type": "environment", "name": world.name, "color": color}] if any(color) else []
        outputs = [n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"]
        out = next((n for n in outputs if n.is_active_output), outputs[0] if outputs else None)
        if out is None or not out.inputs["Surface"].is_linked:
            return []
        background = out.inputs["Surface"].links[0].from_node
        if background.bl_idname not in ("ShaderNodeBackground", "ShaderNodeEmission"):
            self.warn("world '%s': surface %s is not supported; no environment light" % (world.name,
                                                                                       background.bl_idname))
            return []
        strength = float(background.inputs["Strength"].default_value)
        env = {"type": "environment", "name": world.name, "strength": max(strength, 0.0)}
        color_in = background.inputs["Color"]
        source = color_in.links[0].from_node if color_in.is_linked else None
        if source is not None and source.bl_idname == "ShaderNodeTexEnvironment" and source.image is not None:
            where = "world '%s', node '%s'" % (world.name, source.name)
            if source.projection != "EQUIRECTANGULAR":
                self.warn("%s: projection %s is not supported; read as equirectangular" % (where,
                                                                                           source.projection))
            env["file"] = self.images.image_file(source.image, where)
            env["colorspace"] = blender_colorspace(source.image, where)
            vector = source.inputs["Vector"]
            mapping = vector.links[0].from_node if vector.is_linked else None
            if mapping is not None and mapping.bl_idname == "ShaderNodeMapping":
                # Mapping rotates the lookup direction, so the map turns the other way.
                env["rotation"] = -math.degrees(mapping.inputs["Rotation"].default_value[2])
        elif source is not None and source.bl_idname == "ShaderNodeRGB":
            env["color"] = _vec(source.outputs[0].default_value)
        else:
            if source is not None:
                self.warn("world '%s': colour from %s is not supported; using the socket colour"
                          % (world.name, source.bl_idname))
            env["color"] = _vec(color_in.default_value)
            if not any(env["color"]):
                return []
        if env["strength"] == 0.0:
            return []
        return [env]


def write_scene(depsgraph, scene_path, width=None, height=None):
    """Exports and writes the scene JSON; returns the list of warnings."""
    scene, warnings = SceneExporter(depsgraph, scene_path, width, height).export()
    tmp = scene_path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(scene, f, indent=1)
    os.replace(tmp, scene_path)
    return warnings
