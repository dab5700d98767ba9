# Specula's render settings on the scene (scene.specula) and its AOV switches on the view layer
# (view_layer.specula): they become the exported scene's `render` block and the passes the engine registers.
import bpy


class SpeculaRenderSettings(bpy.types.PropertyGroup):
    samples: bpy.props.IntProperty(name="Samples", description="Samples per pixel", default=64, min=1,
                                   max=1048576, soft_max=4096)
    seed: bpy.props.IntProperty(name="Seed", description="Sampler seed: same scene and seed give the same image",
                                default=0, min=0, max=2147483647)
    integrator: bpy.props.EnumProperty(
        name="Integrator",
        items=[("path", "Path Tracing", "Path tracer with next-event estimation and MIS"),
               ("direct", "Direct Lighting", "Direct lighting only")],
        default="path")
    max_bounces: bpy.props.IntProperty(name="Max Bounces", description="Maximum number of indirect bounces",
                                       default=8, min=0, max=1024)
    clamp_indirect: bpy.props.FloatProperty(
        name="Clamp Indirect",
        description="Largest RGB component of an indirect sample (0 = off). 10 is Cycles' default, so a scene "
                    "looks alike in both; it trades fireflies for lost energy",
        default=10.0, min=0.0, max=1e9)
    pixel_filter: bpy.props.EnumProperty(
        name="Pixel Filter",
        items=[("box", "Box", "Uniform over the pixel"),
               ("gaussian", "Gaussian", "Gaussian, variance 1/(2 pi) pixel^2")],
        default="box")
    area_lights: bpy.props.EnumProperty(
        name="Area Lights",
        items=[("ltc", "Analytic (LTC)", "Closed-form polygon integrals with stochastic shadows"),
               ("sampled", "Sampled", "Next-event estimation only")],
        default="ltc")
    tile_size: bpy.props.IntProperty(name="Tile Size", description="Tile edge in pixels (progress granularity only)",
                                     default=32, min=1, max=1024)


class SpeculaViewLayerSettings(bpy.types.PropertyGroup):
    pass_diffuse: bpy.props.BoolProperty(name="Diffuse", description="Light whose first scattering was diffuse",
                                         default=True)
    pass_specular: bpy.props.BoolProperty(name="Specular",
                                          description="Light whose first scattering was glossy or specular",
                                          default=True)


_classes = (SpeculaRenderSettings, SpeculaViewLayerSettings)


def register():
    for c in _classes:
        bpy.utils.register_class(c)
    bpy.types.Scene.specula = bpy.props.PointerProperty(type=SpeculaRenderSettings)
    bpy.types.ViewLayer.specula = bpy.props.PointerProperty(type=SpeculaViewLayerSettings)


def unregister():
    del bpy.types.ViewLayer.specula
    del bpy.types.Scene.specula
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
