#!/usr/bin/env python3
"""Renders the showcase scenes of examples/showcase/ (glints: issue 11 item 6; P-NDF: issue 12 item 9; filtered GGX and LEAN) with the technique and with the naive
version beside it, writes the pictures to docs/gallery/ (JPEG, 960x540) and the render times into the generated
block of docs/gallery.md. Equal render time where the technique costs more per sample (the naive variant then gets
the spp that takes as long, measured on a quarter-size probe).

Usage: python3 tools/render_showcase.py [--build build] [--only NAME] [--quick]
  --quick   480x270 pictures into a scratch folder, docs untouched (a smoke run)."""
import argparse
import copy
import math
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from specula_validation import ROOT, page  # noqa: E402
from specula_validation.render import Renderer, rebase_files, tiled_uv_nodes  # noqa: E402

SHOW = os.path.join(ROOT, "examples", "showcase")


def with_input(scene, node_type, name, value):
    """A copy of the scene in which every node of node_type has its input `name` set to value."""
    s = copy.deepcopy(scene)
    for m in s["materials"].values():
        for n in m["nodes"].values():
            if n.get("type") == node_type:
                n.setdefault("inputs", {})[name] = value
    return s


def glint_ggaa_off(scene):
    """The naive glints: every bsdf.glint without geometric glint anti-aliasing (C21 §4 off)."""
    return with_input(scene, "bsdf.glint", "ggaa", "off")


def glints_without_flakes(scene):
    """The naive flakes: every bsdf.glint with a flake_size counts its microfacets (C20) at every distance, at the same
    density (log_density = ln(1 / flake_size^2), what the node counts with beyond one flake per pixel): one-pixel
    grain where the flakes would be platelets of their size."""
    s = copy.deepcopy(scene)
    for m in s["materials"].values():
        for n in m["nodes"].values():
            inputs = n.get("inputs", {})
            if n.get("type") == "bsdf.glint" and inputs.get("flake_size", 0) > 0:
                inputs["log_density"] = -2.0 * math.log(inputs.pop("flake_size"))
    return s


def sampled_lights(scene):
    """The naive area lights: quad lights point-sampled (render.area_lights 'sampled')."""
    s = copy.deepcopy(scene)
    s["render"]["area_lights"] = "sampled"
    return s


# Roughness of the naive P-NDF stand-in: near-mirror GGX (alpha = 0.0025), the plain normal mapping the P-NDF converges
# to as the normal map's own detail, rather than a roughness, makes the highlight.
NAIVE_PNDF_ROUGHNESS = 0.05


def nodes_to_replace(scene, node_type):
    """A copy of the scene, and (the material's nodes, node id, inputs) of each node of node_type in it, listed before
    the caller replaces them and adds nodes in place."""
    s = copy.deepcopy(scene)
    return s, [(m["nodes"], nid, n.get("inputs", {})) for m in s["materials"].values()
               for nid, n in list(m["nodes"].items()) if n.get("type") == node_type]


def plain_normal_mapping(scene):
    """The naive P-NDF: every bsdf.glint_pndf becomes the same map as plain normal mapping (texture.image raw ->
    texture.normal_map) on near-mirror GGX with the same Fresnel; its tiling (uv_scale) through tiled uv nodes."""
    s, found = nodes_to_replace(scene, "bsdf.glint_pndf")
    for nodes, nid, inp in found:
        tiles = inp.get("uv_scale", 1)
        uvn, look = tiled_uv_nodes([tiles, tiles])
        for k, v in uvn.items():
            nodes[f"{nid}_{k}"] = {"type": v["type"], "inputs": {
                kk: (f"@{nid}_{vv[1:]}" if isinstance(vv, str) and vv.startswith("@") else vv)
                for kk, vv in v.get("inputs", {}).items()}}
        wire = {k: f"@{nid}_{v[1:]}" for k, v in look.items()}
        nodes[f"{nid}_img"] = {"type": "texture.image", "inputs": dict(file=inp["normal_map"], colorspace="raw",
                                                                      **wire)}
        nodes[f"{nid}_nm"] = {"type": "texture.normal_map", "inputs": {"color": f"@{nid}_img.color"}}
        ggx = {"roughness": NAIVE_PNDF_ROUGHNESS, "normal": f"@{nid}_nm.normal"}
        for k in ("weight", "fresnel", "f0", "ior", "eta", "k"):
            if k in inp:
                ggx[k] = inp[k]
        nodes[nid] = {"type": "bsdf.ggx", "inputs": ggx}
    return s


def unfiltered_ggx(scene):
    """The naive filtered GGX: every bsdf.ggx_filtered with filter none, i.e. plain normal-mapped GGX."""
    return with_input(scene, "bsdf.ggx_filtered", "filter", "none")


def mip_normals(scene):
    """The naive LEAN mapping: every texture.lean becomes the same map read as MIP-filtered normals (texture.image raw,
    same uv and footprint -> texture.normal_map), which feeds the lobe's normal; the lobe loses the slope moments."""
    s, found = nodes_to_replace(scene, "texture.lean")
    for nodes, nid, inp in found:
        look = {k: inp[k] for k in ("uv", "duvdx", "duvdy") if k in inp}
        nodes[nid] = {"type": "texture.image", "inputs": dict(file=inp["file"], colorspace="raw", **look)}
        nodes[f"{nid}_nm"] = {"type": "texture.normal_map", "inputs": {"color": f"@{nid}.color"}}
        for other in nodes.values():
            oin = other.get("inputs", {})
            if oin.get("slope") == f"@{nid}.slope" or oin.get("covariance") == f"@{nid}.covariance":
                oin.pop("slope", None)
                oin.pop("covariance", None)
                oin["normal"] = f"@{nid}_nm.normal"
    return s


