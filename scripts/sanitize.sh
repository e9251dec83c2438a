#!/usr/bin/env bash
# The sanitizer pass: builds everything with clang, AddressSanitizer and
# UndefinedBehaviorSanitizer (and libFuzzer's coverage) in build-sanitize/,
# runs the whole test suite there (each fuzz target replays its corpus and
# past crashes as tests too), then fuzzes every target for a bounded time:
#   scripts/sanitize.sh [FUZZ_SECONDS_PER_TARGET]
# (none: the fixed CI fuzzing run of scripts/fuzz.sh; 0 skips fuzzing)
# Any sanitizer report, leak, crash or hang fails it.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-}"
bash "$root/scripts/setup.sh"
jobs="$(nproc 2>/dev/null || echo 2)"
CC=clang-14 CXX=clang++-14 cmake -S "$root" -B "$root/build-sanitize" -DCMAKE_BUILD_TYPE=Release \
  -DRADMESH_FUZZ=ON -DRADMESH_BUILD_BENCH=OFF >/dev/null
cmake --build "$root/build-sanitize" -j "$jobs"
cd "$root/build-sanitize"
if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null 2>&1; then
  xvfb-run -a -s "-screen 0 1280x1024x24" ctest --output-on-failure -j "$jobs" --timeout 1200
else
  ctest --output-on-failure -j "$jobs" --timeout 1200
fi
if [ "$seconds" != 0 ]; then
  bash "$root/scripts/fuzz.sh" ${seconds:+"$seconds"}
fi
