# File > Export > Specula Scene (.json): the same export the render engine does, into a folder of the user's
# choosing (scene.json plus <stem>_assets/ with the meshes), to render later with `specula render`.
import bpy
from bpy_extras.io_utils import ExportHelper

from . import export
from .materials import ExportError


class EXPORT_SCENE_OT_specula(bpy.types.Operator, ExportHelper):
    """Export the scene as a Specula scene (JSON, with glTF meshes in <name>_assets/)"""
    bl_idname = "export_scene.specula"
    bl_label = "Export Specula Scene"
    bl_options = {"PRESET"}

    filename_ext = ".json"
    filter_glob: bpy.props.StringProperty(default="*.json", options={"HIDDEN"})

    def execute(self, context):
        depsgraph = context.evaluated_depsgraph_get()
        try:
            warnings = export.write_scene(depsgraph, self.filepath)
        except ExportError as e:
            self.report({"ERROR"}, "Specula export: %s" % e)
            return {"CANCELLED"}
        for w in warnings:
            self.report({"WARNING"}, "Specula: " + w)
        self.report({"INFO"}, "Exported %s" % self.filepath)
        return {"FINISHED"}


def _menu(self, context):
    self.layout.operator(EXPORT_SCENE_OT_specula.bl_idname, text="Specula Scene (.json)")


def register():
    bpy.utils.register_class(EXPORT_SCENE_OT_specula)
    bpy.types.TOPBAR_MT_file_export.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_file_export.remove(_menu)
    bpy.utils.unregister_class(EXPORT_SCENE_OT_specula)
