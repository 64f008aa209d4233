#!/usr/bin/env bash
# Hemicube workers kept across adaptive levels against workers restarted per level (issue 16;
# docs/adaptive.md, docs/benchmarks.md). Runs the same adaptive solve twice, with the default
# (the first level's forked workers get each level's elements) and with --restart-workers, each
# under GNU time, checks that the per-element radiosity is the same bytes, and prints one markdown
# row per run: elements per level, each level's row-source setup (report
# adaptive.levels.setup_seconds: forking and starting workers, or sending them the new scene, plus
# the near-field correction's setup), each level's seconds, the wall time (time.total) and the CPU
# time (user + sys of ffcube and its worker processes).
#   tools/bench_keep_workers.sh BUILD_DIR OUT_DIR [extra ffcube solve options...]
# Environment: TARGET=1e-3, MAX_ELEMENTS=1500.
set -euo pipefail
build=${1:?usage: bench_keep_workers.sh BUILD_DIR OUT_DIR [options]}
out=${2:?usage: bench_keep_workers.sh BUILD_DIR OUT_DIR [options]}
shift 2
mkdir -p "$out"
target=${TARGET:-1e-3}
max_elements=${MAX_ELEMENTS:-1500}
for mode in keep restart; do
    flag=()
    [[ $mode == restart ]] && flag=(--restart-workers)
    /usr/bin/time -f "%U %S" -o "$out/$mode.time" "$build/ffcube" solve -q --target-error "$target" \
        --max-elements "$max_elements" "${flag[@]}" "$@" --radiosity "$out/$mode.csv" --report "$out/$mode.json"
done
if cmp -s "$out/keep.csv" "$out/restart.csv"; then same=yes; else same=NO; fi
echo "radiosity CSVs identical: $same"
echo "| workers | elements per level | setup s per level | level s | wall s | CPU s |"
echo "|---|---|---|---|---|---|"
for mode in keep restart; do
    python3 - "$out/$mode.json" "$out/$mode.time" "$mode" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
user, sys_ = map(float, open(sys.argv[2]).read().split()[-2:])
a = r["adaptive"]["levels"]
f = lambda xs: ", ".join(f"{x:.2f}" for x in xs)
name = "kept" if sys.argv[3] == "keep" else "restarted per level"
print(f"| {name} | {', '.join(map(str, a['elements']))} | {f(a['setup_seconds'])} | {f(a['seconds'])} "
      f"| {r['time']['total']:.1f} | {user + sys_:.1f} |")
EOF
done
[[ $same == yes ]]
