# Panels: Specula's sampling settings and AOV switches, plus the built-in panels (dimensions, output, materials,
# world, lights) made visible for the Specula engine through their COMPAT_ENGINES sets.
import bpy

ENGINE = "SPECULA"
# Built-in panels that are not marked for 'BLENDER_RENDER' but that a Specula user needs.
EXTRA_PANELS = {"EEVEE_MATERIAL_PT_context_material", "EEVEE_MATERIAL_PT_surface", "EEVEE_WORLD_PT_surface",
                "DATA_PT_light", "DATA_PT_EEVEE_light", "DATA_PT_spot", "DATA_PT_camera_dof",
                "DATA_PT_camera_dof_aperture", "VIEWLAYER_PT_layer_passes", "VIEWLAYER_PT_layer_passes_data"}


class SpeculaPanel:
    """A panel of (owner, property) rows, shown only while Specula is the render engine."""
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    COMPAT_ENGINES = {ENGINE}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        self.layout.use_property_split = True
        for owner, name in self.rows(context):
            self.layout.prop(owner, name)


class RENDER_PT_specula_sampling(SpeculaPanel, bpy.types.Panel):
    bl_label = "Specula"
    bl_context = "render"

    def rows(self, context):
        s = context.scene.specula
        return [(s, name) for name in ("samples", "seed", "integrator", "max_bounces", "clamp_indirect",
                                       "pixel_filter", "area_lights", "tile_size")]


class VIEWLAYER_PT_specula_passes(SpeculaPanel, bpy.types.Panel):
    bl_label = "Specula Passes"
    bl_context = "view_layer"

    def rows(self, context):
        vl = context.view_layer
        return [(vl.specula, "pass_diffuse"), (vl.specula, "pass_specular"), (vl, "use_pass_normal"),
                (vl, "use_pass_z")]


_classes = (RENDER_PT_specula_sampling, VIEWLAYER_PT_specula_passes)


def _builtin_panels():
    return [p for p in bpy.types.Panel.__subclasses__()
            if hasattr(p, "COMPAT_ENGINES") and p not in _classes
            and ("BLENDER_RENDER" in p.COMPAT_ENGINES or p.__name__ in EXTRA_PANELS)]


def register():
    for c in _classes:
        bpy.utils.register_class(c)
    for p in _builtin_panels():
        p.COMPAT_ENGINES.add(ENGINE)


def unregister():
    for p in _builtin_panels():
        p.COMPAT_ENGINES.discard(ENGINE)
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
