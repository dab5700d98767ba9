#!/usr/bin/env python3
"""Scene schema test: docs/scene-schema.json and the scene loader must agree.

Usage: test_schema.py SPECULA_BINARY SOURCE_DIR

Checks, one output line each:
  * the schema is a valid JSON Schema (draft 2020-12);
  * every examples/*.json and every complete scene in a ```json block of docs/scene-format.md validates against
    the schema, and `specula info` accepts it;
  * extra valid scenes that use every key, every shape and light type, material graphs (textures, normal map,
    closure.add, emission) and the less common value forms (single numbers for vectors, {"ref": ...}, matrices,
    environment maps) pass both;
  * a catalogue of invalid scenes (unknown keys, wrong enums, out-of-range numbers, missing required keys,
    wrong types, mutually exclusive keys) is rejected by the schema AND by `specula info` with exit code 1,
    whose message names the expected JSON pointer;
  * drift guard: for every object the loader reads with a fixed key list (top level, render, color, camera,
    transform, each shape and light type, {"ref"}) the loader's own "valid keys: ..." list equals the schema's
    properties, and its "expected one of / valid types" lists equal the schema's enums;
  * scenes only the loader can reject (unknown node types/inputs, missing files, degenerate geometry, ...) are
    accepted by the schema and rejected by `specula info` with exit code 1 at the expected pointer.
Ends with 'N passed, M failed'; exits 1 if anything failed.
"""
import copy
import glob
import json
import os
import re
import subprocess
import sys
import tempfile

try:
    import jsonschema
    from jsonschema.exceptions import best_match
except ImportError:  # pragma: no cover - reported as a failure, not a crash
    jsonschema = None

PASSED = 0
FAILED = 0


def check(ok, text):
    global PASSED, FAILED
    if ok:
        PASSED += 1
    else:
        FAILED += 1
    print(("PASS " if ok else "FAIL ") + text, flush=True)
    return ok


def pointer(path):
    return "/" + "/".join(str(p).replace("~", "~0").replace("/", "~1") for p in path)


# ---- scene builders ----------------------------------------------------------------------------------------------

BASE = {
    "camera": {"position": [0, -5, 1], "look_at": [0, 0, 1]},
    "materials": {"grey": {"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": 0.5}}}, "output": "@d.bsdf"}},
    "shapes": [{"type": "sphere", "material": "grey"}],
}


def scene(**top):
    """BASE with top-level keys replaced (value None removes the key)."""
    s = copy.deepcopy(BASE)
    for k, v in top.items():
        if v is None:
            s.pop(k, None)
        else:
            s[k] = v
    return s


def shape(**kv):
    d = {"type": "sphere", "material": "grey"}
    d.update(kv)
    return scene(shapes=[{k: v for k, v in d.items() if v is not None}])


def material(m):
    return scene(materials={"grey": m})


def light(l):
    return scene(lights=[l])


def camera(**kv):
    d = {"position": [0, -5, 1], "look_at": [0, 0, 1]}
    d.update(kv)
    return scene(camera={k: v for k, v in d.items() if v is not None})


