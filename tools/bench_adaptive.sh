#!/usr/bin/env bash
# Error in object radiosity against run time, uniform meshes against adaptive meshing (issue 16;
# docs/adaptive.md, docs/benchmarks.md). For the built-in Cornell box (or SCENE):
#   1. uniform solves at --max-patch-edge L for each L in UNIFORM (halving L halves the spacing);
#   2. the reference: Richardson extrapolation of the two finest uniform runs with the measured
#      order p = 1 (B* = 2 B(L/2) − B(L)), or REFERENCE_FINE / REFERENCE_COARSE (objects CSVs of an
#      earlier pair of runs, the finer at half the coarser's edge) when given;
#   3. adaptive solves at each --target-error in TARGETS (budget MAX_ELEMENTS);
# and prints one markdown row per run: patches or elements, the command's wall time (report's
# time.total), and the largest and per-object relative error of the luminance of B against the
# reference.
#   tools/bench_adaptive.sh BUILD_DIR OUT_DIR [SCENE]
# Environment: UNIFORM="60 30 15", TARGETS="1e-2 1e-3", MAX_ELEMENTS=4000, REFERENCE_FINE, REFERENCE_COARSE.
set -euo pipefail
build=${1:?usage: bench_adaptive.sh BUILD_DIR OUT_DIR [SCENE]}
out=${2:?usage: bench_adaptive.sh BUILD_DIR OUT_DIR [SCENE]}
scene=${3:-}
uniform=${UNIFORM:-"60 30 15"}
targets=${TARGETS:-"1e-2 1e-3"}
max_elements=${MAX_ELEMENTS:-4000}
mkdir -p "$out"
ffcube="$build/ffcube"
runs=()
"$ffcube" solve $scene -q --objects "$out/default.csv" --report "$out/default.json"
runs+=(default)
for L in $uniform; do
    "$ffcube" solve $scene -q --max-patch-edge "$L" --objects "$out/uniform_$L.csv" --report "$out/uniform_$L.json"
    runs+=("uniform_$L")
done
for t in $targets; do
    "$ffcube" solve $scene -q --target-error "$t" --max-elements "$max_elements" --objects "$out/adaptive_$t.csv" \
        --report "$out/adaptive_$t.json"
    runs+=("adaptive_$t")
done
set -- $uniform
n=$#
fine=${REFERENCE_FINE:-$out/uniform_${!n}.csv}
prev=$((n - 1))
coarse=${REFERENCE_COARSE:-$out/uniform_${!prev}.csv}
python3 - "$out" "$fine" "$coarse" "${runs[@]}" <<'PY'
import csv, json, sys
out, fine, coarse, runs = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
def objects(path):
    return {r["object"]: 0.2126 * float(r["B_r"]) + 0.7152 * float(r["B_g"]) + 0.0722 * float(r["B_b"])
            for r in csv.DictReader(open(path))}
f, c = objects(fine), objects(coarse)
ref = {o: 2 * f[o] - c[o] for o in f}  # Richardson, order 1
names = list(ref)
print(f"reference: 2 x {fine} - {coarse}")
print("| run | patches/elements | time.total s | largest error | " + " | ".join(names) + " |")
print("|---|---|---|---|" + "---|" * len(names))
for run in runs:
    rep = json.load(open(f"{out}/{run}.json"))
    n = rep.get("adaptive", {}).get("elements", rep["patches"])
    b = objects(f"{out}/{run}.csv")
    err = {o: b[o] / ref[o] - 1 for o in names}
    worst = max(abs(e) for e in err.values())
    print(f"| {run} | {n} | {rep['time']['total']:.1f} | {worst*100:.2f}% | " +
          " | ".join(f"{err[o]*100:+.2f}%" for o in names) + " |")
PY
