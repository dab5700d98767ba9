#!/usr/bin/env python3
"""One-off migration (issue 9, item 9): rewrites the manifests of tests/validation/glint/ and
tests/validation/filtered_ggx/ from their two old formats into the toolkit's one format
(tools/specula_validation/manifest.py), WITHOUT re-rendering any reference: the cached EXRs stay byte-identical.

Before writing, it proves that the old caches were up to date by the old rules, and that the new description renders
the same thing:
  * glint: the old manifest's scene, map and file SHA-256 match, the old SHA-256 of the glint C++ sources matches (the
    rule being replaced), and the derived reference / coverage scenes of tools/validate_glint.py equal the scenes
    recorded in the old manifest;
  * filtered GGX: the old scene and input SHA-256 match and every cached file is present;
  * flicker frames: `specula render --camera-shift-px` gives the camera recorded for each old frame (as the float
    the loader uses). Filtered GGX: identical for every frame. Glint: the old script rounded the world coordinates to
    1e-9, so a few coordinates differ by that much (reported; about 5e-8 pixel, far below the 1/8-pixel step).
Then it computes the behavioural fingerprint (probe renders) with the given renderer and writes the manifests.

Usage: tools/migrate_validation_manifests.py --specula build/bin/specula [--dry-run]
"""
import argparse
import hashlib
import json
import os
import struct
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import validate_filtered_ggx as vf  # noqa: E402
import validate_glint as vg  # noqa: E402
from specula_validation import ROOT  # noqa: E402
from specula_validation.manifest import SCHEMA, sha256_file  # noqa: E402
from specula_validation.render import Renderer  # noqa: E402

OLD_GLINT_SOURCES = ["nodes/bsdf/glint/glint_bsdf.h", "nodes/bsdf/glint/glint_bsdf.cpp",
                     "nodes/bsdf/glint/glint_dictionary.h", "nodes/bsdf/glint/glint_dictionary.cpp",
                     "nodes/bsdf/glint/glint.node.cpp"]


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


def old_glint_sources_sha256():
    h = hashlib.sha256()
    for p in OLD_GLINT_SOURCES:
        h.update(p.encode() + b"\0")
        with open(os.path.join(ROOT, p), "rb") as f:
            h.update(f.read())
    return h.hexdigest()


def camera_deviation(rnd, scene, shift, recorded):
    """(largest |difference| of the float coordinates, number of differing coordinates) between the camera of
    `specula render --camera-shift-px shift` and the recorded world coordinates."""
    cam = rnd.camera(scene, "camera", shift_px=shift)
    worst, n = 0.0, 0
    for k in ("position", "look_at"):
        for i in range(3):
            d = abs(f32(cam[k][i]) - f32(recorded[k][i]))
            worst, n = max(worst, d), n + (d != 0)
    return worst, n


def migrate_glint(specula, work, dry):
    with open(vg.MANIFEST) as f:
        old = json.load(f)
    if old.get("schema") == SCHEMA:
        print("glint: already in the toolkit format")
        return
    assert old["glint_sources_sha256"] == old_glint_sources_sha256(), "glint: the old cache was stale (sources)"
    rnd = vg.renderer(specula, work)
    records, extra = {}, {}
    for sid in vg.SCENES:
        e = old["scenes"][sid]
        base = vg.load_scene(sid)
        assert e["scene_sha256"] == sha256_file(os.path.join(vg.EXAMPLES, vg.SCENES[sid]["file"])), sid
        for m, h in e["maps"].items():
            assert h == sha256_file(os.path.normpath(os.path.join(vg.EXAMPLES, m))), m
        main = [x for x in e["files"] if x["frame"] is None][0]
        assert main["scene_json"] == vg.derive(base, vg.REF), f"{sid}: derived reference scene differs"
        assert main["coverage_json"] == vg.coverage_scene(base), f"{sid}: derived coverage scene differs"
        worst, count = 0.0, 0
        for x in e["files"]:
            assert x["file_sha256"] == sha256_file(os.path.join(vg.CACHE, x["file"])), x["file"]
            rec = {"command": vg.file_command(x["file"], x["spp"], x["frame"]), "seconds": x["render_seconds"]}
            if x["frame"] is not None:
                w, n = camera_deviation(rnd, vg.derive(base, vg.REF), vg.shift_px(x["frame"]), x["camera"])
                worst, count = max(worst, w), count + n
                rec["camera_rendered"] = x["camera"]  # what the migrated file was rendered with (rounded to 1e-9)
            records[x["file"]] = rec
        print(f"glint {sid}: old cache verified; --camera-shift-px vs recorded frame cameras: {count} float "
              f"coordinates differ, by at most {worst:.2e} world units")
        extra[sid] = {"frame_ref_noise": e["frame_ref_noise"],
                      "migrated": f"from cache_format 1 by tools/migrate_validation_manifests.py without re-rendering; "
                                  f"frame cameras were rounded to 1e-9 (largest float difference to "
                                  f"--camera-shift-px {worst:.2e} world units in {count} coordinates)"}
    if not dry:
        vg.write_manifest(specula, list(vg.SCENES), work, records, extra)
        print(f"wrote {os.path.relpath(vg.MANIFEST, ROOT)}")


