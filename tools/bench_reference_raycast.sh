#!/bin/bash
# The Cornell box's object-radiosity reference checked with the ray caster (issue 16; docs/adaptive.md,
# "The reference, checked with the ray caster"). Runs tools/bench_reference_raycast on each mesh with
# the hemicube and with the ray caster (two seeds), then prints Markdown tables: each object's mean
# luminance per run, hemicube against ray caster on the same mesh, and the extrapolations.
#
#   tools/bench_reference_raycast.sh BUILD OUT
#
# Environment (defaults in brackets):
#   RAYCAST   meshes for the ray caster ["D 30 D2 15"; D4 had not finished after 9 min CPU]; HEMICUBE meshes for the hemicube ["D 30 D2"]
#             (D: the default --patches 2000; 30, 15: --max-patch-edge; D2, D4: D with every patch
#             split 2 × 2, 4 × 4, nested)
#   SEEDS     ["1 2"]; SCALE divides every ray count [1] (SCALE=16: a quick look, 16× the noise²)
#   THREADS   [2]; runs go under nice -n 10. 60–125 s CPU per ray-cast mesh at SCALE=1 (L = 15 the most).
# Ray counts: about 1.3e8 rays per solve on the rows of patches that do not emit and 5e7 on the
# light's (docs/adaptive.md derives them: about 0.03% one-sigma on each object's mean per seed).
set -euo pipefail
BUILD=${1:?usage: tools/bench_reference_raycast.sh BUILD OUT}
OUT=${2:?usage: tools/bench_reference_raycast.sh BUILD OUT}
RAYCAST=${RAYCAST:-"D 30 D2 15"}
HEMICUBE=${HEMICUBE:-"D 30 D2"}
SEEDS=${SEEDS:-"1 2"}
SCALE=${SCALE:-1}
THREADS=${THREADS:-2}
TOOL="$BUILD/tools/bench_reference_raycast"
mkdir -p "$OUT"
mesh_args() {
    case $1 in
        D) echo "" ;; D2) echo "--split 2" ;; D4) echo "--split 4" ;;
        30|15) echo "--max-patch-edge $1" ;;
        *) echo "bench_reference_raycast.sh: unknown mesh $1 (D, 30, 15, D2, D4)" >&2; exit 2 ;;
    esac
}
# rays per row, other patches and light: 1.3e8 and 5e7 in all, split over 1995/4104/7980/15900/31920
# patches and 12/20/48/63/192 light patches
rays() {
    case $1 in
        D) echo "65536 4194304" ;; 30) echo "32768 2500000" ;; D2) echo "16384 1048576" ;;
        15) echo "8192 800000" ;; D4) echo "4096 262144" ;;
    esac
}
run() {
    local name=$1; shift
    /usr/bin/time -f "%U %S" -o "$OUT/$name.time" nice -n 10 "$TOOL" --threads "$THREADS" "$@" >"$OUT/$name.txt" 2>&1
    echo "$name: $(awk '{printf "%.1f s CPU", $1 + $2}' "$OUT/$name.time")" >&2
}
for m in $HEMICUBE; do run "hc_$m" --method hemicube $(mesh_args "$m"); done
for m in $RAYCAST; do
    read -r n l <<<"$(rays "$m")"
    run "rc_$m" --method raycast $(mesh_args "$m") --rays $((n / SCALE)) --light-rays $((l / SCALE)) --seeds "$SEEDS"
done
/usr/bin/python3 - "$OUT" "$HEMICUBE" "$RAYCAST" <<'EOF'
import csv, math, sys
out, hemi, ray = sys.argv[1], sys.argv[2].split(), sys.argv[3].split()
objs = ['floor', 'ceiling', 'back_wall', 'right_wall', 'left_wall', 'short_block', 'tall_block']
def load(name):
    lines = open(f'{out}/{name}.txt').read().splitlines()
    rows = csv.DictReader(lines[next(k for k, l in enumerate(lines) if l.startswith('object,')):])
    res = {}
    for r in rows:
        seeds = [float(r[c]) for c in r if c.startswith('seed_')]
        res[r['object']] = sum(seeds) / len(seeds)
        res[r['object'] + '/s'] = float(r['s_one_run_pct']) / 100 if 's_one_run_pct' in r else 0.0
    return res
hc = {m: load('hc_' + m) for m in hemi}
rc = {m: load('rc_' + m) for m in ray}
# sigma of a ray-cast mesh's mean over the seeds, pooled over the objects (one dof each per pair)
sig = {}
for m in ray:
    s1 = math.sqrt(sum(rc[m][o + '/s'] ** 2 for o in objs) / len(objs))
    nseeds = len(open(f'{out}/rc_{m}.txt').read().split('object,')[1].splitlines()[0].split('seed_')) - 1
    sig[m] = s1 / math.sqrt(max(nseeds, 1))
pct = lambda x: f'{100 * x:+.3f}%'
print('| run | ' + ' | '.join(objs) + ' |\n|---|' + '---|' * len(objs))
for m in hemi: print(f'| hemicube {m} | ' + ' | '.join(f'{hc[m][o]:.6f}' for o in objs) + ' |')
for m in ray: print(f'| ray caster {m} (σ {100 * sig[m]:.3f}%) | ' + ' | '.join(f'{rc[m][o]:.6f}' for o in objs) + ' |')
print('\n| hemicube / ray caster − 1, same mesh | ' + ' | '.join(objs) + ' |\n|---|' + '---|' * len(objs))
for m in hemi:
    if m in rc: print(f'| {m} (σ {100 * sig[m]:.3f}%) | ' + ' | '.join(pct(hc[m][o] / rc[m][o] - 1) for o in objs) + ' |')
refs = {}
for fine, coarse, src, name in [('15', '30', rc, 'ray caster 2 B(15) − B(30)'), ('D2', 'D', rc, 'ray caster 2 B(D2) − B(D)'),
                                 ('D4', 'D2', rc, 'ray caster 2 B(D4) − B(D2)'), ('D2', 'D', hc, 'hemicube 2 B(D2) − B(D)')]:
    if fine in src and coarse in src: refs[name] = {o: 2 * src[fine][o] - src[coarse][o] for o in objs}
finest = next((m for m in ['D4', '15', 'D2', '30', 'D'] if m in rc), None)
if finest:
    base = rc[finest]
    print(f'\n| against the ray caster on {finest} | ' + ' | '.join(objs) + ' |\n|---|' + '---|' * len(objs))
    for m in hemi: print(f'| hemicube {m} | ' + ' | '.join(pct(hc[m][o] / base[o] - 1) for o in objs) + ' |')
    for m in ray: print(f'| ray caster {m} | ' + ' | '.join(pct(rc[m][o] / base[o] - 1) for o in objs) + ' |')
    for n, r in refs.items(): print(f'| {n} | ' + ' | '.join(pct(r[o] / base[o] - 1) for o in objs) + ' |')
EOF
