#!/usr/bin/env bash
# One process against `mpirun -np 1` and `-np 2` on this machine (docs/scaling.md): the built-in
# Cornell box, formfactors with the default correction, wall time of the whole command and the
# report's row time, and a check that the .ffm files are byte-identical.
#   bash tools/bench_mpi.sh [PATCHES] [RESOLUTION]      (default 5000 128; RUNS=3, the median is shown)
# Threads: the one-process run uses every core (--threads 0); under mpirun each rank's --threads 0
# is the node's cores over its ranks, so every run uses all cores.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${FFCUBE_BUILD_DIR:-build}"
patches="${1:-5000}"
resolution="${2:-128}"
runs="${RUNS:-3}"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
args="formfactors -q --patches $patches --resolution $resolution"
printf "%-14s %9s %9s %9s\n" run "wall (s)" "rows (s)" "rows/s"
launch() {
  case $1 in
    one) "$build/ffcube" $args -o "$dir/$1.ffm" --report "$dir/$1.json" ;;
    np1) mpirun --oversubscribe -np 1 "$build/ffcube" $args -o "$dir/$1.ffm" --report "$dir/$1.json" ;;
    np2) mpirun --oversubscribe -np 2 "$build/ffcube" $args -o "$dir/$1.ffm" --report "$dir/$1.json" ;;
  esac
}
# Interleaved (one, np1, np2, one, ...), so that a change in the machine's load hits every kind alike.
for r in $(seq "$runs"); do
  for run in one np1 np2; do
    start=$(date +%s.%N)
    launch $run
    end=$(date +%s.%N)
    python3 -c "import json; r=json.load(open('$dir/$run.json')); print($end-$start, r['seconds'], r['patches'])" \
      >> "$dir/$run.times"
  done
done
for run in one np1 np2; do
  python3 - "$dir/$run.times" "$run" <<'PY'
import statistics, sys
rows = [list(map(float, l.split())) for l in open(sys.argv[1])]
wall = statistics.median(r[0] for r in rows)
sec = statistics.median(r[1] for r in rows)
print(f"{sys.argv[2]:<14} {wall:>9.2f} {sec:>9.2f} {rows[0][2] / sec:>9.0f}")
PY
done
cmp "$dir/one.ffm" "$dir/np1.ffm" && cmp "$dir/one.ffm" "$dir/np2.ffm" && echo "the three .ffm files are byte-identical"
