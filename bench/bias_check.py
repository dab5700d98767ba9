#!/usr/bin/env python3
"""Is a faster renderer still the same estimator? Compares a render of the current build against a high-spp reference
rendered by a build from before an optimisation (issue 15 item 3: "the image unchanged in expectation").

The "before" binary renders the scene twice at --spp with seeds 0 and 1; the "after" binary once with seed 2. Both
differences, after - before(0) and before(1) - before(0), are then pure noise if nothing changed but speed, so:
  * the RMSE of after - before(0) must match the noise floor, the RMSE of before(1) - before(0) (ratio < 1.2);
  * the mean of after - before(0) over the image, in units of its standard error, must be small (|z| < 4).
A per-block z is not used: path-traced pixel noise is heavy-tailed (rare bright paths), so a block's standard error
from its own 256 pixels is unreliable. Before that, both binaries render --same-seed-spp samples with seed 0: if
the two images are the same bits, the change cannot have changed the expectation either (reported, not required).

Everything goes through the validation toolkit (tools/specula_validation): its Renderer, `specula compare` for the
metrics (the signed mean is mean_a - mean_b, its standard error sqrt((RMSE^2 - mean^2) / n) over the n channel values
of the beauty layer) and OpenImageIO's pixel hash for the identity. Standard library only.
Prints a table and, with --json, writes the numbers. Exit 0 when both statistical checks hold, 1 otherwise.

Usage: bench/bias_check.py --before OLD/specula --after build/bin/specula [--scene examples/anchor-sphere.json]
       [--resolution 128x128] [--spp 4096] [--out DIR] [--json FILE]
"""
import argparse
import json
import math
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tools"))
from specula_validation import exr, metrics  # noqa: E402
from specula_validation.render import Renderer  # noqa: E402


def difference(specula, test, ref):
    """RMSE, signed mean and its z of test - ref over the beauty layer (every pixel and channel)."""
    m = metrics.compare(specula, test, ref, aov="beauty", masks=("all",))
    n = m["mask_pixels"] * m["channels"]
    mean = m["mean_a"] - m["mean_b"]
    se = math.sqrt(max(m["rmse"] ** 2 - mean ** 2, 0.0) / max(n - 1, 1))
    return {"rmse": m["rmse"], "mean": mean, "z": mean / se if se > 0 else 0.0, "reference_mean": m["mean_b"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", required=True, help="specula binary built from before the change")
    ap.add_argument("--after", required=True, help="specula binary of the change")
    ap.add_argument("--scene", default=os.path.join(ROOT, "examples", "anchor-sphere.json"))
    ap.add_argument("--resolution", default="128x128")
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("--same-seed-spp", type=int, default=16, help="spp of the same-seed identity check (0: skip)")
    ap.add_argument("--out", help="keep the renders here (default: a temporary folder)")
    ap.add_argument("--json", help="write the numbers to this file")
    args = ap.parse_args()

    exr.require_oiiotool()
    out = args.out or tempfile.mkdtemp(prefix="bias_check.")
    before, after = Renderer(args.before, out), Renderer(args.after, out)
    scene = os.path.abspath(args.scene)

    identical = None
    if args.same_seed_spp > 0:
        a, _ = before.render(scene, "before_seed0", spp=args.same_seed_spp, resolution=args.resolution, seed=0)
        b, _ = after.render(scene, "after_seed0", spp=args.same_seed_spp, resolution=args.resolution, seed=0)
        identical = exr.pixel_hash(a) == exr.pixel_hash(b)

    ref, t_before = before.render(scene, "before0", spp=args.spp, resolution=args.resolution, seed=0)
    noise, _ = before.render(scene, "before1", spp=args.spp, resolution=args.resolution, seed=1)
    new, t_after = after.render(scene, "after", spp=args.spp, resolution=args.resolution, seed=2)
    floor, change = difference(args.after, noise, ref), difference(args.after, new, ref)

    result = {"scene": args.scene, "resolution": args.resolution, "spp": args.spp,
              "seconds": {"before": t_before, "after": t_after}, "reference_mean": floor["reference_mean"],
              "same_seed_spp": args.same_seed_spp, "same_seed_identical": identical, "noise_floor": floor,
              "change": change, "rmse_ratio": change["rmse"] / max(floor["rmse"], 1e-30)}
    ok = abs(change["z"]) < 4 and result["rmse_ratio"] < 1.2
    result["unbiased"] = ok

    print(f"{args.scene}, {args.resolution}, {args.spp} spp; reference mean {result['reference_mean']:.6f}")
    print(f"{'difference':<28}{'RMSE':>12}{'mean':>14}{'z (image)':>11}")
    for name, s in (("before seed 1 - seed 0", floor), ("after - before seed 0", change)):
        print(f"{name:<28}{s['rmse']:>12.3e}{s['mean']:>14.3e}{s['z']:>11.2f}")
    print(f"RMSE ratio (change / noise floor): {result['rmse_ratio']:.3f}; render seconds before {t_before}, "
          f"after {t_after}; {'no bias beyond noise' if ok else 'BIASED'}")
    if identical is not None:
        print(f"seed 0 at {args.same_seed_spp} spp, every layer: {'the same bits' if identical else 'different bits'}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=2)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
