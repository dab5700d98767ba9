#!/usr/bin/env python3
"""Scaling of the CPU renderer (issue 15 item 6; docs/performance.md "Scaling"), measured through `specula render`:

  threads   the anchor scene at 512x512, 16 spp, with --threads 1 and --threads 2: speed-up (goal >= 1.9x on 2 cores)
  linear    the anchor scene at 256x256/16, 512x512/16 and 512x512/64 spp: seconds per million samples (time linear
            in pixels x spp means this stays constant)
  tiles     render.tile 8, 16, 32 (the default), 64 and 128 at 512x512/16 spp: render seconds
  memory    a smooth sphere mesh of 1 M and 4 M triangles (binary PLY written here, the same grid built in Blender) at
            64x64, 1 spp: peak resident memory of `specula render` and, where `blender` is installed, of Blender 3.4
            Cycles rendering it (bench/cycles/mesh_memory.py); MB per million triangles = the slope between the two

Render seconds are the render's own (the "done" event of --progress json: no start-up, scene load or image writing); the
min of RUNS runs.
Peak memory is the child's ru_maxrss (os.wait4).

  bench/bench_scaling.py [--specula build/bin/specula] [--runs 2] [--only threads,linear,tiles,memory] [--json OUT]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ANCHOR = os.path.join(ROOT, "examples", "anchor-sphere.json")


def run_child(cmd, cwd=None):
    """(stdout + stderr, peak RSS in MB) of one child process."""
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=cwd)
    out = p.stdout.read()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        raise RuntimeError("%s failed (%d):\n%s" % (" ".join(cmd), p.returncode, out[-2000:]))
    return out, usage.ru_maxrss / 1024.0


def render_seconds(specula, scene, tmp, runs, extra=()):
    """The render's own seconds (the "done" event of --progress json, millisecond resolution), min of 'runs'."""
    best = None
    for _ in range(runs):
        out, _ = run_child([specula, "render", scene, "-o", os.path.join(tmp, "o.exr"), "--progress", "json", *extra])
        done = [json.loads(l) for l in out.splitlines() if l.startswith("{") and '"event":"done"' in l]
        if not done:
            raise RuntimeError("no done event in:\n" + out[-2000:])
        t = float(done[-1]["seconds"])
        best = t if best is None else min(best, t)
    return best


def with_render(scene_path, tmp, name, **render):
    s = json.load(open(scene_path))
    s["render"].update(render)
    path = os.path.join(tmp, name + ".json")
    json.dump(s, open(path, "w"))
    return path


def sphere_grid(nu, nv):
    """A unit sphere as an nu x nv (u, v) grid without poles' degenerate rows: 2 nu (nv - 1) triangles."""
    u = np.linspace(0.0, 2.0 * np.pi, nu, endpoint=False)
    v = np.linspace(0.0, np.pi, nv + 1)[1:-1]  # nv - 1 rings strictly between the poles
    uu, vv = np.meshgrid(u, v)
    p = np.stack([np.sin(vv) * np.cos(uu), np.sin(vv) * np.sin(uu), np.cos(vv)], axis=-1).reshape(-1, 3)
    rings, per = len(v), nu
    idx = np.arange(rings * per).reshape(rings, per)
    a, b = idx[:-1, :], np.roll(idx[:-1, :], -1, axis=1)
    c, d = idx[1:, :], np.roll(idx[1:, :], -1, axis=1)
    tris = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])
    return p.astype(np.float32), tris.astype(np.int32)


def write_ply(path, p, tris):
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                 "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face %d\n"
                 "property list uchar int vertex_indices\nend_header\n" % (len(p), len(tris))).encode())
        np.concatenate([p, p], axis=1).astype("<f4").tofile(f)  # unit sphere: the normal is the position
        faces = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<i4", 3)])
        faces["n"] = 3
        faces["i"] = tris
        faces.tofile(f)


