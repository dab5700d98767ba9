# Blender shader node trees -> Specula material graphs (docs/graph-format.md), for the exporter.
# Principled, Diffuse, Glossy, Anisotropic, Emission, Mix/Add Shader, Normal Map, Image Texture, Mapping, RGB and
# Value nodes, user node groups, reroutes and muted nodes are translated; Specula's own nodes (nodes.py) export
# themselves. Anything else is replaced by its socket default, and a warning names the material and the node.
import math
import os
import re

from . import nodes as specula_nodes

# Blender colour-space names (3.x and 4.x configs) -> Specula's built-in config (docs/scene-format.md).
COLORSPACES = {
    "sRGB": "sRGB - Texture",
    "Linear": "Linear Rec.709 (sRGB)",
    "Linear Rec.709": "Linear Rec.709 (sRGB)",
    "Non-Color": "raw",
    "Raw": "raw",
    "Filmic Log": "Filmic Log",
    "Linear ACES": "ACES2065-1",
    "ACES2065-1": "ACES2065-1",
    "Linear ACEScg": "ACEScg",
    "ACEScg": "ACEScg",
    "Linear P3-D65": "Linear P3-D65",
}

WRAP = {"REPEAT": "repeat", "EXTEND": "clamp", "MIRROR": "mirror", "CLIP": "clamp"}


class ExportError(Exception):
    """A scene that cannot be exported (a required file missing, an unsupported colour space, ...)."""


def blender_colorspace(image, where):
    name = image.colorspace_settings.name
    if name not in COLORSPACES:
        raise ExportError("%s: image '%s' has colour space '%s', which Specula does not know (use one of: %s)"
                          % (where, image.name, name, ", ".join(sorted(COLORSPACES))))
    return COLORSPACES[name]


def _clamp01(values):
    return [min(max(float(v), 0.0), 1.0) for v in values]


