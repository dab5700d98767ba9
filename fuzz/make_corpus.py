#!/usr/bin/env python3
"""Seed corpora for the libFuzzer targets (docs/reliability.md), from examples/ and tests/ and a few small files
written here. Usage: make_corpus.py OUT_DIR  (writes OUT_DIR/<target>/...; deterministic)."""
import hashlib
import json
import os
import re
import struct
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MAX_SEED = 64 * 1024  # bigger seeds only slow every execution down


def put(out, target, data):
    if isinstance(data, str):
        data = data.encode()
    if len(data) > MAX_SEED:
        return
    d = os.path.join(out, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, hashlib.sha1(data).hexdigest()[:16]), "wb") as f:
        f.write(data)


def shrink_generated_maps(text):
    """'generate:<kind>:<size>:<seed>' with size over 64 becomes size 64 (see main)."""
    return re.sub(r'"generate:([a-z]+):([0-9]+):', lambda m: '"generate:%s:%d:' % (m.group(1), min(int(m.group(2)), 64)), text)


def json_files():
    for base in ("examples", "tests"):
        for dirpath, _, files in os.walk(os.path.join(ROOT, base)):
            for name in sorted(files):
                if name.endswith(".json"):
                    yield os.path.join(dirpath, name)


def obj_text():
    return ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
            "f 1/1/1 2/2/1 3/3/1 4/4/1\n")


def ply(fmt):
    head = ("ply\nformat %s 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n" % fmt).encode()
    verts = [(0, 0, 0, 0, 0, 1, 0, 0), (1, 0, 0, 0, 0, 1, 1, 0), (0, 1, 0, 0, 0, 1, 0, 1)]
    if fmt == "ascii":
        body = "".join(" ".join(str(x) for x in v) + "\n" for v in verts) + "3 0 1 2\n"
        return head + body.encode()
    e = "<" if fmt == "binary_little_endian" else ">"
    body = b"".join(struct.pack(e + "8f", *v) for v in verts) + struct.pack(e + "B3i", 3, 0, 1, 2)
    return head + body


def gltf(binary):
    pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    idx = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    buf = pos + idx
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                          "min": [0, 0, 0], "max": [1, 1, 0]},
                         {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                           {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
           "buffers": [{"byteLength": len(buf)}]}
    if not binary:
        import base64
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
        return json.dumps(doc).encode()
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    total = 12 + 8 + len(js) + 8 + len(buf)
    return (struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(js), b"JSON") + js +
            struct.pack("<I4s", len(buf), b"BIN\0") + buf)


GLTF_SPLIT = b"\n--8<--\n"  # fuzz_gltf_scene.cpp kSeparator: the scene, then buffer.bin, then image.png


def gltf_scene_seeds(out):
    """fuzz_gltf_scene: byte 0 picks .gltf/.glb; the parts are the scene, buffer.bin and image.png (issue 35)."""
    data = os.path.join(ROOT, "tests", "unit", "data", "gltf")
    with open(os.path.join(data, "triangle.gltf"), "rb") as f:
        put(out, "fuzz_gltf_scene", b"\0" + f.read())
    with open(os.path.join(data, "triangle_external.gltf"), "rb") as f:
        external = f.read().replace(b'"triangle.bin"', b'"buffer.bin"')
    with open(os.path.join(data, "triangle.bin"), "rb") as f:
        bin_data = f.read()
    with open(os.path.join(data, "checker.png"), "rb") as f:
        png = f.read()
    put(out, "fuzz_gltf_scene", b"\0" + external + GLTF_SPLIT + bin_data)
    # The same triangle with a base colour texture from image.png.
    doc = json.loads(external)
    doc["images"] = [{"uri": "image.png"}]
    doc["textures"] = [{"source": 0}]
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
    put(out, "fuzz_gltf_scene", b"\0" + json.dumps(doc).encode() + GLTF_SPLIT + bin_data + GLTF_SPLIT + png)
    put(out, "fuzz_gltf_scene", b"\1" + gltf(True))
    with open(os.path.join(data, "scene.gltf"), "rb") as f:  # its images are checker.png and bumps.png: both absent
        put(out, "fuzz_gltf_scene", b"\0" + f.read())


def images(out):
    try:
        import OpenImageIO as oiio
        import numpy as np
    except ImportError:
        print("make_corpus: no OpenImageIO Python module (python3-openimageio): image seeds from examples only")
        return
    import tempfile
    exts = ["png", "exr", "ppm", "hdr", "tga", "tif", "jpg"]
    px = (np.arange(8 * 8 * 3, dtype=np.float32).reshape(8, 8, 3) % 17) / 16.0
    with tempfile.TemporaryDirectory() as tmp:
        for i, ext in enumerate(exts):
            path = os.path.join(tmp, "seed." + ext)
            o = oiio.ImageOutput.create(path)
            fmt = "half" if ext == "exr" else ("float" if ext == "hdr" else "uint8")
            o.open(path, oiio.ImageSpec(8, 8, 3, fmt))
            o.write_image(px)
            o.close()
            with open(path, "rb") as f:
                data = f.read()
            put(out, "fuzz_image", bytes([i]) + data)
            put(out, "fuzz_image", bytes([i | 0x80]) + data)