def mesh_scene(ply):
    return {"version": 1, "render": {"width": 64, "height": 64, "spp": 1, "integrator": "path", "max_depth": 2},
            "camera": {"position": [0, -4, 1], "look_at": [0, 0, 0], "fov": 40},
            "materials": {"m": {"nodes": {"d": {"type": "bsdf.diffuse", "inputs": {"color": [0.7, 0.7, 0.7]}}},
                                "output": "@d.bsdf"}},
            "shapes": [{"type": "mesh", "file": ply, "material": "m"}],
            "lights": [{"type": "environment", "color": [1, 1, 1]}]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--specula", default=os.path.join(ROOT, "build", "bin", "specula"))
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--only", default="threads,linear,tiles,memory")
    ap.add_argument("--json")
    a = ap.parse_args()
    only = set(a.only.split(","))
    res = {"cores": os.cpu_count()}
    tmp = tempfile.mkdtemp(prefix="specula_scaling_")
    try:
        if "threads" in only:
            scene = with_render(ANCHOR, tmp, "t", width=512, height=512, spp=16)
            t1 = render_seconds(a.specula, scene, tmp, a.runs, ["--threads", "1"])
            t2 = render_seconds(a.specula, scene, tmp, a.runs, ["--threads", "2"])
            res["threads"] = {"1": t1, "2": t2, "speedup": t1 / t2}
            print("threads   1: %.3f s   2: %.3f s   speed-up %.3fx (goal >= 1.9)" % (t1, t2, t1 / t2), flush=True)
        if "linear" in only:
            rows = []
            for w, spp in [(256, 16), (512, 16), (512, 64)]:
                scene = with_render(ANCHOR, tmp, "l%d_%d" % (w, spp), width=w, height=w, spp=spp)
                t = render_seconds(a.specula, scene, tmp, a.runs)
                ms = w * w * spp / 1e6
                rows.append({"pixels": w * w, "spp": spp, "seconds": t, "s_per_msample": t / ms})
                print("linear    %dx%d %3d spp: %.3f s, %.4f s per million samples" % (w, w, spp, t, t / ms), flush=True)
            res["linear"] = rows
        if "tiles" in only:
            rows = []
            for tile in [8, 16, 32, 64, 128]:
                scene = with_render(ANCHOR, tmp, "tile%d" % tile, width=512, height=512, spp=16, tile=tile)
                t = render_seconds(a.specula, scene, tmp, a.runs)
                rows.append({"tile": tile, "seconds": t})
                print("tiles     %3d: %.3f s" % (tile, t), flush=True)
            res["tiles"] = rows
        if "memory" in only:
            rows = []
            blender = shutil.which("blender")
            for mtri, (nu, nv) in [(1, (1000, 501)), (4, (2000, 1001))]:
                p, tris = sphere_grid(nu, nv)
                ply = os.path.join(tmp, "sphere%d.ply" % mtri)
                write_ply(ply, p, tris)
                path = os.path.join(tmp, "mesh%d.json" % mtri)
                json.dump(mesh_scene(ply), open(path, "w"))
                _, rss = run_child([a.specula, "render", path, "-o", os.path.join(tmp, "m.exr"), "--progress", "none"])
                row = {"triangles": int(len(tris)), "specula_peak_mb": rss}
                if blender:
                    out, brss = run_child([blender, "-b", "--factory-startup", "--python",
                                           os.path.join(ROOT, "bench", "cycles", "mesh_memory.py"), "--", str(nu), str(nv)])
                    row["cycles_peak_mb"] = brss
                print("memory    %d triangles: specula %.0f MB" % (len(tris), rss) +
                      ("   Blender Cycles %.0f MB" % row["cycles_peak_mb"] if blender else ""), flush=True)
                rows.append(row)
                os.remove(ply)
            dm = (rows[1]["triangles"] - rows[0]["triangles"]) / 1e6
            res["memory"] = {"rows": rows, "specula_mb_per_mtri": (rows[1]["specula_peak_mb"] - rows[0]["specula_peak_mb"]) / dm}
            print("memory    per million triangles (slope 1 M -> 4 M): specula %.1f MB" % res["memory"]["specula_mb_per_mtri"] +
                  ("" if not blender else ", Blender Cycles %.1f MB" %
                   ((rows[1]["cycles_peak_mb"] - rows[0]["cycles_peak_mb"]) / dm)), flush=True)
            if blender:
                res["memory"]["cycles_mb_per_mtri"] = (rows[1]["cycles_peak_mb"] - rows[0]["cycles_peak_mb"]) / dm
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
