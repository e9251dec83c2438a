#!/usr/bin/env bash
# Runs every libFuzzer target for a bounded time: scripts/fuzz.sh [SECONDS]
# (per target, default 30). Needs the sanitizer build in build-sanitize/
# (scripts/sanitize.sh makes it). Each target starts from its seed corpus
# (fuzz/corpus/<target>/) in a working copy under build-sanitize/fuzz-work/;
# an input that crashes, hangs (10 s) or leaks is written to
# build-sanitize/fuzz-work/<target>/crash-* and the script fails, naming it.
# Per target it prints executions, coverage and corpus size.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-30}"
build="$root/build-sanitize"
work="$build/fuzz-work"
targets=(fuzz_obj_reader fuzz_assimp_reader fuzz_json_scene fuzz_mesh)
status=0
for t in "${targets[@]}"; do
  rm -rf "${work:?}/$t"
  mkdir -p "$work/$t/corpus"
  cp "$root/fuzz/corpus/$t/"* "$work/$t/corpus/"
  log="$work/$t/log.txt"
  if "$build/fuzz/$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
       -max_len=65536 -print_final_stats=1 -artifact_prefix="$work/$t/" "$work/$t/corpus" >"$log" 2>&1; then
    runs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")"
    cov="$(grep -o 'cov: [0-9]*' "$log" | tail -1)"
    echo "fuzz: $t: $runs inputs in ${seconds} s, $cov, corpus $(ls "$work/$t/corpus" | wc -l) files: no defect"
  else
    status=1
    echo "fuzz: $t FAILED; the input: $(ls "$work/$t"/crash-* "$work/$t"/timeout-* "$work/$t"/leak-* "$work/$t"/oom-* 2>/dev/null | tr '\n' ' ')"
    grep -A25 -m1 "ERROR\|radmesh fuzz\|timeout\|deadly" "$log" | head -40 | cut -c1-300
  fi
done
exit $status