class MaterialTranslator:
    """Translates one material. `assets` gives image files (ImageFiles), `warnings` collects messages."""

    def __init__(self, material, assets, warnings):
        self.material, self.assets, self.warnings = material, assets, warnings
        self.graph_nodes = {}
        self.cache = {}
        self.ctx = ()            # the group nodes we are inside, outermost first
        self.current = None      # the Blender node being translated (for messages)

    # ---- entry point ---------------------------------------------------------------------------------------
    def translate(self):
        out = self._output_node()
        surface = None
        if out is not None:
            surface = self.closure(out.inputs["Surface"])
        if surface is None:
            surface = self._black()
        return {"doc": "exported from Blender material '%s'" % self.material.name, "nodes": self.graph_nodes,
                "output": surface}

    def _output_node(self):
        if not self.material.use_nodes or self.material.node_tree is None:
            return None
        outputs = [n for n in self.material.node_tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
        for preferred in (lambda n: n.is_active_output and n.target in ("ALL", "CYCLES"),
                          lambda n: n.target in ("ALL", "CYCLES"), lambda n: True):
            for n in outputs:
                if preferred(n):
                    return n
        return None

    # ---- helpers used by nodes.py ----------------------------------------------------------------------------
    def where(self, node=None):
        node = node or self.current
        path = "".join("%s > " % g.name for g in self.ctx)
        return "material '%s', node '%s%s'" % (self.material.name, path, node.name if node else "?")

    def warn(self, message):
        if message not in self.warnings:
            self.warnings.append(message)

    def error(self, message):
        raise ExportError(message)

    def add(self, node_type, inputs, blender_node=None, suffix=""):
        base = re.sub(r"[^A-Za-z0-9_]", "_", (blender_node.name if blender_node else node_type)) or "n"
        if suffix:
            base += "_" + suffix
        node_id, k = base, 2
        while node_id in self.graph_nodes:
            node_id, k = "%s_%d" % (base, k), k + 1
        self.graph_nodes[node_id] = {"type": node_type,
                                     "inputs": {k: v for k, v in inputs.items() if v is not None}}
        return node_id

    def image_file(self, image, node=None):
        return self.assets.image_file(image, self.where(node))

    def constant(self, node, socket_name):
        """A float input that must be a constant (it feeds a host-side formula)."""
        kind, payload = self._resolve(node.inputs[socket_name], self.ctx)
        if kind == "value":
            return float(payload.default_value)
        if payload[0].bl_idname == "ShaderNodeValue":
            return float(payload[0].outputs[0].default_value)
        self.warn("%s: input '%s' must be a constant for Specula; using its value %g"
                  % (self.where(node), socket_name, node.inputs[socket_name].default_value))
        return float(node.inputs[socket_name].default_value)

    def value(self, node, socket_name, kind):
        return self._value(node.inputs[socket_name], self.ctx, kind)

    def normal(self, node, socket_name, with_derivatives=False):
        """Ports {normal[, dndx, dndy]} of a BSDF whose Normal input is `socket_name` ({} = the shading normal)."""
        if socket_name not in node.inputs:
            return {}
        kind, payload = self._resolve(node.inputs[socket_name], self.ctx)
        if kind == "value":
            return {}
        src, out, ctx = payload
        if src.bl_idname == "ShaderNodeNormalMap":
            nm = self._cached(src, out, ctx, self._normal_map)
            ports = {"normal": "@%s.normal" % nm}
            if with_derivatives:
                ports.update({"dndx": "@%s.dndx" % nm, "dndy": "@%s.dndy" % nm})
            return ports
        if src.bl_idname == "ShaderNodeNewGeometry" and out.identifier == "Normal":
            return {}
        self.warn("%s: normal input from '%s' (%s) is not supported; using the shading normal"
                  % (self.where(node), src.name, src.bl_idname))
        return {}

    # ---- link resolution across reroutes, muted nodes and node groups -----------------------------------------
    def _resolve(self, socket, ctx):
        """('value', socket with the default that applies) or ('link', (node, output socket, ctx))."""
        for _ in range(10000):  # bounded: a malformed tree cannot recurse forever
            links = [l for l in socket.links if l.is_valid and not l.is_muted] if socket.is_linked else []
            if not links:
                return "value", socket
            node, out = links[0].from_node, links[0].from_socket
            if node.bl_idname == "NodeReroute":
                socket = node.inputs[0]
                continue
            if node.mute:
                through = [il.from_socket for il in node.internal_links if il.to_socket == out]
                if not through:
                    return "value", socket
                socket = through[0]
                continue
            if node.bl_idname == "NodeGroupInput":
                if not ctx:
                    return "value", socket
                outer = ctx[-1]
                socket = next(s for s in outer.inputs if s.identifier == out.identifier)
                ctx = ctx[:-1]
                continue
            if node.bl_idname == "ShaderNodeGroup" and node.node_tree is not None:
                group_out = next((n for n in node.node_tree.nodes
                                  if n.bl_idname == "NodeGroupOutput" and n.is_active_output), None)
                if group_out is None:
                    return "value", socket
                socket = next(s for s in group_out.inputs if s.identifier == out.identifier)
                ctx = ctx + (node,)
                continue
            return "link", (node, out, ctx)
        raise ExportError("%s: node links too deep" % self.material.name)

    def _cached(self, node, out, ctx, fn):
        key = (tuple(g.name for g in ctx), node.name, out.identifier if out is not None else "")
        if key not in self.cache:
            saved = self.ctx, self.current
            self.ctx, self.current = ctx, node
            try:
                self.cache[key] = fn(node, out)
            finally:
                self.ctx, self.current = saved
        return self.cache[key]

    # ---- values ----------------------------------------------------------------------------------------------
    def _literal(self, socket, kind):
        v = socket.default_value if hasattr(socket, "default_value") else 0.0
        if kind == "float":
            if hasattr(v, "__len__"):
                return float(sum(v[:3]) / 3.0)
            return float(v)
        if hasattr(v, "__len__"):
            return [float(x) for x in v[:3]]
        return float(v)

    def _value(self, socket, ctx, kind):
        state, payload = self._resolve(socket, ctx)
        if state == "value":
            return self._literal(payload, kind)
        src, out, src_ctx = payload
        if src.bl_idname == "ShaderNodeRGB":
            return self._literal(out, kind)
        if src.bl_idname == "ShaderNodeValue":
            return self._literal(out, kind)
        if src.bl_idname == "ShaderNodeTexImage":
            img = self._cached(src, None, src_ctx, self._image)
            if out.identifier == "Alpha":
                ref = "@%s.alpha" % img
                return ref if kind == "float" else "@%s.out" % self.add("convert.float_to_color3", {"in": ref},
                                                                        src, "rgb")
            ref = "@%s.color" % img
            if kind == "float":
                return "@%s.out" % self.add("convert.color3_to_float", {"in": ref, "channel": "luminance"},
                                            src, "lum")
            return ref
        self.warn("%s: input '%s' comes from '%s' (%s), which Specula does not translate; using its value"
                  % (self.where(), socket.name, src.name, src.bl_idname))
        return self._literal(socket, kind)

    def _image(self, node, _out):
        if node.image is None:
            self.error("%s: Image Texture without an image" % self.where(node))
        if node.projection != "FLAT":
            self.warn("%s: projection %s is not supported; using flat uv mapping" % (self.where(node),
                                                                                     node.projection))
        if node.extension == "CLIP":
            self.warn("%s: extension CLIP is exported as clamp" % self.where(node))
        inputs = {"file": self.image_file(node.image, node),
                  "colorspace": blender_colorspace(node.image, self.where(node)),
                  "wrap": WRAP.get(node.extension, "repeat")}
        inputs.update(self._uv(node.inputs["Vector"], node))
        return self.add("texture.image", inputs, node)

    def _uv(self, socket, node):
        state, payload = self._resolve(socket, self.ctx)
        if state == "value":
            return {}
        src, out, ctx = payload
        if src.bl_idname == "ShaderNodeTexCoord" and out.identifier == "UV":
            return {}
        if src.bl_idname == "ShaderNodeUVMap":
            return {}
        if src.bl_idname == "ShaderNodeMapping":
            return self._cached(src, out, ctx, self._mapping)
        self.warn("%s: texture coordinates from '%s' (%s) are not supported; using the UV map"
                  % (self.where(node), src.name, src.bl_idname))
        return {}

    def _mapping(self, node, _out):
        if node.vector_type not in ("POINT", "TEXTURE"):
            self.warn("%s: mapping type %s is exported as POINT" % (self.where(node), node.vector_type))
        loc = self._literal(node.inputs["Location"], "vector3")
        rot = self._literal(node.inputs["Rotation"], "vector3")
        scale = self._literal(node.inputs["Scale"], "vector3")
        if abs(rot[0]) > 1e-6 or abs(rot[1]) > 1e-6:
            self.warn("%s: only the Z rotation of a Mapping node is used for uvs" % self.where(node))
        inputs = {"scale": [scale[0], scale[1]], "rotation": math.degrees(rot[2]), "offset": [loc[0], loc[1]]}
        if node.vector_type == "TEXTURE":  # the inverse transform
            self.warn("%s: TEXTURE mapping is approximated by the inverse scale and offset" % self.where(node))
            inputs = {"scale": [1.0 / (scale[0] or 1.0), 1.0 / (scale[1] or 1.0)], "rotation": -inputs["rotation"],
                      "offset": [-loc[0], -loc[1]]}
        inputs.update(self._uv(node.inputs["Vector"], node))
        xf = self.add("texture.uv_transform", inputs, node)
        return {"uv": "@%s.uv" % xf, "duvdx": "@%s.duvdx" % xf, "duvdy": "@%s.duvdy" % xf}

    def _normal_map(self, node, _out):
        if node.space != "TANGENT":
            self.warn("%s: normal map space %s is not supported; treated as tangent space" % (self.where(node),
                                                                                            node.space))
        inputs = {"strength": self._value(node.inputs["Strength"], self.ctx, "float")}
        state, payload = self._resolve(node.inputs["Color"], self.ctx)
        if state == "link" and payload[0].bl_idname == "ShaderNodeTexImage":
            img = self._cached(payload[0], None, payload[2], self._image)
            inputs.update({"color": "@%s.color" % img, "dcolor_du": "@%s.dcolor_du" % img,
                           "dcolor_dv": "@%s.dcolor_dv" % img})
            image_inputs = self.graph_nodes[img]["inputs"]
            for port in ("duvdx", "duvdy"):
                if port in image_inputs:
                    inputs[port] = image_inputs[port]
        else:
            inputs["color"] = self._value(node.inputs["Color"], self.ctx, "color3")
        return self.add("texture.normal_map", inputs, node)

    # ---- closures --------------------------------------------------------------------------------------------
    def _black(self):
        return "@%s.bsdf" % self.add("bsdf.emission", {"color": 0.0, "strength": 0.0}, None, "black")

    def closure(self, socket):
        state, payload = self._resolve(socket, self.ctx)
        if state == "value":
            return None
        node, out, ctx = payload
        return self._cached(node, out, ctx, self._closure_of)

    def _closure_of(self, node, out):
        custom = specula_nodes.NODE_DEFS.get(node.bl_idname)
        if custom is not None:
            return custom.export(node, self)
        handler = {
            "ShaderNodeBsdfPrincipled": self._principled,
            "ShaderNodeBsdfDiffuse": self._diffuse,
            "ShaderNodeBsdfGlossy": self._glossy,
            "ShaderNodeBsdfAnisotropic": self._glossy,
            "ShaderNodeBsdfGlass": self._glass,
            "ShaderNodeEmission": self._emission,
            "ShaderNodeMixShader": self._mix,
            "ShaderNodeAddShader": self._add_shader,
        }.get(node.bl_idname)
        if handler is None:
            self.warn("%s: shader %s is not supported by Specula; rendered as grey diffuse"
                      % (self.where(node), node.bl_idname))
            return "@%s.bsdf" % self.add("bsdf.diffuse", {"color": 0.8}, node, "unsupported")
        return handler(node)

    def _sub_closure(self, socket):
        return self.closure(socket) or self._black()

    def _diffuse(self, node):
        if self._literal(node.inputs["Roughness"], "float") > 0.0:
            self.warn("%s: Oren-Nayar roughness is not supported; rendered as Lambert" % self.where(node))
        inputs = {"color": self._value(node.inputs["Color"], self.ctx, "color3")}
        inputs.update(self.normal(node, "Normal"))
        return "@%s.bsdf" % self.add("bsdf.diffuse", inputs, node)

    def _glossy(self, node):
        distribution = getattr(node, "distribution", "GGX")
        color = self._value(node.inputs["Color"], self.ctx, "color3")
        normal = self.normal(node, "Normal")
        if distribution == "SHARP":
            roughness, anisotropy = 0.0, 0.0
        else:
            roughness = self.constant(node, "Roughness")
            anisotropy = self.constant(node, "Anisotropy") if "Anisotropy" in node.inputs else 0.0
        if distribution == "BECKMANN" and anisotropy == 0.0:
            inputs = {"weight": color, "roughness": roughness, "fresnel": "none"}
            inputs.update(normal)
            return "@%s.bsdf" % self.add("bsdf.beckmann_lean", inputs, node)
        if distribution not in ("GGX", "SHARP"):
            self.warn("%s: distribution %s is rendered as single-scattering GGX" % (self.where(node), distribution))
        if "Rotation" in node.inputs and abs(self._literal(node.inputs["Rotation"], "float")) > 1e-6:
            self.warn("%s: anisotropic rotation is not supported (the tangent is dP/du)" % self.where(node))
        # Cycles' Anisotropic BSDF: alpha = r^2 stretched by (1 -/+ anisotropy) (intern/cycles bsdf setup).
        alpha = roughness * roughness
        a = max(min(anisotropy, 0.99), -0.99)
        if a < 0.0:
            ax, ay = alpha / (1.0 + a), alpha * (1.0 + a)
        else:
            ax, ay = alpha * (1.0 - a), alpha / (1.0 - a)
        inputs = {"weight": color, "alpha": [min(ax, 1.0), min(ay, 1.0)], "filter": "none", "f0": 1.0}
        inputs.update(normal)
        return "@%s.bsdf" % self.add("bsdf.ggx_filtered", inputs, node)

    def _glass(self, node):
        """Cycles' Glass BSDF as bsdf.dielectric: its colour tints reflection and refraction alike (the node's weight),
        roughness as GGX's perceptual roughness, the IOR inverted inside closed objects as Cycles does."""
        distribution = getattr(node, "distribution", "GGX")
        if distribution not in ("GGX", "SHARP"):
            self.warn("%s: glass distribution %s is rendered as single-scattering GGX" % (self.where(node), distribution))
        inputs = {"weight": self._value(node.inputs["Color"], self.ctx, "color3"),
                  "roughness": 0.0 if distribution == "SHARP" else self._value(node.inputs["Roughness"], self.ctx, "float"),
                  "ior": min(max(self.constant(node, "IOR"), 1.0001), 10.0)}
        inputs.update(self.normal(node, "Normal"))
        return "@%s.bsdf" % self.add("bsdf.dielectric", inputs, node)

    def _emission(self, node):
        return "@%s.bsdf" % self.add("bsdf.emission", {
            "color": self._value(node.inputs["Color"], self.ctx, "color3"),
            "strength": self._value(node.inputs["Strength"], self.ctx, "float")}, node)

    def _mix(self, node):
        a, b = self._sub_closure(node.inputs[1]), self._sub_closure(node.inputs[2])
        return "@%s.bsdf" % self.add("closure.mix", {"a": a, "b": b,
                                                     "t": self._value(node.inputs["Fac"], self.ctx, "float")}, node)

    def _add_shader(self, node):
        a, b = self._sub_closure(node.inputs[0]), self._sub_closure(node.inputs[1])
        return "@%s.bsdf" % self.add("closure.add", {"a": a, "b": b}, node)

    def _principled(self, node):
        """Cycles 3.x Principled v1 as a Specula graph: mix(diffuse + dielectric GGX, metal GGX, metallic), then the
        coat and the emission. Cycles adds its diffuse and specular lobes without albedo scaling, and so does this."""
        where = self.where(node)
        inp = node.inputs
        for name in ("Subsurface", "Transmission", "Sheen"):
            if name in inp and (inp[name].is_linked or self._literal(inp[name], "float") > 0.0):
                self.warn("%s: Principled %s is not supported; ignored" % (where, name))
        if node.distribution != "GGX":
            self.warn("%s: distribution %s is rendered as single-scattering GGX" % (where, node.distribution))
        if self._literal(inp["Anisotropic Rotation"], "float") != 0.0:
            self.warn("%s: anisotropic rotation is not supported (the tangent is dP/du)" % where)
        base = self._value(inp["Base Color"], self.ctx, "color3")
        roughness = self._value(inp["Roughness"], self.ctx, "float")
        anisotropy = self._value(inp["Anisotropic"], self.ctx, "float")
        normal = self.normal(node, "Normal")
        metallic = self._value(inp["Metallic"], self.ctx, "float")
        specular = self.constant(node, "Specular")
        tint = self.constant(node, "Specular Tint")
        spec_f0 = 0.08 * specular
        if tint > 0.0 and isinstance(base, list):
            lum = 0.2126 * base[0] + 0.7152 * base[1] + 0.0722 * base[2]
            tint_color = [c / lum if lum > 0 else 1.0 for c in base]
            f0_dielectric = _clamp01([spec_f0 * ((1 - tint) + tint * c) for c in tint_color])
        else:
            f0_dielectric = min(spec_f0, 1.0)

        def ggx(f0, suffix):
            inputs = {"roughness": roughness, "anisotropy": anisotropy, "fresnel": "schlick", "f0": f0}
            inputs.update(normal)
            return "@%s.bsdf" % self.add("bsdf.ggx", inputs, node, suffix)

        def dielectric():
            diffuse = {"color": base}
            diffuse.update(normal)
            d = "@%s.bsdf" % self.add("bsdf.diffuse", diffuse, node, "diffuse")
            return "@%s.bsdf" % self.add("closure.add", {"a": d, "b": ggx(f0_dielectric, "specular")}, node,
                                         "dielectric")

        def metal():
            return ggx(_clamp01(base) if isinstance(base, list) else base, "metal")

        if metallic == 1.0:
            surface = metal()
        elif metallic == 0.0:
            surface = dielectric()
        else:
            surface = "@%s.bsdf" % self.add("closure.mix", {"a": dielectric(), "b": metal(), "t": metallic}, node,
                                            "metallic")
        coat = self._value(inp["Clearcoat"], self.ctx, "float")
        if coat != 0.0:
            coat_inputs = {"base": surface, "weight": coat, "ior": 1.5,
                           "roughness": self._value(inp["Clearcoat Roughness"], self.ctx, "float")}
            coat_normal = self.normal(node, "Clearcoat Normal")
            if "normal" in coat_normal:
                coat_inputs["normal"] = coat_normal["normal"]
            surface = "@%s.bsdf" % self.add("closure.coat", coat_inputs, node, "coat")
        strength = self._value(inp["Emission Strength"], self.ctx, "float")
        emission = self._value(inp["Emission"], self.ctx, "color3")
        if strength != 0.0 and emission != [0.0, 0.0, 0.0]:
            e = self.add("bsdf.emission", {"color": emission, "strength": strength}, node, "emission")
            surface = "@%s.bsdf" % self.add("closure.add", {"a": surface, "b": "@%s.bsdf" % e}, node, "emissive")
        return surface


class ImageFiles:
    """Resolves Blender images to files Specula can read: the image's own file, or a copy of a packed or
    generated image written once into the export's asset folder."""

    def __init__(self, asset_dir):
        self.asset_dir = asset_dir
        self.done = {}

    def image_file(self, image, where):
        if image.name in self.done:
            return self.done[image.name]
        if image.source == "TILED":
            raise ExportError("%s: UDIM image '%s' is not supported" % (where, image.name))
        path = None
        if image.packed_file is not None:
            ext = os.path.splitext(image.filepath)[1] or ".png"
            path = os.path.join(self.asset_dir, _safe(image.name) + ext)
            os.makedirs(self.asset_dir, exist_ok=True)
            with open(path, "wb") as f:
                f.write(image.packed_file.data)
        elif image.source == "FILE":
            import bpy
            path = os.path.normpath(bpy.path.abspath(image.filepath, library=image.library))
            if not os.path.isfile(path):
                raise ExportError("%s: image file of '%s' not found: %s" % (where, image.name, path))
        else:  # generated or painted: save a copy as 32-bit float EXR (no view transform)
            os.makedirs(self.asset_dir, exist_ok=True)
            path = os.path.join(self.asset_dir, _safe(image.name) + ".exr")
            copy = image.copy()
            try:
                copy.filepath_raw = path
                copy.file_format = "OPEN_EXR"
                copy.save()
            finally:
                import bpy
                bpy.data.images.remove(copy)
        self.done[image.name] = path
        return path


def _safe(name):
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "image"
