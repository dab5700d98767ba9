#!/usr/bin/env python3
"""A/B timing of two libspecula builds with the same benchmark binary, interleaved (issue 15's before/after rows).

On this 2-core machine one benchmark run differs from the next by 5-15 %, and code-layout effects between builds of
the same code are as large, so a change is timed against the library of the commit before it, in alternating
processes, and reported as min and median over all repetitions. The benchmark finds libspecula through its RUNPATH;
LD_LIBRARY_PATH, which the loader searches first, points each run at one of the two copies.

  cp -a build/lib/libspecula.so* /tmp/before/      # at the commit before the change
  (apply the change, rebuild)  cp -a build/lib/libspecula.so* /tmp/after/
  bench/ab_libspecula.py /tmp/before /tmp/after --filter 'BM_AnchorSphere/64/' --rounds 3

Only changes inside libspecula can be compared this way (the benchmark binary and its inlined headers stay fixed).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("libdirs", nargs=2, help="folders holding the two libspecula.so* copies (before, after)")
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "bin", "bench_render"))
    ap.add_argument("--filter", default="BM_AnchorSphere/64/", help="--benchmark_filter of the benchmark")
    ap.add_argument("--rounds", type=int, default=3, help="processes per library, alternating")
    args = ap.parse_args()

    times = {d: [] for d in args.libdirs}
    for _ in range(args.rounds):
        for d in args.libdirs:
            fd, out = tempfile.mkstemp(suffix=".json")
            os.close(fd)
            env = dict(os.environ, LD_LIBRARY_PATH=os.path.abspath(d))
            subprocess.run([args.bench, "--benchmark_filter=" + args.filter, "--benchmark_format=json",
                            "--benchmark_out=" + out], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                           check=True)
            with open(out) as f:
                data = json.load(f)
            os.remove(out)
            times[d] += [b["real_time"] for b in data["benchmarks"] if b.get("run_type") == "iteration"]
    if not all(times.values()):
        print("no benchmark matched --filter %r" % args.filter)
        return 1
    before, after = (times[d] for d in args.libdirs)
    for name, d, v in (("before", args.libdirs[0], before), ("after", args.libdirs[1], after)):
        print("%-6s %s: n=%d min=%.1f median=%.1f  [%s]" % (name, d, len(v), min(v), statistics.median(v),
                                                           " ".join("%.0f" % x for x in v)))
    print("after/before: min %.3f, median %.3f" % (min(after) / min(before),
                                                   statistics.median(after) / statistics.median(before)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
