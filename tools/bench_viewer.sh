#!/usr/bin/env bash
# Viewer throughput (issue 16, part 3): shots per second of `ffcube view` on the built-in Cornell
# box under xvfb-run, against the headless `ffcube solve` on the same rows (same solver, batch 16,
# forked hemicube workers). The viewer logs its shots and the seconds of the frames that shot;
# solve's report gives its shots and solver time. --batch 2 is the viewer's old default (one
# shooter per worker on 2 cores).
#   bash tools/bench_viewer.sh [RESOLUTION] [FRAMES]     (default 256 100)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${FFCUBE_BUILD_DIR:-build}"
resolution="${1:-256}"
frames="${2:-100}"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
view() {
  xvfb-run -a -s "-screen 0 1280x800x24" "$build/ffcube" view --frames "$frames" --size 640x400 \
    --resolution "$resolution" "$@" 2>&1 | sed -n 's/.* \([0-9]*\) shots in \([0-9.]*\) s of frames that shot.*/\1 \2/p'
}
printf "%-28s %8s %9s %9s\n" run shots seconds shots/s
for batch in 2 16; do
  read -r shots secs < <(view --batch "$batch")
  awk -v n="view --batch $batch" -v s="$shots" -v t="$secs" 'BEGIN { printf "%-28s %8d %9.2f %9.1f\n", n, s, t, s / t }'
done
# Headless: as many shots as the viewer's default run made, timed by solve's own report.
read -r shots _ < <(view)
"$build/ffcube" solve -q --resolution "$resolution" --max-iterations "$shots" --allow-unconverged \
  --report "$dir/solve.json" >/dev/null 2>&1 || true
python3 - "$dir/solve.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
shots, secs = r["shots"], r["time"]["solve_total"]  # from the first row asked to the last shot
print(f"{'solve (headless)':<28} {shots:>8} {secs:>9.2f} {shots / secs:>9.1f}")
PY