def farm_pieces(out):
    """fuzz_merge seeds: pieces as `specula render` writes them (every specula:* attribute of a piece, a 'samples'
    layer for sample splits), 2x2 frames: one whole frame, and its two sample splits (input: 1 byte count - 1, each
    piece but the last preceded by its u32 length)."""
    try:
        import OpenImageIO as oiio
        import numpy as np
    except ImportError:
        print("make_corpus: no OpenImageIO Python module (python3-openimageio): no fuzz_merge seeds")
        return
    import tempfile

    def piece(path, split):
        channels = ["R", "G", "B", "depth.Z"] + (["samples.N"] if split else [])
        spec = oiio.ImageSpec(2, 2, len(channels), "float")
        spec.channelnames = channels
        attrs = {"scene_hash": "0ab84886150f14af", "frame": "3", "frame_size": "2x2", "crop": "0,0,2,2",
                 "spp": "4", "seed": "0", "sample_block": "2" if split else "4", "version": "0.1.0"}
        if split:
            attrs["sample_split"] = split
        for k, v in attrs.items():
            spec.attribute("specula:" + k, v)
        spec.attribute("compression", "zip")
        px = (np.arange(2 * 2 * len(channels), dtype=np.float32).reshape(2, 2, len(channels)) % 5) / 4.0
        if split:
            px[:, :, -1] = 2.0  # the split's 2 samples per pixel
        o = oiio.ImageOutput.create(path)
        o.open(path, spec)
        o.write_image(px)
        o.close()
        with open(path, "rb") as f:
            return f.read()

    with tempfile.TemporaryDirectory() as tmp:
        whole = piece(os.path.join(tmp, "whole.exr"), None)
        s0 = piece(os.path.join(tmp, "s0.exr"), "0/2")
        s1 = piece(os.path.join(tmp, "s1.exr"), "1/2")
    put(out, "fuzz_merge", b"\0" + whole)
    put(out, "fuzz_merge", b"\1" + struct.pack("<I", len(s0)) + s0 + s1)


def farm_plans(out):
    """fuzz_farm_plan seeds: plans as `specula farm submit` writes them ("@FARM@" is the farm folder)."""
    def plan(frames, tiles, splits):
        tasks = []
        for f in range(frames[0], frames[1] + 1):
            for ty in range(tiles[1]):
                for tx in range(tiles[0]):
                    for sp in range(splits):
                        tasks.append({"frame": f, "crop": [tx * 8 // tiles[0], ty * 6 // tiles[1], (tx + 1) * 8 // tiles[0],
                                                           (ty + 1) * 6 // tiles[1]],
                                      "split": [sp, splits], "piece": "pieces/f%04d_x%02d_y%02d_s%02d.exr" % (f, tx, ty, sp)})
        return json.dumps({"version": 1, "name": "scene", "scene": "/shared/scenes/scene.json", "dir": "@FARM@",
                           "specula": "/shared/bin/specula", "frames": list(frames), "tiles": list(tiles), "spp": 4,
                           "spp_split": splits, "retries": 2, "threads_per_task": 1, "attempts": 0, "size": [8, 6],
                           "tasks": tasks, "render_args": ["--seed", "3"]}, indent=1)
    put(out, "fuzz_farm_plan", plan((1, 1), (1, 1), 1))
    put(out, "fuzz_farm_plan", plan((1, 2), (2, 2), 2))


def main():
    out = sys.argv[1]
    for path in json_files():
        try:
            with open(path) as f:
                text = f.read()
            doc = json.loads(text)
        except (ValueError, UnicodeDecodeError):
            continue
        # Scenes whose materials prefilter a whole normal map (P-NDF manifolds, LTC normal-map tables) at 1024² spend
        # minutes under ASan before the first mutation (the kettle showcase timed out at 60 s). The scene and graph
        # targets cap textures at 256 a side (fuzz_common.h), so their generated maps are shrunk to 64 here: the
        # seeds still reach those nodes, in a fraction of a second.
        small = shrink_generated_maps(text)
        if isinstance(doc, dict) and ("shapes" in doc or "camera" in doc):
            put(out, "fuzz_scene", small)
        mats = doc.get("materials") if isinstance(doc, dict) else None
        if isinstance(mats, dict):
            for m in mats.values():
                if isinstance(m, dict) and "nodes" in m:
                    text_m = json.dumps(m)
                    put(out, "fuzz_graph", shrink_generated_maps(text_m))
                    put(out, "fuzz_glsl", text_m)
    put(out, "fuzz_mesh", b"\0" + obj_text().encode())
    for i, fmt in enumerate(("ascii", "binary_little_endian", "binary_big_endian")):
        put(out, "fuzz_mesh", b"\1" + ply(fmt))
    put(out, "fuzz_mesh", b"\2" + gltf(False))
    put(out, "fuzz_mesh", b"\3" + gltf(True))
    gltf_scene_seeds(out)
    for dirpath, _, files in os.walk(os.path.join(ROOT, "examples")):
        for name in sorted(files):
            ext = name.rsplit(".", 1)[-1].lower()
            path = os.path.join(dirpath, name)
            if ext in ("obj", "ply", "gltf", "glb"):
                with open(path, "rb") as f:
                    put(out, "fuzz_mesh", bytes([("obj", "ply", "gltf", "glb").index(ext)]) + f.read())
            if ext in ("png", "exr"):
                with open(path, "rb") as f:
                    put(out, "fuzz_image", bytes([("png", "exr").index(ext)]) + f.read())
    images(out)
    farm_pieces(out)
    farm_plans(out)
    for t in sorted(os.listdir(out)):
        print("make_corpus: %-11s %4d seeds" % (t, len(os.listdir(os.path.join(out, t)))))


if __name__ == "__main__":
    main()
