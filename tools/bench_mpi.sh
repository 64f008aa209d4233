#!/usr/bin/env bash
# One process against `mpirun -np 1` and `-np 2` on this machine (docs/scaling.md): the built-in
# Cornell box, formfactors with the default correction, wall time of the whole command, the
# report's row time, the peak resident memory of the process that writes (one process: ffcube with
# its forked workers, the largest of them; under mpirun: rank 0, measured by /usr/bin/time around
# each rank), and a check that the .ffm files are byte-identical.
#   bash tools/bench_mpi.sh [PATCHES] [RESOLUTION]      (default 5000 128; RUNS=3, the median is shown)
# FFCUBE_BIN=path: another ffcube binary for the mpirun runs (e.g. one built from an older commit,
# to compare rank 0's memory before and after a change; the one-process run uses the build's).
# KINDS="one np2": only those runs (default "one np1 np2").
# Threads: the one-process run uses every core (--threads 0); under mpirun each rank's --threads 0
# is the node's cores over its ranks, so every run uses all cores.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${FFCUBE_BUILD_DIR:-build}"
patches="${1:-5000}"
resolution="${2:-128}"
runs="${RUNS:-3}"
kinds="${KINDS:-one np1 np2}"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
args="formfactors -q --patches $patches --resolution $resolution"
mpibin="${FFCUBE_BIN:-$build/ffcube}"
printf "%-14s %9s %9s %9s %14s\n" run "wall (s)" "rows (s)" "rows/s" "peak RSS (MB)"
# Each rank under /usr/bin/time, its peak resident set (KiB) in $dir/RUN.rss.RANK.
ranked() {
  local run=$1; shift
  mpirun --oversubscribe -np "$1" bash -c '/usr/bin/time -f %M -o "$0.rss.$OMPI_COMM_WORLD_RANK" "$@"' \
    "$dir/$run" "$mpibin" $args -o "$dir/$run.ffm" --report "$dir/$run.json"
}
launch() {
  case $1 in
    one) /usr/bin/time -f %M -o "$dir/$1.rss.0" "$build/ffcube" $args -o "$dir/$1.ffm" --report "$dir/$1.json" ;;
    np1) ranked "$1" 1 ;;
    np2) ranked "$1" 2 ;;
  esac
}
# Interleaved (one, np1, np2, one, ...), so that a change in the machine's load hits every kind alike.
for r in $(seq "$runs"); do
  for run in $kinds; do
    start=$(date +%s.%N)
    launch $run
    end=$(date +%s.%N)
    python3 -c "import json; r=json.load(open('$dir/$run.json')); print($end-$start, r['seconds'], r['patches'], \
      int(open('$dir/$run.rss.0').read().split()[-1]) / 1024)" >> "$dir/$run.times"
  done
done
for run in $kinds; do
  python3 - "$dir/$run.times" "$run" <<'PY'
import statistics, sys
rows = [list(map(float, l.split())) for l in open(sys.argv[1])]
wall = statistics.median(r[0] for r in rows)
sec = statistics.median(r[1] for r in rows)
rss = statistics.median(r[3] for r in rows)
print(f"{sys.argv[2]:<14} {wall:>9.2f} {sec:>9.2f} {rows[0][2] / sec:>9.0f} {rss:>14.0f}")
PY
done
set -- $kinds
for run in "${@:2}"; do cmp "$dir/$1.ffm" "$dir/$run.ffm"; done
echo "the .ffm files of $kinds are byte-identical"
