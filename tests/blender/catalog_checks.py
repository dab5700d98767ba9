# Checks that the add-on's Specula nodes are built from the node catalogue (`specula nodes --json`): every socket and
# setting that sets a Specula port shows that port's default, hard range, documentation and enum values.
# Shared by test_addon.py (source add-on, catalogue asked of the CLI) and test_install.py (zip, node_catalog.json).
import struct

import bpy

FLOAT_MAX = 3.4028234663852886e38   # Blender's bound for a side the port leaves open


def f32(x):
    """x as Blender stores it (a float socket holds float32)."""
    return struct.unpack("f", struct.pack("f", x))[0]


def check_nodes_follow_catalog(specula, catalog, check):
    """catalog: {node id: node} of the CLI's JSON. Adds one check per socket and setting; returns how many."""
    nodes = specula.nodes
    mat = bpy.data.materials.new("catalogue check")
    mat.use_nodes = True
    checked = 0
    for idname, nodedef in nodes.NODE_DEFS.items():
        node = mat.node_tree.nodes.new(idname)
        declared = [d.name for d in nodedef.socket_decls]
        shown = [s.name for s in node.node_tree.inputs if not s.hide_value]
        check("%s: its sockets are the declared ones" % idname, shown == declared, "%s vs %s" % (shown, declared))
        check("%s: its description is the documentation of %s" % (idname, nodedef.specula_nodes[0]),
              type(node).bl_description.startswith(catalog[nodedef.specula_nodes[0]]["doc"]))
        for decl in nodedef.socket_decls:
            if isinstance(decl, nodes.HostSocket):
                continue   # Blender's own parameterisation (filtered GGX roughness, anisotropy): no port
            port = {p["name"]: p for p in catalog[decl.node_id]["inputs"]}[decl.port]
            iface, sock = node.node_tree.inputs[decl.name], node.inputs[decl.name]
            where = "%s '%s' = %s.%s" % (idname, decl.name, decl.node_id, decl.port)
            default = port["default"]
            if decl.host_default is not None:
                check(where + ": a host default differs from the declared one", decl.host_default != tuple(default),
                      "%s vs %s" % (decl.host_default, default))
                default = decl.host_default
            if port["type"] == "color3":
                want = tuple(f32(v) for v in default) + (1.0,)
                got = (tuple(iface.default_value), tuple(sock.default_value))
                check(where + ": default", got == (want, want), "%s, want %s" % (got, want))
            else:
                lo = f32(port["hard_min"]) if port["hard_min"] is not None else -FLOAT_MAX
                hi = f32(port["hard_max"]) if port["hard_max"] is not None else FLOAT_MAX
                got = (iface.default_value, sock.default_value, iface.min_value, iface.max_value)
                want = (f32(default), f32(default), f32(lo), f32(hi))
                check(where + ": default and hard range", got == want, "%s, want %s" % (got, want))
            # Blender keeps 63 bytes of a socket's tooltip: a longer doc shows as its start, cut at a word.
            tip, doc = iface.description, port["doc"]
            ok = tip == doc if len(doc.encode()) <= 63 else \
                (tip.endswith("...") and doc.startswith(tip[:-3] + " ") and len(tip.encode()) <= 63)
            check(where + ": tooltip is the port's doc", ok, "'%s' vs '%s'" % (tip, doc))
            checked += 1
        for key, (node_id, port_name) in nodedef.setting_ports.items():
            port = {p["name"]: p for p in catalog[node_id]["inputs"]}[port_name]
            prop = type(node).bl_rna.properties[key]
            where = "%s setting %s = %s.%s" % (idname, key, node_id, port_name)
            if prop.type == "BOOLEAN":
                ok = sorted(port["enum"]) == ["off", "on"] and getattr(node, key) == (port["default"] == "on")
                check(where + ": an on/off switch with the declared default", ok, str(port["enum"]))
            else:
                items = [i.identifier for i in prop.enum_items]
                check(where + ": the declared values and default", items == port["enum"] and
                      getattr(node, key) == port["default"], "%s / %s" % (items, getattr(node, key)))
            check(where + ": tooltip is the port's doc", prop.description == port["doc"])
            checked += 1
    bpy.data.materials.remove(mat)
    return checked
