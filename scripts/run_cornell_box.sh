#!/usr/bin/env bash
# The main job: installs what is missing, builds radmesh (Release), meshes and
# solves the bundled Cornell box, and writes radiosity.vtu, radiosity.png and
# summary.json to out/cornell_box/ (or the directory given as $1).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$root/out/cornell_box}"
bash "$root/scripts/build.sh" --target radmesh
run=("$root/build/cli/radmesh" run "$root/data/cornell_box/cornell_box.obj" -o "$out")
# VTK renders through X: use a virtual display when there is no real one.
if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null 2>&1; then
  xvfb-run -a -s "-screen 0 1280x1024x24" "${run[@]}"
else
  "${run[@]}"
fi
echo "results are in $out (open radiosity.vtu in ParaView)"
