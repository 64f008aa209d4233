#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine for ffcube and builds it:
#   1. installs the Debian packages the build and the tests need (skipping what is present),
#   2. configures with CMake (Ninja, RelWithDebInfo) into ./build (or $FFCUBE_BUILD_DIR),
#   3. builds what the main job needs: the ffcube executable and the Python module
#      (FFCUBE_BUILD_ALL=1: everything, tests and tools included, as tools/test.sh asks).
# Safe to run again: it installs nothing twice and rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake ninja-build pkg-config git
  libglm-dev libfmt-dev nlohmann-json3-dev libcli11-dev
  libegl-dev libegl-mesa0 libgl-dev libgl1-mesa-dri libosmesa6 libosmesa6-dev
  libopenexr-dev libglfw3-dev libimgui-dev libembree-dev libstb-dev
  libgtest-dev libbenchmark-dev libassimp-dev libgmsh-dev python3-meshio
  xvfb xauth python3 python3-numpy python3-scipy python3-mpmath
  libzstd-dev python3-dev pybind11-dev python3-pybind11 libopenmpi-dev openmpi-bin
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all Debian packages present"
fi

build_dir="${FFCUBE_BUILD_DIR:-build}"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="${FFCUBE_BUILD_TYPE:-RelWithDebInfo}" ${FFCUBE_CMAKE_ARGS:-}
if [ "${FFCUBE_BUILD_ALL:-0}" = 1 ]; then
  cmake --build "$build_dir" -j "$(nproc)"
  echo "setup: built everything in $build_dir"
else
  targets=(ffcube)
  # The Python module, where CMake found pybind11 and Python's headers (src/python/CMakeLists.txt).
  if cmake --build "$build_dir" --target help | grep -q '^[^ ]*ffcube_python'; then targets+=(ffcube_python); fi
  cmake --build "$build_dir" -j "$(nproc)" --target "${targets[@]}"
  echo "setup: built $build_dir/ffcube (tests: bash tools/test.sh)"
fi
