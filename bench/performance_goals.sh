#!/usr/bin/env bash
# Every ratio of issues 15 and 37 (docs/performance.md) measured in one run, one after the other, on an otherwise idle
# machine: render / Embree-only, ours / Cycles at 1 and 64 spp, graph overhead (per point and batched), filtered GGX
# per evaluation and per frame, the 1 -> 2 thread speed-up and peak memory. With BEFORE_BUILD, every bench runs for
# that build right before the same bench of BUILD (before/after rows from one run, issue 37 item 4). Each bench prints
# its own table; the lines starting with RATIO are the summary.
# Usage: bench/performance_goals.sh [BUILD_DIR] [OUT_DIR] [BEFORE_BUILD_DIR]   (about 6 minutes per build on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
OUT=${2:-$(mktemp -d)}
BEFORE=${3:-}
mkdir -p "$OUT"
PY=/usr/bin/python3  # Debian's, with python3-numpy (platform.md); a python3 earlier on PATH may lack it
builds=("$BUILD")
labels=(after)
if [ -n "$BEFORE" ]; then builds=("$BEFORE" "$BUILD"); labels=(before after); fi
for B in "${builds[@]}"; do
  for b in bench_embree_limit bench_graph bench_filtered_ggx bench_render specula; do
    [ -x "$B/bin/$b" ] || { echo "missing $B/bin/$b: build first (./scripts/setup)"; exit 1; }
  done
done
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown); builds: ${builds[*]}"

# each NAME CMD...: runs CMD once per build (before first), with $B the build directory, output to $OUT/<label>_NAME.txt.
each() {
  local name=$1; shift
  for i in "${!builds[@]}"; do
    B=${builds[$i]}
    echo "-- ${labels[$i]} ($B)"
    eval "$@" | tee "$OUT/${labels[$i]}_$name.txt"
  done
}

echo "== item 2: render / Embree alone (anchor scene, 512x512, 16 spp, 5 runs)"
each embree_limit '"$B/bin/bench_embree_limit" 16 512 5'

echo "== item 3: ours / Cycles (anchor scene, min of 3)"
each cycles 'bench/compare_cycles.sh "$B" 3'

echo "== item 4: graph overhead"
each graph '"$B/bin/bench_graph" --benchmark_min_time=0.5 2>/dev/null | grep -E "ratio|median"'

echo "== item 5: filtered GGX per evaluation"
each filtered_ggx '"$B/bin/bench_filtered_ggx" --benchmark_min_time=0.3 2>/dev/null | grep -E "^RATIO|median"'

echo "== item 5: filtered GGX per frame (512x384, 16 spp, min of 3)"
each frames '"$PY" bench/bench_filtered_ggx_frames.py --specula "$B/bin/specula" --resolution 512x384 --spp 16 --repeat 3'

echo "== item 6: threads (anchor scene 512x512, 16 spp, min of 3)"
each scaling '"$PY" bench/bench_scaling.py --specula "$B/bin/specula" --runs 3 --only threads'

echo "== memory: peak resident memory per million triangles"
each memory '"$PY" bench/bench_scaling.py --specula "$B/bin/specula" --runs 1 --only memory'

echo "== summary"
for l in "${labels[@]}"; do
  echo "-- $l"
  grep -h "RATIO" "$OUT/${l}_embree_limit.txt" || true
  sed -n 's/^anchor-sphere \(.*\)ours\/cycles \(.*\)$/RATIO ours\/Cycles \1= \2/p' "$OUT/${l}_cycles.txt"
  grep -h "= ratio" "$OUT/${l}_graph.txt" | sed 's/^/RATIO /'
  grep -hE "^RATIO (projected_approx|projected/|slope|none)" "$OUT/${l}_filtered_ggx.txt" || true
done
echo "outputs in $OUT"
