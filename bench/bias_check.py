#!/usr/bin/env python3
"""Is a faster renderer still the same estimator? Compares a render of the current build against a high-spp reference
rendered by a build from before an optimisation (issue 15 item 3: "the image unchanged in expectation").

The "before" binary renders the scene twice at --spp with seeds 0 and 1; the "after" binary once with seed 2. Both
differences, after - before(0) and before(1) - before(0), are then pure noise if nothing changed but speed, so:
  * the RMSE of after - before(0) must match the noise floor, the RMSE of before(1) - before(0);
  * the mean of after - before(0) over the image, in units of its standard error, must be small (|z| < 4).
A per-block z is not used: path-traced pixel noise is heavy-tailed (rare bright paths), so a block's standard error
from its own 256 pixels is unreliable. Before that, both binaries render --same-seed-spp samples with seed 0: if
the two images are the same bits, the change cannot have changed the expectation either (reported, not required).
Prints a table and, with --json, writes the numbers. Exit 0 when both statistical checks hold, 1 otherwise.

Usage: bench/bias_check.py --before OLD/specula --after build/bin/specula [--scene examples/anchor-sphere.json]
       [--resolution 128x128] [--spp 4096] [--out DIR] [--json FILE]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio


def render(binary, scene, resolution, spp, seed, path):
    cmd = [binary, "render", scene, "--resolution", resolution, "--spp", str(spp), "--seed", str(seed), "-o", path,
           "--progress", "json"]
    done = subprocess.run(cmd, check=True, capture_output=True, text=True)
    seconds = None
    for line in done.stdout.splitlines():
        try:
            event = json.loads(line)
        except json.JSONDecodeError:
            continue
        if event.get("event") == "done":
            seconds = event.get("seconds")
    return seconds


def beauty(path):
    buf = oiio.ImageBuf(path)
    pixels = buf.get_pixels(oiio.FLOAT)
    return np.asarray(pixels, dtype=np.float64)[:, :, :3]


def all_layers(path):
    return np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", required=True, help="specula binary built from before the change")
    ap.add_argument("--after", required=True, help="specula binary of the change")
    ap.add_argument("--scene", default="examples/anchor-sphere.json")
    ap.add_argument("--resolution", default="128x128")
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("--same-seed-spp", type=int, default=16, help="spp of the same-seed identity check (0: skip)")
    ap.add_argument("--out", help="keep the three renders here (default: a temporary folder)")
    ap.add_argument("--json", help="write the numbers to this file")
    args = ap.parse_args()

    out = args.out or tempfile.mkdtemp(prefix="bias_check.")
    os.makedirs(out, exist_ok=True)
    paths = {k: os.path.join(out, k + ".exr") for k in ("before0", "before1", "after")}
    seconds = {
        "before0": render(args.before, args.scene, args.resolution, args.spp, 0, paths["before0"]),
        "before1": render(args.before, args.scene, args.resolution, args.spp, 1, paths["before1"]),
        "after": render(args.after, args.scene, args.resolution, args.spp, 2, paths["after"]),
    }
    identical = None
    if args.same_seed_spp > 0:
        same = [os.path.join(out, k + "_seed0.exr") for k in ("before", "after")]
        render(args.before, args.scene, args.resolution, args.same_seed_spp, 0, same[0])
        render(args.after, args.scene, args.resolution, args.same_seed_spp, 0, same[1])
        identical = bool(np.array_equal(all_layers(same[0]), all_layers(same[1])))
    ref, noise, new = beauty(paths["before0"]), beauty(paths["before1"]), beauty(paths["after"])
    floor, change = noise - ref, new - ref

    def stats(diff):
        flat = diff.reshape(-1)
        se = flat.std(ddof=1) / math.sqrt(flat.size)
        return {"rmse": float(np.sqrt(np.mean(flat ** 2))), "mean": float(flat.mean()),
                "z": float(flat.mean() / se) if se > 0 else 0.0}

    result = {"scene": args.scene, "resolution": args.resolution, "spp": args.spp, "seconds": seconds,
              "reference_mean": float(ref.mean()), "same_seed_spp": args.same_seed_spp,
              "same_seed_identical": identical, "noise_floor": stats(floor), "change": stats(change)}
    result["rmse_ratio"] = result["change"]["rmse"] / max(result["noise_floor"]["rmse"], 1e-30)
    ok = abs(result["change"]["z"]) < 4 and result["rmse_ratio"] < 1.2
    result["unbiased"] = ok

    print(f"{args.scene}, {args.resolution}, {args.spp} spp; reference mean {result['reference_mean']:.6f}")
    print(f"{'difference':<28}{'RMSE':>12}{'mean':>14}{'z (image)':>11}")
    for name, key in (("before seed 1 - seed 0", "noise_floor"), ("after - before seed 0", "change")):
        s = result[key]
        print(f"{name:<28}{s['rmse']:>12.3e}{s['mean']:>14.3e}{s['z']:>11.2f}")
    print(f"RMSE ratio (change / noise floor): {result['rmse_ratio']:.3f}; render seconds before {seconds['before0']}, "
          f"after {seconds['after']}; {'no bias beyond noise' if ok else 'BIASED'}")
    if identical is not None:
        print(f"seed 0 at {args.same_seed_spp} spp, every layer: {'the same bits' if identical else 'different bits'}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=2)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
