# A minimal glTF 2.0 writer for exported meshes: one triangle primitive with POSITION, NORMAL, TEXCOORD_0 and
# TANGENT in a .gltf + .bin pair, which Specula's mesh loader (tinygltf) reads. Standard library and NumPy only.
import json
import os

import numpy as np

_FLOAT, _UINT = 5126, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963


def write_gltf(path, positions, indices, normals=None, uvs=None, tangents=None):
    """positions (n,3), normals (n,3), uvs (n,2) with v up (Blender/OpenGL), tangents (n,4) with w the bitangent
    sign, indices (m,3). glTF's v points down, so uvs are written as (u, 1 - v) and Specula flips them back."""
    positions = np.ascontiguousarray(positions, dtype=np.float32)
    indices = np.ascontiguousarray(indices, dtype=np.uint32).reshape(-1)
    attributes = [("POSITION", positions, "VEC3")]
    if normals is not None:
        attributes.append(("NORMAL", np.ascontiguousarray(normals, dtype=np.float32), "VEC3"))
    if uvs is not None:
        flipped = np.array(uvs, dtype=np.float32).reshape(-1, 2)
        flipped[:, 1] = 1.0 - flipped[:, 1]
        attributes.append(("TEXCOORD_0", flipped, "VEC2"))
    if tangents is not None:
        attributes.append(("TANGENT", np.ascontiguousarray(tangents, dtype=np.float32), "VEC4"))

    blobs, views, accessors, offset = [], [], [], 0
    for name, data, kind in attributes:
        raw = data.tobytes()
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(raw), "target": _ARRAY_BUFFER})
        accessor = {"bufferView": len(views) - 1, "componentType": _FLOAT, "count": int(data.shape[0]),
                    "type": kind}
        if name == "POSITION":
            accessor["min"] = [float(x) for x in data.min(axis=0)]
            accessor["max"] = [float(x) for x in data.max(axis=0)]
        accessors.append(accessor)
        blobs.append(raw)
        offset += len(raw)
    raw = indices.tobytes()
    views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(raw), "target": _ELEMENT_ARRAY_BUFFER})
    accessors.append({"bufferView": len(views) - 1, "componentType": _UINT, "count": int(indices.size),
                      "type": "SCALAR"})
    blobs.append(raw)
    offset += len(raw)

    bin_name = os.path.splitext(os.path.basename(path))[0] + ".bin"
    document = {
        "asset": {"version": "2.0", "generator": "Specula Blender add-on"},
        "buffers": [{"uri": bin_name, "byteLength": offset}],
        "bufferViews": views,
        "accessors": accessors,
        "meshes": [{"primitives": [{"attributes": {name: i for i, (name, _, _) in enumerate(attributes)},
                                    "indices": len(accessors) - 1, "mode": 4}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    with open(os.path.join(os.path.dirname(path), bin_name), "wb") as f:
        for blob in blobs:
            f.write(blob)
    with open(path, "w") as f:
        json.dump(document, f)
