#!/usr/bin/env bash
# Error in object radiosity against run time, uniform meshes against adaptive meshing (issue 16;
# docs/adaptive.md, docs/benchmarks.md). For the built-in Cornell box (or SCENE):
#   1. uniform solves at --max-patch-edge L for each L in UNIFORM (halving L halves the spacing);
#   2. the reference: Richardson extrapolation of the two finest uniform runs with order ORDER
#      (B* = B(L/2) + (B(L/2) − B(L)) / (2^p − 1); p = 1 without contact cuts, measured), or
#      REFERENCE_FINE / REFERENCE_COARSE (objects CSVs of an earlier pair of runs, the finer at half
#      the coarser's edge) when given; with three or more uniform runs it also prints the order
#      each object's last two steps show (log2 of the ratio of successive differences);
#   3. adaptive solves at each --target-error in TARGETS (budget MAX_ELEMENTS);
# and prints one markdown row per run: patches or elements, the command's wall time (report's
# time.total), and the largest and per-object relative error of the luminance of B against the
# reference.
#   tools/bench_adaptive.sh BUILD_DIR OUT_DIR [SCENE]
# Environment: UNIFORM="60 30 15", TARGETS="1e-2 1e-3", MAX_ELEMENTS=4000, REFERENCE_FINE, REFERENCE_COARSE,
# CONTACT_CUTS=auto|on|off (--contact-cuts of every run; auto: off for the default and uniform runs,
# on for the adaptive ones), ORDER=1.
set -euo pipefail
build=${1:?usage: bench_adaptive.sh BUILD_DIR OUT_DIR [SCENE]}
out=${2:?usage: bench_adaptive.sh BUILD_DIR OUT_DIR [SCENE]}
scene=${3:-}
uniform=${UNIFORM:-"60 30 15"}
targets=${TARGETS:-"1e-2 1e-3"}
max_elements=${MAX_ELEMENTS:-4000}
cuts=${CONTACT_CUTS:-auto}
order=${ORDER:-1}
mkdir -p "$out"
ffcube="$build/ffcube"
runs=()
"$ffcube" solve $scene -q --contact-cuts "$cuts" --objects "$out/default.csv" --report "$out/default.json"
runs+=(default)
for L in $uniform; do
    "$ffcube" solve $scene -q --contact-cuts "$cuts" --max-patch-edge "$L" --objects "$out/uniform_$L.csv" --report "$out/uniform_$L.json"
    runs+=("uniform_$L")
done
for t in $targets; do
    "$ffcube" solve $scene -q --contact-cuts "$cuts" --target-error "$t" --max-elements "$max_elements" --objects "$out/adaptive_$t.csv" \
        --report "$out/adaptive_$t.json"
    runs+=("adaptive_$t")
done
set -- $uniform
n=$#
fine=${REFERENCE_FINE:-$out/uniform_${!n}.csv}
prev=$((n - 1))
coarse=${REFERENCE_COARSE:-$out/uniform_${!prev}.csv}
uniform_csvs=""
for L in $uniform; do uniform_csvs="$uniform_csvs,$out/uniform_$L.csv"; done
python3 - "$out" "$fine" "$coarse" "$order" "${uniform_csvs#,}" "${runs[@]}" <<'PY'
import csv, json, math, sys
out, fine, coarse, order, series, runs = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4]), sys.argv[5], sys.argv[6:]
def objects(path):
    return {r["object"]: 0.2126 * float(r["B_r"]) + 0.7152 * float(r["B_g"]) + 0.0722 * float(r["B_b"])
            for r in csv.DictReader(open(path))}
f, c = objects(fine), objects(coarse)
ref = {o: f[o] + (f[o] - c[o]) / (2 ** order - 1) for o in f}  # Richardson, order p
names = list(ref)
print(f"reference: {fine} + ({fine} - {coarse}) / (2^{order:g} - 1)")
levels = [objects(p) for p in series.split(",")]
if len(levels) >= 3:  # observed order of the last two halvings, per object
    a, b, c3 = levels[-3], levels[-2], levels[-1]
    print("observed order: " + ", ".join(
        f"{o} {math.log2(abs((b[o] - a[o]) / (c3[o] - b[o]))):.2f}" if c3[o] != b[o] and b[o] != a[o] else f"{o} -"
        for o in names))
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
