#!/bin/sh
# ctest's replay of a fuzz target: runs the command after the first argument
# with TMPDIR set to that folder, made empty first, and fails when the
# command fails or leaves anything in it (the target's scratch folder must
# be gone at exit).
set -eu
scratch="$1"
shift
rm -rf "$scratch"
mkdir -p "$scratch"
TMPDIR="$scratch" "$@"
left="$(ls -A "$scratch")"
if [ -n "$left" ]; then
  echo "fuzz replay: left behind in $scratch: $left" >&2
  exit 1
fi
rmdir "$scratch"
