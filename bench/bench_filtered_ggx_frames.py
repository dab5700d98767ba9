#!/usr/bin/env python3
"""Filtered GGX per frame (issue 15 item 5): each filtered-GGX validation scene (examples/filtered-ggx/) rendered by
`specula render` with every NDF filter of its bsdf.ggx_filtered node, against the same node with filter "none" (plain
GGX through the same code) in the same run; docs/performance.md keeps the table.

The scenes are rendered at --resolution and --spp (the validation references are 128x96 at 4096 spp; a larger frame
at fewer samples measures the same per-sample work in seconds). The time is the render's own "seconds" (the tile
loop, scene loading excluded). Rounds interleave the variants so that a load change hits all of them; the minimum of
the rounds is kept.

  bench/bench_filtered_ggx_frames.py [--specula build/bin/specula] [--resolution 512x384] [--spp 16] [--repeat 3]
                                     [--threads N] [--json OUT]
"""
import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile

FILTERS = ["none", "projected_approx", "projected", "slope", "iso_max"]


def with_filter(scene, filt):
    doc = json.loads(json.dumps(scene))
    found = 0
    for mat in doc.get("materials", {}).values():
        for node in mat.get("nodes", {}).values():
            if node.get("type") == "bsdf.ggx_filtered":
                node.setdefault("inputs", {})["filter"] = filt
                found += 1
    if not found:
        raise SystemExit("no bsdf.ggx_filtered node in the scene")
    return doc


def render_seconds(specula, path, out, args):
    cmd = [specula, "render", path, "-o", out, "--resolution", args.resolution, "--spp", str(args.spp),
           "--progress", "json"]
    if args.threads:
        cmd += ["--threads", str(args.threads)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode:
        raise SystemExit("specula render failed (%d): %s" % (r.returncode, r.stderr.strip()[-1000:]))
    done = [json.loads(l) for l in (r.stdout + r.stderr).splitlines() if l.startswith("{") and '"done"' in l]
    return done[-1]["seconds"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--specula", default=os.path.join("build", "bin", "specula"))
    ap.add_argument("--examples", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples",
                                                       "filtered-ggx"))
    ap.add_argument("--resolution", default="512x384")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0, help="render threads (default: the renderer's)")
    ap.add_argument("--json", default="", help="also write the rows as JSON to this file")
    args = ap.parse_args()
    scenes = sorted(glob.glob(os.path.join(args.examples, "*.json")))
    times = {}
    with tempfile.TemporaryDirectory() as tmp:
        jobs = []
        for path in scenes:
            name = os.path.basename(path)[:-5]
            with open(path) as f:
                scene = json.load(f)
            for filt in FILTERS:
                # Written beside the original, so relative texture paths still resolve; removed at the end.
                p = os.path.join(os.path.dirname(path), ".bench-%s-%s.json" % (name, filt))
                with open(p, "w") as f:
                    json.dump(with_filter(scene, filt), f)
                jobs.append((name, filt, p))
        try:
            for rnd in range(args.repeat):
                for name, filt, p in jobs:
                    s = render_seconds(args.specula, p, os.path.join(tmp, "frame.exr"), args)
                    times[(name, filt)] = min(times.get((name, filt), float("inf")), s)
                    print("round %d  %-10s %-17s %7.3f s" % (rnd + 1, name, filt, s), flush=True)
        finally:
            for _, _, p in jobs:
                os.remove(p)
    rows = []
    print("\n%s at %d spp, min of %d rounds; ratio to filter \"none\" of the same scene in the same run" %
          (args.resolution, args.spp, args.repeat))
    print("| scene | " + " | ".join(FILTERS) + " |")
    print("|---|" + "---:|" * len(FILTERS))
    for path in scenes:
        name = os.path.basename(path)[:-5]
        base = times[(name, "none")]
        cells = ["%.3f s" % base] + ["%.3f (%+.1f %%)" % (times[(name, f)] / base, 100 * (times[(name, f)] / base - 1))
                                      for f in FILTERS[1:]]
        print("| %s | %s |" % (name, " | ".join(cells)))
        rows.append({"scene": name, "seconds": {f: times[(name, f)] for f in FILTERS}})
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
