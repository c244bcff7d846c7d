#!/usr/bin/env bash
# Installs the Debian 12 packages mesh_refiner needs, only if some are missing.
# clang, its sanitizer and libFuzzer runtimes and llvm-symbolizer: scripts/fuzz.sh, sanitize.sh.
set -euo pipefail
PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libceres-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libopencv-dev libgtest-dev
  libegl-dev libgl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri
  colmap
  clang libclang-rt-14-dev llvm
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all packages present"
  exit 0
fi
echo "install_deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
