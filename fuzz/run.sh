#!/usr/bin/env bash
# Runs every libFuzzer target of fuzz/ (docs/reliability.md) for SECONDS each (or RUNS executions each with --runs),
# from seed corpora made by fuzz/make_corpus.py plus what earlier runs found (BUILD/fuzz-corpus, kept between runs).
# Prints one line per target: executions, coverage (edges), corpus size, crashes; exits 1 if any target crashed and
# leaves the crashing inputs in BUILD/fuzz-artifacts/<target>/.
#   fuzz/run.sh BUILD SECONDS            e.g. fuzz/run.sh build-sanitize 60   (CI's smoke)
#   fuzz/run.sh BUILD --runs N           e.g. fuzz/run.sh build-sanitize --runs 1000000
#   fuzz/run.sh BUILD --smoke            CI: a fixed seed and a fixed number of executions per target (about a minute
#                                        each), so that a run that passed here passes in CI with the same binaries
set -uo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:?usage: fuzz/run.sh BUILD SECONDS | --runs N}
shift
SMOKE=0
LIMIT=(-max_total_time="${1:?seconds}")
if [ "$1" = "--runs" ]; then LIMIT=(-runs="${2:?executions}"); fi
if [ "$1" = "--smoke" ]; then SMOKE=1; fi
smoke_runs() {  # executions of each target in about a minute under ASan on 2 cores (measured 2026-12-03; fuzz_image 2026-12-04;
  # fuzz_gltf_scene, fuzz_merge, fuzz_farm_plan: about 25 s each, from CI's smoke of 2026-12-07 with a fuzzer running
  # beside it: 6000 runs in 11 s, 2500 in 28 s, 8000 in 5 s)
  case "$1" in
    fuzz_glsl) echo 150000 ;; fuzz_mesh) echo 40000 ;; fuzz_scene) echo 20000 ;; fuzz_graph) echo 10000 ;; fuzz_image) echo 4000 ;; fuzz_gltf_scene) echo 12000 ;;
    fuzz_merge) echo 2500 ;; fuzz_farm_plan) echo 40000 ;; *) echo 300 ;;
  esac
}
TARGETS=${SPECULA_FUZZ_TARGETS:-"fuzz_scene fuzz_graph fuzz_glsl fuzz_mesh fuzz_image fuzz_gltf_scene fuzz_merge fuzz_farm_plan"}
CORPUS="$BUILD/fuzz-corpus"
ARTIFACTS="$BUILD/fuzz-artifacts"
SEEDS=$(mktemp -d)
trap 'rm -rf "$SEEDS"' EXIT
/usr/bin/python3 fuzz/make_corpus.py "$SEEDS" >/dev/null
# shellcheck source=fuzz/sanitizer_env.sh
. fuzz/sanitizer_env.sh
export SPECULA_CACHE_DIR="$BUILD/fuzz-cache"  # glint dictionaries, P-NDFs, LTC prefilters: built once, kept
status=0
printf '%-16s %12s %9s %8s %8s %8s\n' target executions exec/s cov corpus crashes
for t in $TARGETS; do
  corpus="$CORPUS/$t"
  # The smoke run starts from the seeds alone, as in a clean clone: a corpus grown by earlier runs would take the
  # fixed-seed run down another path, and a smoke run that passed here could fail in CI.
  if [ $SMOKE = 1 ]; then corpus="$SEEDS/smoke-$t"; fi
  mkdir -p "$corpus" "$ARTIFACTS/$t"
  [ -d "$SEEDS/$t" ] && cp -n "$SEEDS/$t"/* "$corpus/" 2>/dev/null
  log="$BUILD/fuzz-$t.log"
  # -rss_limit_mb: the targets' own limits (textures 4 GiB of floats) are checked against the memory budget first.
  if [ $SMOKE = 1 ]; then LIMIT=(-seed=1 -runs="$(smoke_runs "$t")"); fi
  "$BUILD/fuzz/$t" "$corpus" "${LIMIT[@]}" -detect_leaks=0 -rss_limit_mb=3072 -max_len=65536 -timeout=60 -print_final_stats=1 \
      -artifact_prefix="$ARTIFACTS/$t/" >"$log" 2>&1
  rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
  secs=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$log" | tail -1)
  rate=$([ -n "$secs" ] && [ "$secs" -gt 0 ] && echo $(( ${execs:-0} / secs )) || echo "-")
  # crash-, leak-, timeout- and oom- inputs are findings; slow-unit- ones (over 10 s under ASan) are not
  crashes=$(find "$ARTIFACTS/$t" -type f ! -name 'slow-unit-*' | wc -l)
  printf '%-16s %12s %9s %8s %8s %8s\n' "$t" "${execs:-?}" "$rate" "${cov:-?}" "$(ls "$corpus" | wc -l)" "$crashes"
  if [ $rc -ne 0 ] || [ "$crashes" -ne 0 ]; then
    status=1
    echo "fuzz/run.sh: $t failed (exit $rc); log $log, inputs in $ARTIFACTS/$t/:" >&2
    grep -m5 -E 'ERROR|SUMMARY|==[0-9]+==|runtime error|Assertion|abort' "$log" >&2
  fi
done
exit $status
