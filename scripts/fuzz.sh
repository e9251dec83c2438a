#!/usr/bin/env bash
# Runs every libFuzzer target, bounded. Two ways:
#   scripts/fuzz.sh           the CI run: seed 1 and a fixed number of inputs per
#                             target (see ci_runs; at most 120 s each), so that
#                             the same commit fuzzes the same inputs
#   scripts/fuzz.sh SECONDS   exploration: a random seed, SECONDS per target
# Needs the sanitizer build in build-sanitize/ (scripts/sanitize.sh makes it;
# RADMESH_FUZZ_BUILD names another build folder).
# Each target starts from its seed corpus (fuzz/corpus/<target>/) in a working
# copy under build-sanitize/fuzz-work/; an input that crashes, hangs (10 s),
# leaks or breaks a check is written to build-sanitize/fuzz-work/<target>/ and
# the script fails, naming it. Per target it prints inputs run, coverage and
# corpus size.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-}"
# Inputs per target in the CI run: sized so that each target ends well inside
# -max_total_time on a slow machine (docs/testing.md).
declare -A ci_runs=([fuzz_obj_reader]=20000 [fuzz_assimp_reader]=5000 [fuzz_json_scene]=40000
                   [fuzz_mgf_reader]=10000 [fuzz_mesh]=2000
                   [fuzz_gltf_nodes]=2000 [fuzz_numbers]=10000 [fuzz_writers]=1000)
build="${RADMESH_FUZZ_BUILD:-$root/build-sanitize}"
work="$build/fuzz-work"
# RADMESH_FUZZ_TARGETS="a b" runs only those targets.
read -r -a targets <<< "${RADMESH_FUZZ_TARGETS:-fuzz_obj_reader fuzz_assimp_reader fuzz_json_scene fuzz_mgf_reader fuzz_mesh fuzz_gltf_nodes fuzz_numbers fuzz_writers}"
status=0
for t in "${targets[@]}"; do
  rm -rf "${work:?}/$t"
  mkdir -p "$work/$t/corpus"
  cp "$root/fuzz/corpus/$t/"* "$work/$t/corpus/"
  log="$work/$t/log.txt"
  if [ -n "$seconds" ]; then
    bound=(-max_total_time="$seconds")
  else
    bound=(-seed=1 -runs="${ci_runs[$t]}" -max_total_time=120)
  fi
  start=$SECONDS
  # The target's scratch files go in its working copy, not /tmp: an input
  # that crashes it leaves them there, beside the input.
  mkdir -p "$work/$t/tmp"
  if TMPDIR="$work/$t/tmp" "$build/fuzz/$t" "${bound[@]}" -timeout=10 -rss_limit_mb=4096 \
       -max_len=65536 -print_final_stats=1 -artifact_prefix="$work/$t/" "$work/$t/corpus" >"$log" 2>&1; then
    runs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")"
    cov="$(grep -o 'cov: [0-9]*' "$log" | tail -1)"
    echo "fuzz: $t: $runs inputs in $((SECONDS - start)) s, $cov, corpus $(ls "$work/$t/corpus" | wc -l) files: no defect"
  else
    status=1
    echo "fuzz: $t FAILED; the input: $(ls "$work/$t"/crash-* "$work/$t"/timeout-* "$work/$t"/leak-* "$work/$t"/oom-* 2>/dev/null | tr '\n' ' ')"
    { grep -A25 -m1 "ERROR\|radmesh fuzz\|timeout\|deadly" "$log" | head -40 | cut -c1-300; } || true
  fi
done
exit $status
