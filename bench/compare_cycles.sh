#!/usr/bin/env bash
# Times the anchor scene in Specula (bench_render, in-process render time) and, when `blender` is
# installed, in Blender 3.4 Cycles (bench/cycles/anchor_sphere.py, time of bpy.ops.render.render),
# in the same run, at 1 and 64 spp; prints the min of RUNS runs each and the ratio ours/Cycles.
# Usage: bench/compare_cycles.sh [BUILD_DIR] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
RUNS=${2:-3}
BENCH="$BUILD/bin/bench_render"
[ -x "$BENCH" ] || { echo "missing $BENCH: build first (./scripts/setup)"; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

"$BENCH" --benchmark_repetitions="$RUNS" --benchmark_format=json --benchmark_out="$TMP/ours.json" >/dev/null
ours() {  # min real time in seconds for spp $1
  python3 - "$TMP/ours.json" "$1" <<'PY'
import json, sys
data = json.load(open(sys.argv[1]))
runs = [b["real_time"] for b in data["benchmarks"]
        if b["name"].startswith("BM_AnchorSphere/%s/" % sys.argv[2]) and b.get("run_type") == "iteration"]
print("%.3f" % (min(runs) / 1000.0))
PY
}
echo "machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
for spp in 1 64; do
  o=$(ours "$spp")
  if command -v blender >/dev/null 2>&1; then
    best=""
    for i in $(seq "$RUNS"); do
      t=$(blender -b --factory-startup --python bench/cycles/anchor_sphere.py -- "$spp" "$TMP/cycles" 2>/dev/null \
          | sed -n 's/^RENDER_SECONDS //p')
      if [ -z "$best" ] || awk "BEGIN{exit !($t < $best)}"; then best=$t; fi
    done
    ratio=$(awk "BEGIN{printf \"%.2f\", $o / $best}")
    echo "anchor-sphere ${spp} spp: specula ${o} s, cycles ${best} s, ours/cycles ${ratio}"
  else
    echo "anchor-sphere ${spp} spp: specula ${o} s (blender not installed: no Cycles comparison)"
  fi
done
