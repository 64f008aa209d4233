#!/usr/bin/env bash
# End-to-end row rate of `ffcube formfactors` on the built-in Cornell box (issue 15, part 3: at
# least 2,000 rows/s at 5k patches, N=128, with the default correction), against the bare
# hemicubes (--correct none), each written to a streamed .ffm. Per run: rows/s of the row phase
# (the report's seconds), wall and CPU seconds of the whole run (the process and its worker
# processes, GNU time), peak resident memory, and where the CPU went: the worker processes'
# drawing and accumulation (the report's time.drawing, time.accumulation) against the correction
# (analysis and exact values, sender quadrature and merging: corrections.near_seconds and
# corrections.seconds, CPU summed over threads). BASELINE=path/to/ffcube runs an older build
# the same way in the same sitting, alternating with this one, for ratios (the machines are
# shared: compare within one run). Also checks that both builds wrote the same bytes.
#   bash tools/bench_rows.sh [PATCHES] [RESOLUTION] [REPEATS]     (default 5000 128 2)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${FFCUBE_BUILD_DIR:-build}"
patches="${1:-5000}"
resolution="${2:-128}"
repeats="${3:-2}"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
echo "Cornell box, --patches $patches, N=$resolution, $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
printf "%-9s %-8s %8s %8s %8s %8s %8s %8s %10s %10s\n" build correct rows/s "wall s" "cpu s" "peak MB" "draw s" "accum s" "correct s" "same bytes"
for rep in $(seq 1 "$repeats"); do
  for correct in near none; do
    for which in ${BASELINE:+baseline} current; do
      bin="$build/ffcube"
      [ "$which" = baseline ] && bin="$BASELINE"
      tag="$which-$correct"
      /usr/bin/time -f "%e %U %S %M" -o "$dir/$tag.time" "$bin" formfactors -q --patches "$patches" \
        --resolution "$resolution" --correct "$correct" -o "$dir/$tag.ffm" --report "$dir/$tag.json" 2>"$dir/$tag.log"
      same="-"
      if [ "$which" = current ] && [ -n "${BASELINE:-}" ]; then
        if cmp -s "$dir/baseline-$correct.ffm" "$dir/$tag.ffm"; then same=yes; else same=NO; fi
      fi
      python3 - "$dir/$tag.time" "$dir/$tag.json" "$which" "$correct" "$same" <<'PY'
import json, sys
wall, user, system, kib = map(float, open(sys.argv[1]).read().split()[-4:])
r = json.load(open(sys.argv[2]))
t, c = r["time"], r.get("corrections", {})
draw, accum = t.get("drawing", 0), t.get("accumulation", 0)
corr = c.get("near_seconds", 0) + c.get("seconds", 0)
print(f"{sys.argv[3]:<9} {sys.argv[4]:<8} {r['patches'] / r['seconds']:>8.0f} {wall:>8.2f} {user + system:>8.2f}"
      f" {kib / 1024:>8.0f} {draw:>8.2f} {accum:>8.2f} {corr:>10.2f} {sys.argv[5]:>10}")
PY
    done
  done
done
