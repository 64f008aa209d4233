#!/usr/bin/env bash
# `mpirun -np 2 ffcube …` on scenes with obstruction-only surfaces (View3D's O, and the null N
# surface, which blocks as one; docs/scene-format.md, docs/scaling.md): every rank draws the whole
# scene (the broadcast carries Scene::drawn), computes its rows' obstructed shares, and rank 0
# gathers them for the sky:
#   1. formfactors .ffm (streamed) and .mtx (gathered) with --sky, --view3d, --elmer: the same
#      bytes as one process (cmp);
#   2. --checkpoint shards cut part-way (a killed run's state) and --resume: the same bytes;
#   3. solve --solver jacobi on two plates with an O plate between them: B within the two runs'
#      error bounds of one process (as tests/mpi/mpi_np2.sh derives), and the blocker's effect on
#      B larger than those bounds (so a rank that did not draw it would fail).
# Exit 77 (skipped) when mpirun is missing.
set -u
ffcube=$1
work=$2
. "${BASH_SOURCE[0]%/*}/mpi_env.sh"
examples="$(cd "$(dirname "$0")/../../examples" && pwd)"
rm -rf "$work" && mkdir -p "$work/tmp" && cd "$work" || exit 1
export TMPDIR="$work/tmp"

# Two unit-square-ish scenes: the lidded box (5 rows; the lid intercepts each row's 0.2 that would
# be sky), and a 2 x 2 wall with a null square (hole) facing another wall (3 rows; what would see
# the hole is blocked).
cat > hole.vs3 <<'VS3'
T wall with a null square facing another wall
F 3
V 1 0 0 0
V 2 2 0 0
V 3 2 2 0
V 4 0 2 0
V 5 0.5 0.5 0
V 6 1.5 0.5 0
V 7 1.5 1.5 0
V 8 0.5 1.5 0
V 9 0 0 1
V 10 2 0 1
V 11 2 2 1
V 12 0 2 1
S 1 1 2 3 4 0 0 0.9 wall
N 2 8 7 6 5 1 0 0.9 hole
S 3 9 12 11 10 0 0 0.9 opposite
End
VS3
outs() { echo "--sky $1.csv --view3d $1.txt --elmer $1.dat"; }
for scene in "$examples/lidded_box.vs3" hole.vs3; do
    name=$(basename "$scene" .vs3)
    job="$scene --no-subdivide --threads 1 -q"
    # 1. One process against two ranks, streamed (.ffm) and gathered (.mtx).
    "$ffcube" formfactors $job -o $name-one.ffm $(outs $name-one) || fail "$name: one process"
    "$ffcube" formfactors $job -o $name-one.mtx || fail "$name: one process .mtx"
    mpi formfactors $job -o $name-two.ffm $(outs $name-two) || fail "$name: mpirun .ffm"
    mpi formfactors $job -o $name-two.mtx $(outs $name-twom) || fail "$name: mpirun .mtx"
    for ext in ffm csv txt dat; do cmp $name-one.$ext $name-two.$ext || fail "$name: .$ext differs at -np 2"; done
    cmp $name-one.mtx $name-two.mtx || fail "$name: .mtx differs at -np 2"
    for ext in csv txt dat; do cmp $name-one.$ext $name-twom.$ext || fail "$name: .$ext (gathered) differs at -np 2"; done
    echo "ok: $name: F, --sky, --view3d, --elmer byte-identical at -np 2"
    # 2. Checkpoint shards, each log cut to half (a killed run leaves a prefix of its records,
    # possibly torn), then resumed.
    mpi formfactors $job -o $name-ck.ffm $(outs $name-ck) --checkpoint $name-ck || fail "$name: mpirun --checkpoint"
    for ext in ffm csv txt dat; do cmp $name-one.$ext $name-ck.$ext || fail "$name: checkpointed .$ext differs"; done
    for log in $name-ck/rank-*-of-2/rows.log; do truncate -s $(( $(stat -c %s "$log") / 2 )) "$log"; done
    mpi formfactors $job -o $name-res.ffm $(outs $name-res) --checkpoint $name-ck --resume --report $name-res.json ||
        fail "$name: mpirun --resume"
    for ext in ffm csv txt dat; do cmp $name-one.$ext $name-res.$ext || fail "$name: resumed .$ext differs"; done
    echo "ok: $name: checkpoint shards cut part-way and resumed, byte-identical"
done
[ -z "$(ls -A tmp)" ] || fail "spool left behind: $(ls -A tmp)"

# 3. Distributed Jacobi: a lit floor and a ceiling 1 above, a 0.6 x 0.6 O plate halfway between
# them (obstructing about a third of their exchange).
cat > plates.vs3 <<'VS3'
T floor and ceiling with an obstruction between
F 3
V 1 0 0 0
V 2 1 0 0
V 3 1 1 0
V 4 0 1 0
V 5 0 0 1
V 6 1 0 1
V 7 1 1 1
V 8 0 1 1
V 9 0.2 0.2 0.5
V 10 0.8 0.2 0.5
V 11 0.8 0.8 0.5
V 12 0.2 0.8 0.5
S 1 1 2 3 4 0 0 0.5 floor
S 2 5 8 7 6 0 0 0.5 ceiling
O 3 9 10 11 12 0 0 0.5 blocker
End
VS3
grep -v '^O ' plates.vs3 > open.vs3
printf 'floor,0.5,0.5,0.5,1,1,1\n' > lit.csv
solve="--materials lit.csv --max-patch-edge 0.25 --threads 1 -q --solver jacobi --tolerance 1e-6"
"$ffcube" solve plates.vs3 $solve --radiosity one.csv --report one.json || fail "one-process solve"
mpi solve plates.vs3 $solve --radiosity two.csv --report two.json || fail "mpirun solve"
"$ffcube" solve open.vs3 $solve --radiosity open.csv || fail "one-process solve without the blocker"
python3 - one.csv two.csv one.json two.json open.csv <<'PY' || fail "solve: B differs"
import csv, json, sys
one, two, open_ = (list(csv.DictReader(open(p))) for p in (sys.argv[1], sys.argv[2], sys.argv[5]))
b1, b2 = (json.load(open(p))["error_bound"]["mean_abs"] for p in sys.argv[3:5])
assert len(one) == len(two) == len(open_) and len(one) > 0
area = sum(float(r["area"]) for r in one)
for c, name in enumerate(("B_r", "B_g", "B_b")):
    mean = lambda a, b: sum(float(x["area"]) * abs(float(x[name]) - float(y[name])) for x, y in zip(a, b)) / area
    diff, blocked = mean(one, two), mean(one, open_)
    print(f"{name}: area-weighted mean |B_two - B_one| = {diff:.3e}, bound {b1[c] + b2[c]:.3e}; "
          f"the blocker moves B by {blocked:.3e}")
    assert diff <= b1[c] + b2[c], name
    assert blocked > 10 * (b1[c] + b2[c]), name
PY
echo "ok: distributed jacobi with an obstruction agrees with one process within its error bounds"
