#!/usr/bin/env bash
# Runs commands alternately, ROUNDS times each, and prints the median and minimum of their wall
# and CPU seconds (user + sys of the command and the children it waits for, GNU time): the way
# to compare two builds on these shared, noisy machines (docs/benchmarks.md).
#   bash tools/interleave.sh ROUNDS "label|command" ["label|command" ...]
set -euo pipefail
rounds="$1"
shift
out="$(mktemp)"
trap 'rm -f "$out"' EXIT
for ((r = 0; r < rounds; r++)); do
  for spec in "$@"; do
    label="${spec%%|*}"
    cmd="${spec#*|}"
    # shellcheck disable=SC2086  # the command is split into words on purpose
    /usr/bin/time -f "$label %e %U %S" -a -o "$out" $cmd >/dev/null 2>&1
  done
done
python3 - "$out" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
for line in open(sys.argv[1]):
    label, wall, user, system = line.split()
    runs[label].append((float(wall), float(user) + float(system)))
for label, v in runs.items():
    w = [x[0] for x in v]
    c = [x[1] for x in v]
    print(f"{label:12s} wall median {statistics.median(w):.3f} min {min(w):.3f}  "
          f"cpu median {statistics.median(c):.3f} min {min(c):.3f}  n={len(v)}")
PY
