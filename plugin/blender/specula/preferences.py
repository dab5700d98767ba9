# Add-on preferences (Edit > Preferences > Add-ons > Specula): where the `specula` binary is, and how it runs.
# The binary is looked up as: this preference, then $SPECULA_BIN, then `specula` on $PATH.
import os
import shutil

import bpy

ADDON_ID = __package__


class SpeculaPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_ID

    binary_path: bpy.props.StringProperty(
        name="Specula binary",
        description="Path of the `specula` command-line program. Empty: $SPECULA_BIN, then `specula` on PATH",
        subtype="FILE_PATH",
        default="",
    )
    threads: bpy.props.IntProperty(
        name="Threads",
        description="Render threads (0 = all cores). The image does not depend on it",
        default=0, min=0, max=1024,
    )
    keep_files: bpy.props.BoolProperty(
        name="Keep exported files",
        description="Keep the exported scene and the rendered EXR in the render's temporary folder (for debugging)",
        default=False,
    )

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "binary_path")
        found, message = locate_binary()
        row = layout.row()
        row.label(text=message, icon="CHECKMARK" if found else "ERROR")
        layout.prop(self, "threads")
        layout.prop(self, "keep_files")


def get():
    """The add-on's preferences, or None when the add-on is enabled without being registered in the user prefs."""
    addon = bpy.context.preferences.addons.get(ADDON_ID)
    return addon.preferences if addon else None


def locate_binary():
    """(path or None, message). Never raises: the engine turns a None into a Blender error report."""
    prefs = get()
    configured = bpy.path.abspath(prefs.binary_path) if prefs and prefs.binary_path else ""
    source = "preference"
    if not configured and os.environ.get("SPECULA_BIN"):
        configured, source = os.environ["SPECULA_BIN"], "$SPECULA_BIN"
    if configured:
        if os.path.isfile(configured) and os.access(configured, os.X_OK):
            return configured, "Using %s (%s)" % (configured, source)
        return None, ("Specula binary not found or not executable: '%s' (from the %s; set it in Edit > Preferences "
                      "> Add-ons > Specula)" % (configured, source))
    on_path = shutil.which("specula")
    if on_path:
        return on_path, "Using %s (PATH)" % on_path
    return None, ("Specula binary not found: set its path in Edit > Preferences > Add-ons > Specula, or $SPECULA_BIN, "
                  "or put `specula` on PATH")


def register():
    bpy.utils.register_class(SpeculaPreferences)


def unregister():
    bpy.utils.unregister_class(SpeculaPreferences)
