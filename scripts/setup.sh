#!/usr/bin/env bash
# Installs radmesh's build and run dependencies from Debian 12 packages.
# Does nothing when everything is already installed. Uses sudo only when not root.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev libpolyclipping-dev
  libembree-dev libtbb-dev libglm-dev
  libvtk9-dev
  libtinyobjloader-dev libassimp-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libx11-dev xvfb xauth
  python3-dev pybind11-dev python3-numpy python3-pytest python3-matplotlib  # the Python module, its tests and examples
  clang-14 libclang-rt-14-dev  # the sanitizer and fuzzing pass (scripts/sanitize.sh)
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} dependencies are installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  SUDO="sudo"
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