# Valid scenes beyond the examples: every type and value form the loader accepts.
VALID = [
    ("minimal", {"camera": {"position": [0, -5, 1], "look_at": [0, 0, 1]}, "shapes": []}),
    ("everything", {
        "$schema": "../docs/scene-schema.json",
        "version": 1,
        "description": "every key",
        "render": {"width": 64, "height": 48, "spp": 1, "seed": 7, "tile": 16, "integrator": "direct", "max_depth": 0,
                   "filter": "gaussian", "gaussian_sigma2": 0.25, "pixel_center": True,
                   "clamp_indirect": 10, "shadow_map_size": 256},
        "color": {"config": "builtin", "view": "Filmic", "exposure": -1.5},
        "camera": {"type": "perspective", "position": [0, -5, 1], "look_at": [0, 0, 1], "up": [0, 0, 1], "fov": 50,
                   "fov_axis": "y", "aperture_radius": 0.05, "focus_distance": 4},
        "materials": {
            "tex": {"doc": "sRGB texture times a colour", "nodes": {
                "t": {"type": "texture.image", "inputs": {"file": "tex.ppm", "colorspace": "sRGB - Texture",
                                                          "wrap": "clamp"}},
                "d": {"type": "bsdf.diffuse", "inputs": {"color": "@t.color"}, "doc": "base"}},
                "output": "@d.bsdf"},
            "gold": {"nodes": {"g": {"type": "bsdf.ggx", "inputs": {
                "roughness": 0.2, "fresnel": "conductor", "eta": [0.143, 0.374, 1.442], "k": [3.983, 2.385, 1.603]}}},
                "output": "@g.bsdf"},
            "coat": {"nodes": {
                "n": {"type": "texture.image", "inputs": {"file": "tex.ppm", "colorspace": "raw"}},
                "nm": {"type": "texture.normal_map", "inputs": {"color": "@n.color", "strength": 0.5}},
                "base": {"type": "bsdf.diffuse", "inputs": {"color": [0.2, 0.1, 0.05]}},
                "spec": {"type": "bsdf.ggx", "inputs": {"roughness": 0.5, "anisotropy": 0.5, "fresnel": "dielectric",
                                                        "ior": 1.45, "normal": "@nm.normal"}},
                "sum": {"type": "closure.add", "inputs": {"a": "@base.bsdf", "b": "@spec.bsdf"}}},
                "output": "@sum.bsdf"},
            "white_ggx": {"nodes": {"g": {"type": "bsdf.ggx", "inputs": {"fresnel": "none", "weight": 1}}},
                          "output": "@g.bsdf"},
            "glow": {"nodes": {"e": {"type": "bsdf.emission", "inputs": {"color": [1, 0.5, 0.2], "strength": 10}}},
                     "output": "@e.bsdf"},
        },
        "shapes": [
            {"type": "sphere", "name": "s", "radius": 0.5, "segments": 16, "material": {"ref": "gold"},
             "transform": {"translate": [0, 0, 0.5], "rotate": 45, "scale": 2}},
            {"type": "quad", "size": 3, "material": "tex",
             "transform": {"matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -1, 0, 0, 0, 1]}},
            {"type": "disk", "radius": 0.3, "material": "glow", "transform": {"scale": [1, -1, 1]}},
            {"type": "cylinder", "radius": 0.1, "height": 2, "material": "coat"},
            {"type": "torus", "major_radius": 1, "minor_radius": 0.1, "segments": 4096, "material": "white_ggx"},
            {"type": "mesh", "file": "tri.obj", "material": "tex"},
            {"type": "mesh", "file": "tri.ply", "material": "tex"},
        ],
        "lights": [
            {"type": "point", "name": "p", "position": [1, 1, 3], "intensity": 10, "color": 0.9},
            {"type": "spot", "position": [0, -2, 3], "look_at": [0, 0, 0], "cone_angle": 180, "blend": 0,
             "power": 100},
            {"type": "directional", "direction": [0, 0, -1], "irradiance": 2, "color": [1, 0.9, 0.8]},
            {"type": "quad", "position": [0, 0, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "size": [1, 2],
             "radiance": 5, "two_sided": True},
            {"type": "quad", "position": [2, 0, 3], "look_at": [0, 0, 0], "size": 0.5, "power": 50},
            {"type": "environment", "file": "tex.ppm", "colorspace": "lin_rec709", "rotation": -90, "strength": 0.5},
            {"type": "environment", "color": [0.1, 0.1, 0.2]},
        ],
    }),
]

# (name, scene as a dict or raw text, JSON pointer the loader must report)
INVALID = [
    # unknown keys (with a nearest-name suggestion in the loader's message)
    ("unknown_top_key", scene(light=[]), "/light"),
    ("unknown_render_key", scene(render={"samples": 4}), "/render/samples"),
    ("unknown_color_key", scene(color={"display": "sRGB"}), "/color/display"),
    ("unknown_camera_key", camera(fvo=40), "/camera/fvo"),
    ("unknown_shape_key", shape(radus=2), "/shapes/0/radus"),
    ("key_of_another_shape_type", shape(size=[1, 1]), "/shapes/0/size"),
    ("unknown_transform_key", shape(transform={"translation": [0, 0, 1]}), "/shapes/0/transform/translation"),
    ("old_style_material", material({"type": "diffuse", "color": 0.5}), "/materials/grey/color"),
    ("unknown_material_key", material({"nodes": {}, "output": "@d.bsdf", "outputs": 1}), "/materials/grey/outputs"),
    ("unknown_node_key", material({"nodes": {"d": {"type": "bsdf.diffuse", "input": {}}}, "output": "@d.bsdf"}),
     "/materials/grey/nodes/d/input"),
    ("unknown_light_key", light({"type": "point", "position": [0, 0, 3], "power": 10, "radius": 1}),
     "/lights/0/radius"),
    ("textures_top_level_key", scene(textures={"t": {"file": "tex.ppm", "colorspace": "raw"}}), "/textures"),
    ("material_ref_extra_key", shape(material={"ref": "grey", "name": "x"}), "/shapes/0/material/name"),
    # wrong enum values
    ("bad_version", scene(version=2), "/version"),
    ("unknown_integrator", scene(render={"integrator": "pathh"}), "/render/integrator"),
    ("unknown_filter", scene(render={"filter": "gauss"}), "/render/filter"),
    ("unknown_camera_type", camera(type="orthographic"), "/camera/type"),
    ("unknown_fov_axis", camera(fov_axis="z"), "/camera/fov_axis"),
    ("unknown_view", scene(color={"view": "filmic"}), "/color/view"),
    ("unknown_shape_type", shape(type="sphre"), "/shapes/0/type"),
    ("unknown_light_type", light({"type": "area", "position": [0, 0, 3]}), "/lights/0/type"),
    ("shape_type_not_string", shape(type=3), "/shapes/0/type"),
    # out of range
    ("width_zero", scene(render={"width": 0}), "/render/width"),
    ("spp_too_large", scene(render={"spp": 2000000}), "/render/spp"),
    ("seed_negative", scene(render={"seed": -1}), "/render/seed"),
    ("max_depth_too_large", scene(render={"max_depth": 1025}), "/render/max_depth"),
    ("sigma2_zero", scene(render={"gaussian_sigma2": 0}), "/render/gaussian_sigma2"),
    ("pixel_center_needs_spp_1", scene(render={"spp": 4, "pixel_center": True}), "/render/pixel_center"),
    ("exposure_too_large", scene(color={"exposure": 31}), "/color/exposure"),
    ("fov_too_large", camera(fov=200), "/camera/fov"),
    ("aperture_negative", camera(aperture_radius=-0.1), "/camera/aperture_radius"),
    ("sphere_radius_negative", shape(radius=-1), "/shapes/0/radius"),
    ("segments_too_few", shape(segments=4), "/shapes/0/segments"),
    ("quad_size_zero", shape(type="quad", size=[1, 0]), "/shapes/0/size/1"),
    ("scale_zero", shape(transform={"scale": 0}), "/shapes/0/transform/scale"),
    ("light_color_negative", light({"type": "point", "position": [0, 0, 3], "power": 1, "color": [0.5, -0.1, 0.5]}),
     "/lights/0/color/1"),
    ("point_power_negative", light({"type": "point", "position": [0, 0, 3], "power": -5}), "/lights/0/power"),
    ("spot_cone_zero", light({"type": "spot", "position": [0, 0, 3], "look_at": [0, 0, 0], "cone_angle": 0,
                              "power": 10}), "/lights/0/cone_angle"),
    ("spot_blend_above_one", light({"type": "spot", "position": [0, 0, 3], "look_at": [0, 0, 0], "blend": 2,
                                    "power": 10}), "/lights/0/blend"),
    ("env_rotation_too_large", light({"type": "environment", "file": "tex.ppm", "colorspace": "raw", "rotation": 4000}),
     "/lights/0/rotation"),
    ("clamp_indirect_negative", scene(render={"clamp_indirect": -1}), "/render/clamp_indirect"),
    ("shadow_map_size_too_small", scene(render={"shadow_map_size": 8}), "/render/shadow_map_size"),
    ("shadow_map_size_too_large", scene(render={"shadow_map_size": 8193}), "/render/shadow_map_size"),
    ("shadow_map_size_not_integer", scene(render={"shadow_map_size": 512.5}), "/render/shadow_map_size"),
    # missing required keys
    ("missing_camera", scene(camera=None), "/"),
    ("missing_shapes", scene(shapes=None), "/"),
    ("camera_missing_look_at", camera(look_at=None), "/camera"),
    ("shape_missing_type", scene(shapes=[{"material": "grey"}]), "/shapes/0"),
    ("shape_missing_material", shape(material=None), "/shapes/0"),
    ("mesh_missing_file", shape(type="mesh"), "/shapes/0"),
    ("material_missing_nodes", material({"output": "@d.bsdf"}), "/materials/grey/nodes"),
    ("material_missing_output", material({"nodes": {"d": {"type": "bsdf.diffuse"}}}), "/materials/grey"),
    ("node_missing_type", material({"nodes": {"d": {"inputs": {}}}, "output": "@d.bsdf"}),
     "/materials/grey/nodes/d/type"),
    ("point_missing_power", light({"type": "point", "position": [0, 0, 3]}), "/lights/0"),
    ("point_missing_position", light({"type": "point", "power": 10}), "/lights/0"),
    ("directional_missing_irradiance", light({"type": "directional", "direction": [0, 0, -1]}), "/lights/0"),
    ("env_file_missing_colorspace", light({"type": "environment", "file": "tex.ppm"}), "/lights/0"),
    # wrong types and wrong shapes of values
    ("spp_not_integer", scene(render={"spp": 1.5}), "/render/spp"),
    ("tile_string", scene(render={"tile": "32"}), "/render/tile"),
    ("pixel_center_number", scene(render={"pixel_center": 1}), "/render/pixel_center"),
    ("render_not_object", scene(render=[640, 480]), "/render"),
    ("position_string", camera(position="origin"), "/camera/position"),
    ("up_two_numbers", camera(up=[0, 1]), "/camera/up"),
    ("shapes_not_array", scene(shapes={"type": "sphere"}), "/shapes"),
    ("lights_not_array", scene(lights={"type": "point"}), "/lights"),
    ("materials_not_object", scene(materials=[{"type": "diffuse"}]), "/materials"),
    ("material_is_number", shape(material=5), "/shapes/0/material"),
    ("shape_name_number", shape(name=5), "/shapes/0/name"),
    ("material_not_object", scene(materials={"grey": "diffuse"}), "/materials/grey"),
    ("nodes_not_object", material({"nodes": [], "output": "@d.bsdf"}), "/materials/grey/nodes"),
    ("node_type_not_string", material({"nodes": {"d": {"type": 5}}, "output": "@d.bsdf"}),
     "/materials/grey/nodes/d/type"),
    ("node_inputs_not_object", material({"nodes": {"d": {"type": "bsdf.diffuse", "inputs": [0.5]}},
                                         "output": "@d.bsdf"}), "/materials/grey/nodes/d/inputs"),
    ("node_input_boolean", material({"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": True}}},
                                     "output": "@d.bsdf"}), "/materials/grey/nodes/d/inputs/color"),
    ("node_input_four_numbers", material({"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": [1, 1, 1, 1]}}},
                                          "output": "@d.bsdf"}), "/materials/grey/nodes/d/inputs/color"),
    ("output_not_reference", material({"nodes": {"d": {"type": "bsdf.diffuse"}}, "output": "d.bsdf"}),
     "/materials/grey/output"),
    ("two_sided_string", light({"type": "quad", "position": [0, 0, 3], "look_at": [0, 0, 0], "power": 10,
                                "two_sided": "yes"}), "/lights/0/two_sided"),
    ("matrix_12_numbers", shape(transform={"matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]}),
     "/shapes/0/transform/matrix"),
    # mutually exclusive keys
    ("power_and_intensity", light({"type": "point", "position": [0, 0, 3], "power": 10, "intensity": 1}),
     "/lights/0/intensity"),
    ("quad_power_and_radiance", light({"type": "quad", "position": [0, 0, 3], "look_at": [0, 0, 0], "power": 10,
                                       "radiance": 1}), "/lights/0/radiance"),
    ("matrix_and_translate", shape(transform={"translate": [0, 0, 1],
                                              "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}),
     "/shapes/0/transform/matrix"),
]


# Valid for the schema, rejected by the loader (exit 1): the checks docs/scene-format.md says only the loader makes.
LOADER_ONLY = [
    ("unknown_node_type", material({"nodes": {"d": {"type": "bsdf.difuse"}}, "output": "@d.bsdf"}),
     "/materials/grey/nodes/d/type"),
    ("unknown_node_input", material({"nodes": {"g": {"type": "bsdf.ggx", "inputs": {"roughnes": 0.2}}},
                                     "output": "@g.bsdf"}), "/materials/grey/nodes/g/inputs/roughnes"),
    ("unknown_enum_value", material({"nodes": {"g": {"type": "bsdf.ggx", "inputs": {"fresnel": "metal"}}},
                                     "output": "@g.bsdf"}), "/materials/grey/nodes/g/inputs/fresnel"),
    ("reference_to_unknown_node", material({"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": "@t.color"}}},
                                            "output": "@d.bsdf"}), "/materials/grey/nodes/d/inputs/color"),
    ("unknown_material_name", shape(material="gray"), "/shapes/0/material"),
    ("texture_file_missing", material({"nodes": {
        "t": {"type": "texture.image", "inputs": {"file": "nope.png", "colorspace": "raw"}},
        "d": {"type": "bsdf.diffuse", "inputs": {"color": "@t.color"}}}, "output": "@d.bsdf"}),
     "/materials/grey/nodes/t/inputs/file"),
    ("mesh_file_missing", shape(type="mesh", file="nope.obj"), "/shapes/0/file"),
    ("env_unknown_colorspace", light({"type": "environment", "file": "tex.ppm", "colorspace": "srgbb"}),
     "/lights/0/colorspace"),
    ("camera_look_at_equals_position", camera(look_at=[0, -5, 1]), "/camera/look_at"),
    ("torus_minor_not_smaller", shape(type="torus", major_radius=1, minor_radius=1), "/shapes/0/minor_radius"),
    ("singular_matrix", shape(transform={"matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1]}),
     "/shapes/0/transform/matrix"),
    ("too_many_pixels", scene(render={"width": 16384, "height": 16384}), "/render/width"),
]


# Drift guard probes: (label, scene with an unknown key or enum value at one place, schema location).
# The loader's message lists the valid keys/values; the schema must list exactly the same.
def key_probes():
    p = [("top level", scene(zzz_probe=1), ("properties",)),
         ("render", scene(render={"zzz_probe": 1}), ("$defs", "render", "properties")),
         ("color", scene(color={"zzz_probe": 1}), ("$defs", "color_settings", "properties")),
         ("camera", camera(zzz_probe=1), ("$defs", "camera", "properties")),
         ("transform", shape(transform={"zzz_probe": 1}), ("$defs", "transform", "properties")),
         ("material reference", shape(material={"ref": "grey", "zzz_probe": 1}),
          ("$defs", "materialRef", "oneOf", 1, "properties"))]
    for t in ["sphere", "quad", "disk", "cylinder", "torus", "mesh"]:
        p.append((f"shape {t}", shape(type=t, zzz_probe=1), ("$defs", f"shape_{t}", "properties")))
    for t in ["point", "spot", "directional", "quad", "environment"]:
        p.append((f"light {t}", light({"type": t, "zzz_probe": 1}), ("$defs", f"light_{t}", "properties")))
    return p


def enum_probes():
    p = [(f"render.{k}", scene(render={k: "zzz_probe"}), ("$defs", "render", "properties", k, "enum"))
         for k in ["integrator", "filter", "derivatives"]]
    p += [(f"camera.{k}", camera(**{k: "zzz_probe"}), ("$defs", "camera", "properties", k, "enum"))
          for k in ["type", "fov_axis"]]
    p += [("shape type", shape(type="zzz_probe"), ("$defs", "shape", "properties", "type", "enum")),
          ("light type", light({"type": "zzz_probe"}), ("$defs", "light", "properties", "type", "enum"))]
    return p


def listed(message, lead):
    m = re.search(re.escape(lead) + r" (.*?)(?: \(did you mean '.*'\?\))?$", message)
    return None if m is None else {x.strip() for x in m.group(1).split(",")}


def write_fixtures(d):
    # 2x2 sRGB texture (PPM), a one-triangle OBJ and PLY with uvs.
    with open(os.path.join(d, "tex.ppm"), "w") as f:
        f.write("P3\n2 2\n255\n255 0 0  0 255 0\n0 0 255  255 255 255\n")
    with open(os.path.join(d, "tri.obj"), "w") as f:
        f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n")
    with open(os.path.join(d, "tri.ply"), "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                "property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\n"
                "end_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n")


def run_info(specula, path, env):
    try:
        p = subprocess.run([specula, "info", path], capture_output=True, text=True, env=env, timeout=120)
    except (OSError, subprocess.TimeoutExpired) as e:
        return -1, str(e)
    return p.returncode, (p.stderr.strip().splitlines() or [""])[-1]


def main():
    if len(sys.argv) != 3:
        print("usage: test_schema.py SPECULA_BINARY SOURCE_DIR", file=sys.stderr)
        return 2
    specula, src = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if jsonschema is None:
        check(False, "python3-jsonschema is installed (apt-get install python3-jsonschema)")
        print(f"{PASSED} passed, {FAILED} failed")
        return 1

    schema_path = os.path.join(src, "docs", "scene-schema.json")
    try:
        with open(schema_path) as f:
            schema = json.load(f)
        jsonschema.Draft202012Validator.check_schema(schema)
        ok, why = True, ""
    except Exception as e:  # noqa: BLE001 - any problem with the schema file is one failed check
        ok, why = False, f": {e}"
    check(ok, f"schema {os.path.relpath(schema_path, src)} is a valid draft 2020-12 JSON Schema{why}")
    if not ok:
        print(f"{PASSED} passed, {FAILED} failed")
        return 1
    validator = jsonschema.Draft202012Validator(schema)

    with tempfile.TemporaryDirectory(prefix="specula-schema-") as tmp:
        env = dict(os.environ)
        env["SPECULA_CACHE_DIR"] = os.path.join(tmp, "cache")  # texture MIP cache stays in the temp dir
        env.setdefault("SPECULA_DATA_DIR", os.path.join(src, "data"))
        write_fixtures(tmp)

        def accepted(label, path, doc):
            errors = sorted(validator.iter_errors(doc), key=lambda e: list(e.absolute_path))
            detail = "; ".join(f"{pointer(e.absolute_path)}: {e.message}" for e in errors[:3])
            check(not errors, f"{label}: schema accepts" + (f" (but: {detail})" if errors else ""))
            rc, msg = run_info(specula, path, env)
            check(rc == 0, f"{label}: specula info exits 0" + ("" if rc == 0 else f" (got {rc}: {msg})"))

        examples = sorted(glob.glob(os.path.join(src, "examples", "*.json")))
        check(len(examples) > 0, f"found {len(examples)} examples/*.json")
        for path in examples:
            with open(path) as f:
                doc = json.load(f)
            accepted(os.path.relpath(path, src), path, doc)

        doc_path = os.path.join(src, "docs", "scene-format.md")
        blocks = []
        if os.path.exists(doc_path):
            with open(doc_path) as f:
                blocks = re.findall(r"```json\n(.*?)```", f.read(), re.S)
        scenes = []
        for i, b in enumerate(blocks):
            try:
                doc = json.loads(b)
            except ValueError:
                continue  # fragments, not scenes
            if isinstance(doc, dict) and "camera" in doc and "shapes" in doc:
                scenes.append((i, doc))
        check(len(scenes) > 0, f"docs/scene-format.md has {len(scenes)} complete example scene(s)")
        for i, doc in scenes:
            path = os.path.join(tmp, f"doc_example_{i}.json")
            with open(path, "w") as f:
                json.dump(doc, f, indent=1)
            accepted(f"docs/scene-format.md json block {i + 1}", path, doc)

        for name, doc in VALID:
            path = os.path.join(tmp, f"valid_{name}.json")
            with open(path, "w") as f:
                json.dump(doc, f, indent=1)
            accepted(f"valid/{name}", path, doc)

        def at(path):
            node = schema
            for k in path:
                node = node[k]
            return node

        for label, doc, where in key_probes():
            path = os.path.join(tmp, "probe.json")
            with open(path, "w") as f:
                json.dump(doc, f)
            rc, msg = run_info(specula, path, env)
            loader = listed(msg, "valid keys:")
            ours = set(at(where)) if loader is not None else None
            ok = rc == 1 and loader is not None and loader == ours
            detail = "" if ok else (f" (loader: exit {rc}: {msg})" if loader is None else
                                    f" (only in loader: {sorted(loader - ours)}, only in schema: {sorted(ours - loader)})")
            check(ok, f"keys/{label}: schema properties = loader's valid keys" + detail)

        for label, doc, where in enum_probes():
            path = os.path.join(tmp, "probe.json")
            with open(path, "w") as f:
                json.dump(doc, f)
            rc, msg = run_info(specula, path, env)
            loader = listed(msg, "expected one of:") or listed(msg, "valid types:")
            ours = set(at(where)) if loader is not None else None
            ok = rc == 1 and loader is not None and loader == ours
            detail = "" if ok else (f" (loader: exit {rc}: {msg})" if loader is None else
                                    f" (only in loader: {sorted(loader - ours)}, only in schema: {sorted(ours - loader)})")
            check(ok, f"enum/{label}: schema enum = loader's values" + detail)

        def refused_by_loader(label, name, doc, ptr):
            """Writes doc, checks `specula info` refuses it at ptr; returns the schema's best error (None: accepted)."""
            path = os.path.join(tmp, f"{label.replace('-', '_')}_{name}.json")
            with open(path, "w") as f:
                json.dump(doc, f, indent=1)
            rc, msg = run_info(specula, path, env)
            ok = rc == 1 and msg.startswith(f"specula: error: {ptr}: ")
            check(ok, f"{label}/{name}: specula info exits 1 at {ptr}" + ("" if ok else f" (got exit {rc}: {msg})"))
            return best_match(validator.iter_errors(doc))

        for name, doc, ptr in INVALID:
            err = refused_by_loader("invalid", name, doc, ptr)
            check(err is not None, f"invalid/{name}: schema rejects" +
                  (f" at {pointer(err.absolute_path)}: {err.message}" if err is not None else " (but it was accepted)"))

        for name, doc, ptr in LOADER_ONLY:
            err = refused_by_loader("loader-only", name, doc, ptr)
            check(err is None, f"loader-only/{name}: schema accepts (the loader alone checks this)" +
                  (f" (but it rejects at {pointer(err.absolute_path)}: {err.message})" if err is not None else ""))

    print(f"{PASSED} passed, {FAILED} failed")
    return 0 if FAILED == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
