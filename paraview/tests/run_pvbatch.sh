#!/usr/bin/env bash
# The ParaView plugin's test (ctest `paraview`): finds pvbatch (on PATH, in
# RADMESH_PARAVIEW_DIR, or unpacked from Debian's paraview and
# python3-paraview packages into BUILD/paraview-debs: installing them would
# remove libvtk9-dev), runs the radmesh program on the Cornell box and
# check_plugin.py against its radiosity.vtu. Exit 77 (skipped) with the
# reason when no pvbatch can be had or started.
# Usage: run_pvbatch.sh RADMESH_PROGRAM PYTHON_DIR DATA_DIR WORK_DIR [SCREENSHOT]
set -euo pipefail
radmesh=$1 pydir=$2 data=$3 work=$4 screenshot=${5:-}
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
skip() { echo "SKIPPED: $*"; exit 77; }

pvbatch=$(command -v pvbatch || true)
libs=""
if [ -z "$pvbatch" ]; then
  root=${RADMESH_PARAVIEW_DIR:-$work/paraview-debs}
  if [ ! -x "$root/usr/bin/pvbatch" ]; then
    command -v apt-get >/dev/null || skip "no pvbatch on PATH and no apt-get to fetch Debian's paraview"
    mkdir -p "$work/debs" "$root"
    (cd "$work/debs" && apt-get download paraview python3-paraview >/dev/null 2>&1) ||
      skip "no pvbatch on PATH, and apt-get download paraview python3-paraview failed (no network?)"
    for deb in "$work"/debs/*.deb; do dpkg -x "$deb" "$root"; done
  fi
  pvbatch=$root/usr/bin/pvbatch
  libs=$root/usr/lib/x86_64-linux-gnu:$root/usr/lib/x86_64-linux-gnu/paraview-5.11
  export PYTHONPATH=$root/usr/lib/python3/dist-packages${PYTHONPATH:+:$PYTHONPATH}
fi
export LD_LIBRARY_PATH=$libs${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
missing=$(ldd "$pvbatch" 2>/dev/null | grep "not found" || true)
[ -z "$missing" ] || skip "pvbatch cannot start, libraries missing: $missing"
export PYTHONPATH=$pydir:${PYTHONPATH:-}

scene=$data/cornell_box/cornell_box.obj
"$radmesh" run "$scene" -o "$work/cli" -q --no-png --epsilon 0.01 --max-edge 150 >/dev/null
run=("$pvbatch" "$here/check_plugin.py" "$here/../radmesh_paraview.py" "$scene" "$work/cli" $screenshot)
if [ -z "${DISPLAY:-}" ]; then
  command -v xvfb-run >/dev/null || skip "pvbatch needs a display and xvfb-run is missing"
  xvfb-run -a "${run[@]}"
else
  "${run[@]}"
fi