def migrate_filtered_ggx(specula, work, dry):
    path = os.path.join(ROOT, vf.MANIFEST)
    with open(path) as f:
        old = json.load(f)
    if old.get("schema") == SCHEMA:
        print("filtered GGX: already in the toolkit format")
        return
    rnd = Renderer(specula, work)
    records = {}
    for n in vf.SCENES:
        e = old["scenes"][n]
        assert e["scene_sha256"] == sha256_file(os.path.join(ROOT, e["scene"])), n
        for p, h in e["inputs_sha256"].items():
            assert h == sha256_file(os.path.join(ROOT, p)), p
        assert e["flicker"]["frames_count"] == vf.FLICKER_FRAMES and e["flicker"]["spp"] == vf.FLICKER_SPP
        assert e["reference"]["spp"] == vf.REF_SPP
        records[e["reference"]["file"]] = {"command": e["reference"]["command"],
                                           "seconds": e["reference"]["seconds"]}
        worst, count = 0.0, 0
        for t, fr in enumerate(e["flicker"]["frames"]):
            assert os.path.exists(os.path.join(ROOT, vf.CACHE_DIR, fr["file"])), fr["file"]
            w, c = camera_deviation(rnd, os.path.join(ROOT, e["scene"]), vf.shift_px(t),
                                    {"position": fr["camera_position"], "look_at": fr["camera_look_at"]})
            worst, count = max(worst, w), count + c
            dx, dy = vf.shift_px(t)
            records[fr["file"]] = {"command": f"specula render {e['scene']} -o {fr['file']} --spp {vf.FLICKER_SPP} "
                                              f"--camera-shift-px {dx!r},{dy!r}  (migrated: rendered from a frame "
                                              f"scene with the same camera floats)", "seconds": fr["seconds"]}
        assert count == 0, f"filtered GGX {n}: --camera-shift-px differs from the recorded frame cameras"
        print(f"filtered GGX {n}: old cache verified; --camera-shift-px gives the recorded frame cameras exactly")
    if not dry:
        spec_ = vf.cache_spec(specula)
        spec_.write(specula, work, records, old["renderer_version"],
                    {n: {"migrated": "from the tools/validate_filtered_ggx.py format by "
                                     "tools/migrate_validation_manifests.py without re-rendering"} for n in vf.SCENES})
        print(f"wrote {vf.MANIFEST}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--specula", default=os.path.join(ROOT, "build", "bin", "specula"))
    ap.add_argument("--dry-run", action="store_true", help="verify only, write nothing")
    a = ap.parse_args()
    specula = os.path.abspath(a.specula)
    with tempfile.TemporaryDirectory(prefix="migrate_") as work:
        migrate_glint(specula, work, a.dry_run)
        migrate_filtered_ggx(specula, work, a.dry_run)
    return 0


if __name__ == "__main__":
    sys.exit(main())
