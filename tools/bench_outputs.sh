#!/usr/bin/env bash
# Peak memory of the outputs other tools read (.mtx, Elmer's ViewFactors.dat, View3D's file)
# written from the row stream, against a reference binary that held the whole matrix for them
# (e.g. a build from before the streamed writers), and whether both wrote the same bytes (cmp).
# Seconds and peak resident memory from GNU time (the largest of ffcube and its workers), on the
# built-in Cornell box. Usage: bash tools/bench_outputs.sh [PATCHES] [RESOLUTION] (default 20000
# 32). FFCUBE: the binary measured (default build/ffcube); REFERENCE: a second binary to measure
# and compare with (optional); STATS_MEMORY: --stats-memory MiB for both (default 64: the streamed
# run's reciprocity band, which at the default 512 would hold every entry of a 20k-patch run and
# hide the difference). Needs /usr/bin/time. Runs in a scratch directory.
set -euo pipefail
patches=${1:-20000}
res=${2:-32}
ffcube=${FFCUBE:-$(cd "$(dirname "$0")/.." && pwd)/build/ffcube}
reference=${REFERENCE:-}
stats=${STATS_MEMORY:-64}
dir=$(mktemp -d /tmp/bench_outputs.XXXXXX)
trap 'rm -rf "$dir"' EXIT
printf '%-10s %10s %10s %12s %14s %s\n' binary seconds peak_MB nnz mtx_bytes streamed
binaries=("new:$ffcube")
[ -n "$reference" ] && binaries+=("reference:$reference")
for b in "${binaries[@]}"; do
  name=${b%%:*}
  bin=${b#*:}
  /usr/bin/time -f '%e %M' -o "$dir/time" "$bin" formfactors --patches "$patches" --resolution "$res" -q --stats-memory "$stats" \
    -o "$dir/$name.mtx" --elmer "$dir/$name.dat" --view3d "$dir/$name.vf" --report "$dir/$name.json"
  read -r secs kib < "$dir/time"
  python3 -c "import json,sys,os; r=json.load(open(sys.argv[1]))
print('%-10s %10s %10.0f %12d %14d %s' % (sys.argv[2], sys.argv[3], int(sys.argv[4])/1024, r['nnz'], os.path.getsize(sys.argv[5]), r['streamed']))" \
    "$dir/$name.json" "$name" "$secs" "$kib" "$dir/$name.mtx"
done
if [ -n "$reference" ]; then
  for ext in mtx dat vf; do
    cmp "$dir/new.$ext" "$dir/reference.$ext" && echo "$ext: same bytes"
  done
fi
