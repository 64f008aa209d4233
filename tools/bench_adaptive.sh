#!/usr/bin/env bash
# Error in object radiosity against run time, uniform meshes against adaptive meshing (issue 16;
# docs/adaptive.md, docs/benchmarks.md). For the built-in Cornell box (or SCENE):
#   1. uniform solves at --max-patch-edge L for each L in UNIFORM (halving L halves the spacing);
#   2. the reference: Richardson extrapolation of the two finest uniform runs with order ORDER
#      (B* = B(L/2) + (B(L/2) − B(L)) / (2^p − 1); p = 1 without contact cuts, measured), or
#      REFERENCE_FINE / REFERENCE_COARSE (objects CSVs of an earlier pair of runs, the finer at half
#      the coarser's edge) when given; with three or more uniform runs it also prints the order
#      each object's last two steps show (log2 of the ratio of successive differences);
#   3. adaptive solves at each --target-error in TARGETS (budget MAX_ELEMENTS), with rows carried
#      between levels;
# and prints one markdown row per run: patches or elements, the command's wall time (report's
# time.total), and the largest and per-object relative error of the luminance of B against the
# reference; OUT_DIR/error_vs_time.svg plots the largest error against time.total, uniform and
# adaptive runs as two series.
#   tools/bench_adaptive.sh BUILD_DIR OUT_DIR [SCENE]
# Environment: UNIFORM="60 30 15", TARGETS="1e-2 1e-3", MAX_ELEMENTS=4000, REFERENCE_FINE, REFERENCE_COARSE,
# CONTACT_CUTS=auto|on|off (--contact-cuts of every run; auto, the default: cut wherever an object
# stands on another), ORDER=1, STARTS=coarse (adaptive starting meshes:
# coarse, the start of about 500 patches, or N: --patches N; e.g. STARTS="coarse 2000" for both; runs
# from N are named adaptive_T_startN).
set -euo pipefail
build=${1:?usage: bench_adaptive.sh BUILD_DIR OUT_DIR [SCENE]}
out=${2:?usage: bench_adaptive.sh BUILD_DIR OUT_DIR [SCENE]}
scene=${3:-}
uniform=${UNIFORM:-"60 30 15"}
targets=${TARGETS:-"1e-2 1e-3"}
max_elements=${MAX_ELEMENTS:-4000}
cuts=${CONTACT_CUTS:-auto}
order=${ORDER:-1}
starts=${STARTS:-coarse}
mkdir -p "$out"
ffcube="$build/ffcube"
runs=()
# solve NAME ARGS...: one run, its CPU time (user + sys of ffcube and its worker processes, GNU
# time) in OUT/NAME.cpu when /usr/bin/time is there.
solve() {
    local name=$1; shift
    local timer=()
    [ -x /usr/bin/time ] && timer=(/usr/bin/time -f "%U %S" -o "$out/$name.cpu")
    "${timer[@]}" "$ffcube" solve $scene -q --contact-cuts "$cuts" "$@" --objects "$out/$name.csv" --report "$out/$name.json"
}
solve default
runs+=(default)
for L in $uniform; do
    solve "uniform_$L" --max-patch-edge "$L"
    runs+=("uniform_$L")
done
for t in $targets; do
    for s in $starts; do
        name="adaptive_$t"; flag=""
        if [ "$s" != coarse ]; then name="${name}_start$s"; flag="$flag --patches $s"; fi
        solve "$name" --target-error "$t" --max-elements "$max_elements" $flag
        runs+=("$name")
    done
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
print("| run | patches/elements | time.total s | CPU s | largest error | " + " | ".join(names) + " |")
print("|---|---|---|---|---|" + "---|" * len(names))
points = []
for run in runs:
    rep = json.load(open(f"{out}/{run}.json"))
    n = rep.get("adaptive", {}).get("elements", rep["patches"])
    b = objects(f"{out}/{run}.csv")
    err = {o: b[o] / ref[o] - 1 for o in names}
    worst = max(abs(e) for e in err.values())
    try:
        cpu = f"{sum(float(x) for x in open(f'{out}/{run}.cpu').read().split()[-2:]):.1f}"
    except (OSError, ValueError):
        cpu = "-"
    print(f"| {run} | {n} | {rep['time']['total']:.1f} | {cpu} | {worst*100:.2f}% | " +
          " | ".join(f"{err[o]*100:+.2f}%" for o in names) + " |")
    points.append((run, rep["time"]["total"], max(worst, 1e-6)))
# error_vs_time.svg: log-log, uniform (and default) runs in blue, adaptive runs in red.
W, H, M = 640, 420, 60
ts = [p[1] for p in points]; es = [p[2] for p in points]
t0, t1 = math.log10(min(ts)) - 0.1, math.log10(max(ts)) + 0.1
e0, e1 = math.log10(min(es)) - 0.1, math.log10(max(es)) + 0.1
X = lambda t: M + (math.log10(t) - t0) / (t1 - t0) * (W - 2 * M)
Y = lambda e: H - M - (math.log10(e) - e0) / (e1 - e0) * (H - 2 * M)
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="11">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<line x1="{M}" y1="{H-M}" x2="{W-M}" y2="{H-M}" stroke="black"/><line x1="{M}" y1="{M}" x2="{M}" y2="{H-M}" stroke="black"/>',
       f'<text x="{W/2}" y="{H-15}" text-anchor="middle">time.total (s, log)</text>',
       f'<text x="15" y="{H/2}" transform="rotate(-90 15 {H/2})" text-anchor="middle">largest object error (log)</text>']
for series, colour in (("uniform", "#1f77b4"), ("adaptive", "#d62728")):
    pts = sorted((p for p in points if p[0].startswith("adaptive") == (series == "adaptive")), key=lambda p: p[1])
    if pts:
        svg.append(f'<polyline fill="none" stroke="{colour}" points="' + " ".join(f"{X(t):.1f},{Y(e):.1f}" for _, t, e in pts) + '"/>')
    for name, t, e in pts:
        svg.append(f'<circle cx="{X(t):.1f}" cy="{Y(e):.1f}" r="3" fill="{colour}"/>'
                   f'<text x="{X(t)+5:.1f}" y="{Y(e)-5:.1f}">{name} {e*100:.2f}%</text>')
svg.append('</svg>')
open(f"{out}/error_vs_time.svg", "w").write("\n".join(svg))
print(f"wrote {out}/error_vs_time.svg")
PY
