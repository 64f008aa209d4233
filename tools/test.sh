#!/usr/bin/env bash
# Sets everything up (tools/setup.sh, building everything: the tests and tools too) and runs the
# whole test suite with CTest.
# Tests need no GPU: they run on Mesa's llvmpipe through EGL (surfaceless) and OSMesa.
set -euo pipefail
cd "$(dirname "$0")/.."
FFCUBE_BUILD_ALL=1 bash tools/setup.sh
build_dir="${FFCUBE_BUILD_DIR:-build}"
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)" "$@"