# name, scene file, (technique label, naive label, naive transform, equal time?)
SHOWCASES = [
    ("carpaint", "glint-carpaint.json", "glints + GGAA under a clear coat", "GGAA off", glint_ggaa_off, False),
    ("snow", "glint-snow.json", "glints + GGAA", "GGAA off", glint_ggaa_off, False),
    # Issue 38 item 3: flakes of their size against the same density counted per pixel. The counted glints integrate
    # the quad light (quad_lights "integrated"; the flakes sample it where they show), so the naive side is the slower.
    ("glitter", "glint-glitter.json", "flakes (flake_size 0.03)", "the same density counted per pixel (no flakes)",
     glints_without_flakes, False),
    # Equal spp: the quarter-size probes of equal-time mode are dominated by the P-NDF's fixed costs (manifold and
    # masking-fit build, ~1.6 s), so they misjudge the full-size ratio; the table gives both times instead.
    ("pndf-plate", "pndf-plate.json", "P-NDF glints (bsdf.glint_pndf)", "plain normal mapping, GGX roughness 0.05",
     plain_normal_mapping, False),
    ("pndf-kettle", "pndf-kettle.json", "P-NDF glints (bsdf.glint_pndf)", "plain normal mapping, GGX roughness 0.05",
     plain_normal_mapping, False),
    ("filtered-ggx", "filtered-ggx-hall.json", "filtered GGX (projected_approx)", "filter none (normal-mapped GGX)",
     unfiltered_ggx, True),
    ("lean", "lean-brushed.json", "LEAN mapping with slope correlation", "MIP-filtered normals", mip_normals, True),
]

BEGIN, END = "<!-- render_showcase: begin -->", "<!-- render_showcase: end -->"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--only", action="append", help="render only these showcases (by name)")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    specula = os.path.join(a.build, "bin", "specula")
    if shutil.which("oiiotool") is None:
        raise SystemExit("FAIL: oiiotool (Debian: openimageio-tools) is needed to write the JPEG pictures")
    work = tempfile.mkdtemp(prefix="specula-showcase-")
    rnd = Renderer(specula, work, scene_dir=SHOW)
    gal = os.path.join(ROOT, "docs", "gallery") if not a.quick else os.path.join(work, "gallery")
    os.makedirs(gal, exist_ok=True)
    times_path = os.path.join(ROOT, "docs", "gallery", "showcase_times.json")
    times = json.load(open(times_path)) if os.path.exists(times_path) else {}
    full = None if not a.quick else "480x270"
    for name, file, tech, naive, transform, equal_time in SHOWCASES:
        if a.only and name not in a.only:
            continue
        scene = json.load(open(os.path.join(SHOW, file)))
        spp = scene["render"]["spp"]
        exr, t = rnd.render(scene, name, resolution=full)
        naive_scene = transform(scene)
        naive_spp = spp
        if equal_time:  # the spp the naive variant renders in the technique's time (quarter-size probes of both)
            w, h = scene["render"]["width"] // 4, scene["render"]["height"] // 4
            _, tp = rnd.render(scene, name + "_probe", resolution=f"{w}x{h}")
            _, tn = rnd.render(naive_scene, name + "_naive_probe", resolution=f"{w}x{h}")
            naive_spp = max(1, int(round(spp * tp / max(tn, 1e-6))))
        exr_n, tn_full = rnd.render(naive_scene, name + "_naive", spp=naive_spp, resolution=full)
        for src, dst in ((exr, f"{name}.jpg"), (exr_n, f"{name}_naive.jpg")):
            subprocess.run(["oiiotool", src[:-4] + ".png", "--compression", "jpeg:92", "-o", os.path.join(gal, dst)],
                           check=True)
        times[name] = {"scene": file, "spp": spp, "seconds": t, "naive_spp": naive_spp, "naive_seconds": tn_full,
                       "technique": tech, "naive": naive}
        print(f"{name}: {t:.1f} s at {spp} spp; naive ({naive}) {tn_full:.1f} s at {naive_spp} spp", flush=True)
    if a.quick:
        print("quick run: pictures in", gal)
        return
    with open(times_path, "w") as f:
        json.dump(times, f, indent=1, sort_keys=True)
    rows = []
    for name, file, *_ in SHOWCASES:
        if name in times:
            r = times[name]
            rows.append([name, f"`examples/showcase/{r['scene']}`", f"{r['technique']}, {r['spp']} spp",
                         f"{r['seconds']:.1f} s", f"{r['naive']}, {r['naive_spp']} spp", f"{r['naive_seconds']:.1f} s"])
    block = ["Render times on this machine (2 cores, `python3 tools/render_showcase.py`, 960 × 540):", ""] + \
        page.table(["showcase", "scene", "technique", "time", "naive", "time"], rows)
    gm = os.path.join(ROOT, "docs", "gallery.md")
    text = page.replace_block(open(gm).read(), BEGIN, END, "\n".join(block))
    with open(gm + ".tmp", "w") as f:
        f.write(text)
    os.replace(gm + ".tmp", gm)


if __name__ == "__main__":
    main()
