#!/usr/bin/env bash
# .ffm version 2 streamed against the matrix held in memory (the test hook FFCUBE_TEST_IN_MEMORY;
# writing version 1 was retired at d9debc9, docs/benchmarks.md): seconds, peak resident
# memory (GNU time's maximum RSS, the largest of ffcube and its workers), file bytes and bytes per
# nonzero, on the built-in Cornell box. Usage: bash tools/bench_ffm.sh [PATCHES] [RESOLUTION] [SET]
# (default 20000 64 plain). SET "enforce": --enforce $ENFORCE (default reciprocity: the built-in
# Cornell box is open, closure is refused) streamed out of core, with the default and a 64 MiB
# budget (passes over the file, G's passes for closure, scratch MiB), against in memory. SCENE
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
variants=("v2-streamed:" "v2-streamed-64MiB:--stats-memory 64"
  "in-memory:--in-memory")
if [ "$set_" = enforce ]; then
  variants=("$mode-streamed:--enforce $mode" "$mode-streamed-64MiB:--enforce $mode --stats-memory 64"
    "$mode-in-memory:--enforce $mode --in-memory")
fi
for variant in "${variants[@]}"; do
  name=${variant%%:*}
  flags=${variant#*:}
  env=()
  if [[ $flags == *--in-memory* ]]; then env=(FFCUBE_TEST_IN_MEMORY=1); flags=${flags/--in-memory/}; fi
  # shellcheck disable=SC2086
  env "${env[@]}" /usr/bin/time -f '%e %M' -o "$dir/time" "$ffcube" formfactors $scene --patches "$patches" --resolution "$res" -q \
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
