#!/usr/bin/env bash
# Fuzzes the OBJ/MTL, STL and View3D loaders, the PLY and glTF pre-checks of the assimp path, the
# analytic kernel and the .ffm reader with libFuzzer under AddressSanitizer and
# UndefinedBehaviorSanitizer (docs/robustness.md).
#   1. installs clang-14, libclang-rt-14-dev (libFuzzer and the sanitizer runtimes) and llvm-14
#      (llvm-symbolizer, for readable stacks) when missing;
#   2. configures ./build-fuzz (or $FFCUBE_FUZZ_DIR) with clang++ and -DFFCUBE_FUZZ=ON and builds
#      only the fuzz targets (tests/fuzz/fuzz_*.cpp);
#   3. runs each target for $FFCUBE_FUZZ_SECONDS seconds (default 60) on a copy of its seed corpus
#      (tests/fuzz/corpus/NAME; the repository's corpus is never modified).
# FFCUBE_FUZZ_TARGETS="fuzz_ply fuzz_gltf" builds and runs only those (default: every target).
# A crash, a sanitizer report, a leak or an input slower than 10 s fails the script; libFuzzer
# leaves the input as crash-*/leak-*/timeout-* in the build directory's fuzz-artifacts/.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${FFCUBE_FUZZ_DIR:-build-fuzz}"
seconds="${FFCUBE_FUZZ_SECONDS:-60}"

missing=()
for p in clang-14 libclang-rt-14-dev llvm-14; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then missing+=("$p"); fi
done
if ((${#missing[@]})); then
  echo "fuzz: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 \
  -DCMAKE_CXX_COMPILER=clang++-14 -DFFCUBE_FUZZ=ON -DFFCUBE_BUILD_TESTS=OFF -DFFCUBE_BUILD_TOOLS=OFF \
  -DFFCUBE_BUILD_EXAMPLES=OFF
targets=()
if [ -n "${FFCUBE_FUZZ_TARGETS:-}" ]; then
  read -r -a targets <<<"$FFCUBE_FUZZ_TARGETS"
else
  for src in tests/fuzz/fuzz_*.cpp; do targets+=("$(basename "$src" .cpp)"); done
fi
cmake --build "$build_dir" -j "$(nproc)" --target "${targets[@]}"

# alloc_dealloc_mismatch=0: libfreeimage's exit-time mismatch (tools/sanitize.sh says why).
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:alloc_dealloc_mismatch=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export ASAN_SYMBOLIZER_PATH="${ASAN_SYMBOLIZER_PATH:-/usr/lib/llvm-14/bin/llvm-symbolizer}"
artifacts="$build_dir/fuzz-artifacts"
mkdir -p "$artifacts"
for t in "${targets[@]}"; do
  corpus_name="${t#fuzz_}"
  work="$build_dir/fuzz-corpus/$corpus_name"
  mkdir -p "$work"
  cp -n tests/fuzz/corpus/"$corpus_name"/* "$work"/ 2>/dev/null || true
  echo "fuzz: $t for ${seconds} s"
  "$build_dir/tests/fuzz/$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
    -artifact_prefix="$artifacts/$t-" -print_final_stats=1 "$work"
done
echo "fuzz: no findings"
