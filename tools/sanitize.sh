#!/usr/bin/env bash
# Builds ffcube with AddressSanitizer + UndefinedBehaviorSanitizer (g++, -DFFCUBE_SANITIZE=ON) in
# ./build-asan (or $FFCUBE_ASAN_DIR) and runs the whole test suite there. Any sanitizer report
# fails the test that triggered it (undefined behaviour aborts: -fno-sanitize-recover).
# Installs missing Debian packages first, like tools/setup.sh (which it reuses).
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${FFCUBE_ASAN_DIR:-build-asan}"
FFCUBE_BUILD_DIR="$build_dir" FFCUBE_CMAKE_ARGS="-DFFCUBE_SANITIZE=ON ${FFCUBE_CMAKE_ARGS:-}" bash tools/setup.sh

# Leak checking stays on for ffcube's code. Mesa (llvmpipe, the EGL/OSMesa drivers, LLVM's JIT)
# keeps process-lifetime allocations that it never frees and that are not ffcube's to free: they
# are suppressed by library in tools/lsan.supp. Hemicube worker processes end with _Exit, which
# skips LeakSanitizer's exit hook, so they report nothing either way.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/tools/lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)" "$@"
