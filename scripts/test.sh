#!/usr/bin/env bash
# Builds everything (installing missing dependencies first) and runs every
# test with ctest; then the sanitizer pass (scripts/sanitize.sh: the suite
# again under AddressSanitizer and UndefinedBehaviorSanitizer, and a bounded
# fuzzing run). RADMESH_SANITIZE=0 skips the sanitizer pass. The PNG tests
# need a display: a virtual one is used when there is none.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/build.sh"
cd "$root/build"
if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null 2>&1; then
  xvfb-run -a -s "-screen 0 1280x1024x24" ctest --output-on-failure -j 2
else
  ctest --output-on-failure -j 2
fi
if [ "${RADMESH_SANITIZE:-1}" != 0 ]; then
  bash "$root/scripts/sanitize.sh"
fi
