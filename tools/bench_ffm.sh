#!/usr/bin/env bash
# .ffm version 2 streamed, at the default and a 64 MiB statistics budget (the in-memory path and its
# test hook FFCUBE_TEST_IN_MEMORY were retired after 2957dbb, issue 42: docs/benchmarks.md keeps
# their figures; writing version 1 was retired at d9debc9): seconds, peak resident
# memory (GNU time's maximum RSS, the largest of ffcube and its workers), file bytes and bytes per
# nonzero, on the built-in Cornell box. Usage: bash tools/bench_ffm.sh [PATCHES] [RESOLUTION] [SET]
# (default 20000 64 plain). SET "enforce": --enforce $ENFORCE (default reciprocity: the built-in
# Cornell box is open, closure is refused) streamed out of core, with the default and a 64 MiB
# budget (passes over the file, G's passes for closure, scratch MiB). SCENE
# names a scene file instead of the built-in box (e.g. SCENE=examples/cube.obj ENFORCE=closure).
# Needs build/ffcube and /usr/bin/time. Runs in a scratch directory.
# The streamed runs' peak is mostly the reciprocity check's bands (--stats-memory, default 512 MiB):
# the second variant gives them 64 MiB, at the price of more passes over the file.
set -euo pipefail
patches=${1:-20000}
res=${2:-64}
set_=${3:-plain}
mode=${ENFORCE:-reciprocity}
scene=${SCENE:+$(realpath "$SCENE")}
ffcube=${FFCUBE:-$(cd "$(dirname "$0")/.." && pwd)/build/ffcube}
dir=$(mktemp -d /tmp/bench_ffm.XXXXXX)
trap 'rm -rf "$dir"' EXIT
printf '%-28s %10s %10s %14s %10s %12s %s\n' variant seconds peak_MB file_bytes B/nnz nnz passes
variants=("v2-streamed:" "v2-streamed-64MiB:--stats-memory 64")
if [ "$set_" = enforce ]; then
  variants=("$mode-streamed:--enforce $mode" "$mode-streamed-64MiB:--enforce $mode --stats-memory 64")
fi
for variant in "${variants[@]}"; do
  name=${variant%%:*}
  flags=${variant#*:}
  # shellcheck disable=SC2086
  /usr/bin/time -f '%e %M' -o "$dir/time" "$ffcube" formfactors $scene --patches "$patches" --resolution "$res" -q \
    $flags -o "$dir/$name.ffm" --report "$dir/$name.json"
  read -r secs kib < "$dir/time"
  bytes=$(stat -c %s "$dir/$name.ffm")
  nnz=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['nnz'])" "$dir/$name.json")
  # Passes over the written (or, with --enforce, the computed rows') file; G's passes; scratch bytes.
  passes=$(python3 -c "import json,sys; r=json.load(open(sys.argv[1])); e=r.get('enforce',{}); c=r.get('reciprocity',{})
print(f\"file:{e.get('passes',c.get('passes','-'))} G:{e.get('g_passes','-')} scratch_MB:{(e.get('scratch_bytes',c.get('scratch_bytes',0)))/2**20:.0f}\")" "$dir/$name.json")
  awk -v n="$name" -v s="$secs" -v k="$kib" -v b="$bytes" -v z="$nnz" -v p="$passes" \
    'BEGIN { printf "%-28s %10.1f %10.0f %14d %10.2f %12d %s\n", n, s, k / 1024, b, b / z, z, p }'
done
