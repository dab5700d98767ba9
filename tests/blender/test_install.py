# The user's way in: Edit > Preferences > Add-ons > Install... with build/specula-blender-addon.zip, then enable it.
# Run with BLENDER_USER_SCRIPTS pointing at an empty folder, so the user's own add-ons are not touched.
#   blender -b --factory-startup --python-exit-code 1 --python test_install.py -- ZIP
import json
import os
import sys

import addon_utils
import bpy

zip_path = sys.argv[sys.argv.index("--") + 1]
results = []


def check(name, ok, detail=""):
    results.append(bool(ok))
    print(("PASS " if ok else "FAIL ") + name + ((": " + detail) if detail else ""), flush=True)


user_scripts = os.environ.get("BLENDER_USER_SCRIPTS", "")
check("BLENDER_USER_SCRIPTS is a scratch folder", user_scripts and "blender-install" in user_scripts, user_scripts)
bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
installed = os.path.join(user_scripts, "addons", "specula", "__init__.py")
check("the zip installs into the user's add-ons folder", os.path.isfile(installed), installed)
addon_utils.enable("specula", default_set=True, handle_error=None)
check("the add-on enables", addon_utils.check("specula")[1])
import specula  # noqa: E402
check("it is the installed copy", os.path.dirname(specula.__file__) == os.path.dirname(installed), specula.__file__)
# Its nodes come from the node_catalog.json packed with it (no binary is configured here).
catalog_file = os.path.join(os.path.dirname(installed), "node_catalog.json")
check("the zip carries the node catalogue", specula.nodes.CATALOG_FILE == catalog_file and os.path.isfile(catalog_file))
with open(catalog_file) as f:
    catalog = {n["id"]: n for n in json.load(f)["nodes"]}
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from catalog_checks import check_nodes_follow_catalog  # noqa: E402
check("its nodes follow the catalogue", check_nodes_follow_catalog(specula, catalog, check) >= 20)
check("bl_info names Blender 3.4", tuple(specula.bl_info["blender"]) == (3, 4, 0))
check("the Specula engine is registered",
      "SPECULA" in {e.bl_idname for e in bpy.types.RenderEngine.__subclasses__()})
bpy.context.scene.render.engine = "SPECULA"
check("it can be selected as the render engine", bpy.context.scene.render.engine == "SPECULA")
addon_utils.disable("specula", default_set=True)
check("and disables cleanly", not addon_utils.check("specula")[1])
print("%d passed, %d failed" % (results.count(True), results.count(False)))
sys.exit(0 if all(results) else 1)
