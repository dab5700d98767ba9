#!/usr/bin/env python3
"""Filtered GGX per frame (issue 15 item 5): each filtered-GGX validation scene (examples/filtered-ggx/) rendered by
`specula render` with every NDF filter of its bsdf.ggx_filtered node, against the same node with filter "none" (plain
GGX through the same code) in the same run; docs/performance.md keeps the table.

The scenes are rendered at --resolution and --spp (the validation references are 128x96 at 4096 spp; a larger frame
at fewer samples measures the same per-sample work in seconds). The time is the render's own "seconds" (the tile
loop, scene loading excluded; with --cpu-time the CPU seconds of the process less those of an 8x8 frame at 1 spp
of the same scene, which other jobs on the same cores disturb less). Rounds interleave the variants (and the binaries, when --specula is given more than
once, e.g. a build from before a change and the current one) so that a load change hits all of them; the minimum and
the median of the rounds are kept, and the tables give the minimum's ratio (the median's in brackets).

  bench/bench_filtered_ggx_frames.py [--specula build/bin/specula [--specula OTHER]] [--resolution 512x384] [--spp 16]
                                     [--repeat 3] [--filters none,projected_approx,...] [--threads N] [--cpu-time]
                                     [--json OUT]
"""
import argparse
import glob
import json
import os
import resource
import statistics
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


def render_seconds(specula, path, out, args, resolution=None, spp=None):
    cmd = [specula, "render", path, "-o", out, "--resolution", resolution or args.resolution,
           "--spp", str(spp or args.spp), "--progress", "json"]
    if args.threads:
        cmd += ["--threads", str(args.threads)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    r = subprocess.run(cmd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode:
        raise SystemExit("specula render failed (%d): %s" % (r.returncode, r.stderr.strip()[-1000:]))
    if args.cpu_time:
        return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    done = [json.loads(l) for l in (r.stdout + r.stderr).splitlines() if l.startswith("{") and '"done"' in l]
    return done[-1]["seconds"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--specula", action="append", default=[],
                    help="a specula binary; repeat to compare binaries in the same run (default build/bin/specula)")
    ap.add_argument("--examples", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples",
                                                       "filtered-ggx"))
    ap.add_argument("--resolution", default="512x384")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0, help="render threads (default: the renderer's)")
    ap.add_argument("--cpu-time", action="store_true",
                    help="time the CPU seconds of the process, less those of an 8x8 frame at 1 spp of the same scene "
                         "(start-up, loading, writing), instead of the render's wall-clock seconds: steadier when "
                         "other jobs share the cores")
    ap.add_argument("--filters", default=",".join(FILTERS), help="comma-separated; \"none\" is always rendered")
    ap.add_argument("--json", default="", help="also write the rows as JSON to this file")
    args = ap.parse_args()
    binaries = args.specula or [os.path.join("build", "bin", "specula")]
    filters = ["none"] + [f for f in args.filters.split(",") if f and f != "none"]
    scenes = sorted(glob.glob(os.path.join(args.examples, "*.json")))
    times = {}
    with tempfile.TemporaryDirectory() as tmp:
        jobs = []
        for path in scenes:
            name = os.path.basename(path)[:-5]
            with open(path) as f:
                scene = json.load(f)
            for filt in filters:
                # Written beside the original, so relative texture paths still resolve; removed at the end.
                p = os.path.join(os.path.dirname(path), ".bench-%s-%s.json" % (name, filt))
                with open(p, "w") as f:
                    json.dump(with_filter(scene, filt), f)
                jobs.append((name, filt, p))
        try:
            for rnd in range(args.repeat):
                for name, filt, p in jobs:
                    for b, specula in enumerate(binaries):
                        s = render_seconds(specula, p, os.path.join(tmp, "frame.exr"), args)
                        if args.cpu_time:  # less the start-up, loading and writing: an 8x8 frame at 1 spp
                            s -= render_seconds(specula, p, os.path.join(tmp, "frame.exr"), args, "8x8", 1)
                        times.setdefault((b, name, filt), []).append(s)
                        print("round %d  %-10s %-17s %7.3f s  %s" % (rnd + 1, name, filt, s, specula), flush=True)
        finally:
            for _, _, p in jobs:
                os.remove(p)
    rows = []
    for b, specula in enumerate(binaries):
        print("\n%s: %s at %d spp, min of %d rounds; ratio to filter \"none\" of the same scene in the same run "
              "(ratio of the medians in brackets)" % (specula, args.resolution, args.spp, args.repeat))
        print("| scene | " + " | ".join(filters) + " |")
        print("|---|" + "---:|" * len(filters))
        for path in scenes:
            name = os.path.basename(path)[:-5]
            t = {f: times[(b, name, f)] for f in filters}
            base, baseMed = min(t["none"]), statistics.median(t["none"])
            cells = ["%.3f s" % base]
            for f in filters[1:]:
                r, rm = min(t[f]) / base, statistics.median(t[f]) / baseMed
                cells.append("%.3f (%+.1f %%) [%+.1f %%]" % (r, 100 * (r - 1), 100 * (rm - 1)))
            print("| %s | %s |" % (name, " | ".join(cells)))
            rows.append({"specula": specula, "scene": name, "seconds": t})
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
