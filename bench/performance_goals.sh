#!/usr/bin/env bash
# Every ratio of issue 15 (docs/performance.md) measured in one run, one after the other, on an otherwise idle machine:
# render / Embree-only, ours / Cycles at 1 and 64 spp, graph overhead, filtered GGX per evaluation and per frame, and
# the 1 -> 2 thread speed-up. Each bench prints its own table; the lines starting with RATIO are the summary.
# Usage: bench/performance_goals.sh [BUILD_DIR] [OUT_DIR]   (about 6 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
OUT=${2:-$(mktemp -d)}
mkdir -p "$OUT"
PY=/usr/bin/python3  # Debian's, with python3-numpy (platform.md); a python3 earlier on PATH may lack it
for b in bench_embree_limit bench_graph bench_filtered_ggx bench_render specula; do
  [ -x "$BUILD/bin/$b" ] || { echo "missing $BUILD/bin/$b: build first (./scripts/setup)"; exit 1; }
done
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"

echo "== item 2: render / Embree alone (anchor scene, 512x512, 16 spp, 5 runs)"
"$BUILD/bin/bench_embree_limit" 16 512 5 | tee "$OUT/embree_limit.txt"

echo "== item 3: ours / Cycles (anchor scene, min of 3)"
bench/compare_cycles.sh "$BUILD" 3 | tee "$OUT/cycles.txt"

echo "== item 4: graph overhead"
"$BUILD/bin/bench_graph" --benchmark_min_time=0.5 2>/dev/null | tee "$OUT/graph.txt" | grep -E "ratio"

echo "== item 5: filtered GGX per evaluation"
"$BUILD/bin/bench_filtered_ggx" --benchmark_min_time=0.3 2>/dev/null | tee "$OUT/filtered_ggx.txt" | grep -E "^RATIO"

echo "== item 5: filtered GGX per frame (512x384, 16 spp, min of 3)"
"$PY" bench/bench_filtered_ggx_frames.py --specula "$BUILD/bin/specula" --resolution 512x384 --spp 16 --repeat 3 \
  --json "$OUT/frames.json" | tee "$OUT/frames.txt"

echo "== item 6: threads (anchor scene 512x512, 16 spp, min of 3)"
"$PY" bench/bench_scaling.py --specula "$BUILD/bin/specula" --runs 3 --only threads --json "$OUT/scaling.json" \
  | tee "$OUT/scaling.txt"

echo "== summary"
grep -h "RATIO" "$OUT/embree_limit.txt" || true
sed -n 's/^anchor-sphere \(.*\)ours\/cycles \(.*\)$/RATIO ours\/Cycles \1= \2/p' "$OUT/cycles.txt"
grep -h "= ratio" "$OUT/graph.txt" | sed 's/^/RATIO /'
grep -hE "^RATIO (projected_approx|projected/|slope|none)" "$OUT/filtered_ggx.txt" || true
echo "outputs in $OUT"
