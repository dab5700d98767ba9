# Specula for Blender: a thin Blender 3.4+ add-on over the `specula` command line (docs/blender.md).
# It exports the evaluated depsgraph as a Specula scene, renders it with `specula render --progress json` and loads
# the beauty and AOV passes; Specula's own BSDF nodes appear in the shader editor with a Cycles/EEVEE fallback inside.
bl_info = {
    "name": "Specula",
    "author": "Specula developers",
    "version": (0, 3, 0),
    "blender": (3, 4, 0),
    "location": "Render Properties > Render Engine > Specula; Shader Editor > Add > Specula; File > Export",
    "description": "Renders with Specula (glints, LEAN, filtered GGX, P-NDF) through its command line",
    "doc_url": "https://example.invalid/specula/docs/blender.md",
    "category": "Render",
}

import bpy

from . import engine, export, nodes, operators, preferences, properties, ui

_modules = (preferences, properties, nodes, engine, operators, ui)


def register():
    # A module that fails (nodes.py without a node catalogue) takes back what the ones before it registered, so the
    # add-on can be enabled again once the cause is fixed.
    done = []
    try:
        for m in _modules:
            m.register()
            done.append(m)
    except Exception:
        for m in reversed(done):
            m.unregister()
        raise


def unregister():
    for m in reversed(_modules):
        m.unregister()
