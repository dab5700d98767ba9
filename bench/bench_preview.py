#!/usr/bin/env python3
"""GPU preview timing per material (issue 14 item 5; docs/performance.md "GPU preview"): one scene per material kind,
each drawn by `specula preview --resolution WxH --frames N --json`, which prints gpu_ms_per_frame (GL_TIME_ELAPSED of
the frame's draws) and wall_ms_per_frame (the host clock, each frame ended by glFinish). Every scene is the same tilted
floor filling the whole frame (so every pixel runs the material) under one point and one directional light; only the
material changes, and "ggx + quad (LTC)" adds a quad light out of view. Ratios are against the plain-GGX scene of the
same run.

The driver compiles a program at its first draw (llvmpipe: about a second of LLVM per material). So each scene first
runs once at 64x36, which fills the driver's shader cache (MESA_SHADER_CACHE_DIR, a fresh folder per bench run unless
set), then at WxH with 1 and with 1 + N frames; the figure is the difference of the two totals divided by N, which
also removes what else the first frame pays (cache lookup, first touch of the render target).
Mesa llvmpipe's GL_TIME_ELAPSED is unreliable (about 190x the wall time, docs/preview.md), so on llvmpipe the ratios
use the wall clock; on any other renderer they use the GPU timer.

  bench/bench_preview.py [--specula build/bin/specula] [--resolution 1920x1080] [--frames 3] [--repeat 1] [--only a,b] [--no-output]
                         [--json OUT]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

# The floor: 40 x 40 units, uv 0..1 over it, seen from 2 units up at 34 degrees down; no pixel sees the background.
BASE = {
    "version": 1,
    "render": {"width": 1920, "height": 1080, "spp": 1},
    "camera": {"position": [0, -3, 2], "look_at": [0, 0, 0], "fov": 50},
    "shapes": [{"type": "quad", "size": [40, 40], "material": "m"}],
    "lights": [
        {"type": "point", "position": [1, 1, 2], "intensity": 20},
        {"type": "directional", "direction": [-0.4, 0.6, -1], "irradiance": 1.5},
    ],
}
QUAD = {"type": "quad", "position": [0, -4, 5], "look_at": [0, 2, 0], "size": [2, 1], "radiance": 4}


def ggxf(filter_):
    return {"nodes": {"s": {"type": "bsdf.ggx_filtered", "inputs": {"alpha": [0.09, 0.09], "filter": filter_,
                                                                      "f0": [0.9, 0.7, 0.5]}}},
            "output": "@s.bsdf"}


def glint(ggaa):
    return {"nodes": {"s": {"type": "bsdf.glint", "inputs": {"sigma_x": 0.2, "sigma_y": 0.2, "log_density": 12,
                                                               "ggaa": ggaa, "f0": [0.95, 0.64, 0.54],
                                                               "uv_scale": 40}}},
            "output": "@s.bsdf"}


GGX = {"nodes": {"s": {"type": "bsdf.ggx", "inputs": {"roughness": 0.3, "f0": [0.9, 0.7, 0.5]}}}, "output": "@s.bsdf"}
LEAN = {"nodes": {
    "uvs": {"type": "geometry.uv"},
    "uv": {"type": "math.mul.vec2", "inputs": {"a": "@uvs.uv", "b": [40, 40]}},
    "dx": {"type": "math.mul.vec2", "inputs": {"a": "@uvs.duvdx", "b": [40, 40]}},
    "dy": {"type": "math.mul.vec2", "inputs": {"a": "@uvs.duvdy", "b": [40, 40]}},
    "lean": {"type": "texture.lean", "inputs": {"file": "generate:bumps:256:1", "uv": "@uv.out",
                                                "duvdx": "@dx.out", "duvdy": "@dy.out"}},
    "s": {"type": "bsdf.beckmann_lean", "inputs": {"roughness": 0.2, "slope": "@lean.slope",
                                                   "covariance": "@lean.covariance"}}},
    "output": "@s.bsdf"}
PNDF = {"nodes": {"s": {"type": "bsdf.glint_pndf", "inputs": {"normal_map": "generate:scratches:1024:5",
                                                                "uv_scale": 10, "fresnel": "conductor"}}},
        "output": "@s.bsdf"}
DIFFUSE = {"nodes": {"s": {"type": "bsdf.diffuse", "inputs": {"color": [0.5, 0.4, 0.3]}}}, "output": "@s.bsdf"}

# name -> (material, extra lights). "ggx" is the baseline and runs first.
SCENES = [
    ("ggx", GGX, []),
    ("diffuse", DIFFUSE, []),
    ("ggx_filtered none", ggxf("none"), []),
    ("ggx_filtered projected_approx", ggxf("projected_approx"), []),
    ("ggx_filtered projected", ggxf("projected"), []),
    ("ggx_filtered slope", ggxf("slope"), []),
    ("ggx_filtered iso_max", ggxf("iso_max"), []),
    ("glint, GGAA off", glint("off"), []),
    ("glint + GGAA", glint("on"), []),
    ("LEAN (texture.lean + bsdf.beckmann_lean)", LEAN, []),
    ("P-NDF (GPU: LEAN-GGX substitute)", PNDF, []),
    ("ggx + quad light (LTC)", GGX, [QUAD]),
]


def preview(specula, path, resolution, frames, out_dir, env, write=True):
    out = ["-o", os.path.join(out_dir, "frame.exr")] if write else ["--no-output"]
    r = subprocess.run([specula, "preview", path, "--resolution", resolution, "--frames", str(frames), "--json"] + out,
                       capture_output=True, text=True, env=env)
    if r.returncode:
        raise SystemExit("specula preview failed (%d): %s" % (r.returncode, r.stderr.strip()[-1000:]))
    return json.loads(r.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--specula", default=os.path.join("build", "bin", "specula"))
    ap.add_argument("--resolution", default="1920x1080")
    ap.add_argument("--frames", type=int, default=3, help="timed frames after the first (default 3)")
    ap.add_argument("--repeat", type=int, default=1, help="interleaved rounds; the min per scene is kept (default 1)")
    ap.add_argument("--only", default="", help="comma-separated scene names (prefixes); the GGX baseline always runs")
    ap.add_argument("--json", default="", help="also write the rows as JSON to this file")
    ap.add_argument("--no-output", action="store_true",
                    help="time without writing frames (`specula preview --no-output`: no image libraries needed)")
    args = ap.parse_args()
    only = [s.strip() for s in args.only.split(",") if s.strip()]
    scenes = [s for s in SCENES if s[0] == "ggx" or not only or any(s[0].startswith(o) for o in only)]
    env = dict(os.environ)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        env.setdefault("SPECULA_CACHE_DIR", os.path.join(tmp, "cache"))
        env.setdefault("MESA_SHADER_CACHE_DIR", os.path.join(tmp, "mesa-shader-cache"))
        paths = []
        for i, (name, material, extra) in enumerate(scenes):
            doc = json.loads(json.dumps(BASE))
            doc["materials"] = {"m": material}
            doc["lights"] += extra
            paths.append(os.path.join(tmp, "scene%d.json" % i))
            with open(paths[-1], "w") as f:
                json.dump(doc, f)
            preview(args.specula, paths[-1], "64x36", 1, tmp, env, not args.no_output)  # compiles the program into the shader cache
            rows.append({"scene": name, "gpu_ms": float("inf"), "wall_ms": float("inf")})
        # Rounds interleave the scenes, so that a load change on a shared machine hits all of them; the min is kept.
        for rnd in range(args.repeat):
            for path, row in zip(paths, rows):
                one = preview(args.specula, path, args.resolution, 1, tmp, env, not args.no_output)
                many = preview(args.specula, path, args.resolution, 1 + args.frames, tmp, env, not args.no_output)
                n = 1 + args.frames
                row["renderer"] = many["renderer"]
                for key, out in (("gpu_ms_per_frame", "gpu_ms"), ("wall_ms_per_frame", "wall_ms")):
                    row[out] = min(row[out], (many[key] * n - one[key]) / args.frames)
                print("round %d  %-44s wall %9.1f ms/frame  gpu timer %12.1f ms/frame" %
                      (rnd + 1, row["scene"], row["wall_ms"], row["gpu_ms"]), flush=True)
    renderer = rows[0]["renderer"]
    clock = "wall_ms" if "llvmpipe" in renderer else "gpu_ms"
    base = rows[0][clock]
    print("\n%s, %s, %d timed frames per scene, min of %d rounds; ratios on the %s clock (GGX = 1)" %
          (renderer, args.resolution, args.frames, args.repeat, "wall" if clock == "wall_ms" else "GPU timer"))
    print("| material | ms/frame (%s) | × GGX | ms over GGX |" % ("wall" if clock == "wall_ms" else "GPU"))
    print("|---|---|---|---|")
    for r in rows:
        r["ratio"] = r[clock] / base
        print("| %s | %.1f | %.3f | %+.1f |" % (r["scene"], r[clock], r["ratio"], r[clock] - base))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"renderer": renderer, "resolution": args.resolution, "frames": args.frames, "clock": clock,
                       "rows": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
