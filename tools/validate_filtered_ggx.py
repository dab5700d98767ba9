#!/usr/bin/env python3
# Filtered-GGX validation (issue 4), PRELIMINARY: renders a 128×96 sphere (α 0.02) + torus (α 0.05) scene lit by two
# point lights, a 4096-spp Gaussian-σ²=1/(2π) reference without NDF filtering, and 1-spp pixel-centre images for every
# filter × kernel × derivative mode; prints `specula compare --aov specular --json` RMSE/MAE and ratios vs `none`.
# Usage: tools/validate_filtered_ggx.py BUILD/bin/specula OUTDIR   (not yet: cylinders, normal-mapped plane, flicker).
import json, os, subprocess, sys

def scene(mode, kernel, spp, deriv):
    render = {"width": 128, "height": 96, "spp": spp, "seed": 0, "integrator": "direct", "max_depth": 0}
    if spp == 1:
        render.update({"pixel_center": True, "derivatives": deriv})
    else:
        render["filter"] = "gaussian"
    mat = lambda a: {"nodes": {"s": {"type": "bsdf.ggx_filtered", "inputs": {"alpha": [a, a], "filter": mode, "kernel": kernel,
                                                                             "f0": [0.95, 0.64, 0.54]}}}, "output": "@s.bsdf"}
    return {"version": 1, "render": render,
            "camera": {"position": [0, -6, 1.2], "look_at": [0, 0, 0.8], "up": [0, 0, 1], "fov": 40},
            "materials": {"m1": mat(0.02), "m2": mat(0.05)},
            "shapes": [{"type": "sphere", "radius": 0.8, "transform": {"translate": [-1.1, 0, 0.8]}, "material": "m1"},
                       {"type": "torus", "major_radius": 0.6, "minor_radius": 0.2, "transform": {"translate": [1.1, 0, 0.8]}, "material": "m2"}],
            "lights": [{"type": "point", "position": [3, -5, 5], "power": 2000}, {"type": "point", "position": [-4, 2, 3], "power": 800}]}

def render(specula, sc, out):
    path = out[:-4] + ".json"
    json.dump(sc, open(path, "w"), indent=1)
    subprocess.run([specula, "render", path, "-o", out], check=True, stdout=subprocess.DEVNULL)

def main():
    specula, outdir = sys.argv[1], sys.argv[2]
    os.makedirs(outdir, exist_ok=True)
    ref = os.path.join(outdir, "ref.exr")
    if not os.path.exists(ref):
        render(specula, scene("none", "full", 4096, "ray"), ref)
    base = {}
    for deriv in ("ray", "quad"):
        for mode in ("none", "slope", "projected", "projected_approx", "iso_max", "iso_sum", "iso_mean", "iso_rect"):
            for kernel in ("full", "axis_aligned"):
                img = os.path.join(outdir, f"t_{mode}_{kernel}_{deriv}.exr")
                render(specula, scene(mode, kernel, 1, deriv), img)
                r = json.loads(subprocess.run([specula, "compare", img, ref, "--aov", "specular", "--json"], check=True,
                                              capture_output=True, text=True).stdout)
                if mode == "none": base[deriv] = r
                b = base[deriv]
                print(f"{deriv:5} {mode:17} {kernel:12} rmse {r['rmse']:.4f} ({r['rmse']/b['rmse']:.3f})  mae {r['mae']:.4f} ({r['mae']/b['mae']:.3f})")

if __name__ == "__main__":
    main()
