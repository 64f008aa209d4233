#!/usr/bin/env bash
# Curved and finely tessellated meshes (issue 13, part 3): the default run (--correct near)
# against the plain rows (--correct none), timed whole by hyperfine in one run, as a ratio.
# The meshes are the OBJ corpus's (tests/scene/corpus: a Blender-like UV sphere with 6-decimal
# coordinates, a torus, a cylinder with fan caps, a box whose floor is shallow-angle triangles),
# written by the corpus test with FFCUBE_CORPUS_KEEP.
#   bash tools/bench_curved.sh [PATCHES] [RESOLUTION]     (default 3000 128; RUNS=3)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${FFCUBE_BUILD_DIR:-build}"
patches="${1:-3000}"
resolution="${2:-128}"
runs="${RUNS:-3}"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
FFCUBE_CORPUS_KEEP="$dir" "$build/tests/test_scene_corpus" --gtest_filter='*AtDefaultSettings' >/dev/null
printf "%-9s %8s %12s %12s %6s\n" mesh patches "near (s)" "none (s)" ratio
for mesh in sphere torus cylinder terrain; do
  args="formfactors -q $dir/$mesh.obj --patches $patches --resolution $resolution"
  hyperfine -N --runs "$runs" --export-json "$dir/$mesh.json" "$build/ffcube $args" "$build/ffcube $args --correct none" \
    >/dev/null 2>&1
  "$build/ffcube" $args --report "$dir/$mesh.report.json" 2>/dev/null
  python3 - "$dir/$mesh.json" "$dir/$mesh.report.json" "$mesh" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))["results"]
r = json.load(open(sys.argv[2]))
near, none = t[0]["median"], t[1]["median"]
print(f"{sys.argv[3]:<9} {r['patches']:>8} {near:>12.2f} {none:>12.2f} {near / none:>6.2f}")
PY
done
