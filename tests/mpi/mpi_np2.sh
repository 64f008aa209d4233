#!/usr/bin/env bash
# `mpirun -np 2 ffcube …` on one machine against the one-process run (docs/scaling.md):
#   1. formfactors .ffm and .mtx: byte-identical (cmp);
#   2. with --checkpoint (a shard per rank): byte-identical; a rank killed with SIGKILL part-way
#      makes mpirun fail (non-zero, no output file), and --resume finishes it, byte-identical;
#   3. solve --solver jacobi and gauss-seidel over 2 ranks against one process: the area-weighted
#      L1 difference of B within the two runs' error bounds (derivation below).
# Exit 77 (skipped) when mpirun is missing.
set -u
ffcube=$1
work=$2
. "${BASH_SOURCE[0]%/*}/mpi_env.sh"
descendants() { for c in $(ps -o pid= --ppid "$1"); do echo "$c"; descendants "$c"; done; }
scene="$(cd "$(dirname "$0")/../../examples" && pwd)/cube.obj"
rm -rf "$work" && mkdir -p "$work/tmp" && cd "$work" || exit 1
# Where the ranks spool their rows without --checkpoint (docs/scaling.md): checked empty after runs.
export TMPDIR="$work/tmp"
rows="$scene --patches 600 --resolution 64 --threads 1 -q"

# 1. Byte-identical outputs.
"$ffcube" formfactors $rows -o one.ffm --report one.json || fail "one-process formfactors"
"$ffcube" formfactors $rows -o one.mtx || fail "one-process formfactors .mtx"
mpi formfactors $rows -o two.ffm --report two.json || fail "mpirun formfactors"
mpi formfactors $rows -o two.mtx || fail "mpirun formfactors .mtx"
cmp one.ffm two.ffm || fail ".ffm differs"
cmp one.mtx two.mtx || fail ".mtx differs"
echo "ok: .ffm and .mtx byte-identical at -np 2"
# Without a matrix file rank 0 holds the rows in memory for the statistics: the same feed.
# Each row's estimates travel with it in rank 1's chunks (RowSide): the patch table's error column
# is every row's, as one process's.
"$ffcube" formfactors $rows --groups one-g.csv --sky one-sky.csv --patch-table one-t.csv || fail "one-process formfactors without -o"
mpi formfactors $rows --groups two-g.csv --sky two-sky.csv --patch-table two-t.csv || fail "mpirun formfactors without -o"
cmp one-g.csv two-g.csv || fail "--groups differs without -o"
cmp one-sky.csv two-sky.csv || fail "--sky differs without -o"
head -1 one-t.csv | grep -q ',error_estimate$' || fail "no error column in the patch table"
cmp one-t.csv two-t.csv || fail "--patch-table differs (the estimates of rank 1's rows?)"
echo "ok: --groups, --sky and --patch-table byte-identical at -np 2 without a matrix file"
# The report's per-row figures (estimates, tolerance distribution, how each row was measured) are
# every row's too: equal to one process's, none missing.
python3 - one.json two.json <<'PY' || fail "the report's per-row figures under mpirun differ from one process's"
import json, sys
one, two = (json.load(open(f)) for f in sys.argv[1:])
a, b = one["row_error_estimate"]["rows"], two["row_error_estimate"]["rows"]
assert len(a) == 600 and min(a) >= 0 and a == b, "row_error_estimate.rows"
assert one["corrections"]["row_measure"] == two["corrections"]["row_measure"] and min(one["corrections"]["row_measure"]) >= 0
for k in ("max", "mean", "worst_row"):
    assert one["row_error_estimate"][k] == two["row_error_estimate"][k], k
PY
echo "ok: the report's per-row estimates and measures under mpirun are every row's, equal to one process's"
# The .ffm goes through the streamed writer under mpirun too: rank 0 takes rank 1's rows in chunks,
# and no scratch or spool directory is left beside the output.
python3 -c "import json,sys; r=json.load(open(sys.argv[1])); assert r['streamed'] and r['mpi']['streamed'], r" \
    two.json || fail "the .ffm run under mpirun was not streamed"
[ -z "$(ls -A | grep scratch)" ] && [ -z "$(ls -A tmp)" ] || fail "scratch left behind: $(ls -A . tmp)"
# The providers' statistics (core/stats.hpp) count every rank's rows: each rank's set is merged onto
# rank 0's, so every counter of the hemicube and the correction equals the one-process run's (the
# ranks' blocks partition the rows, and on this scene a row's counts do not depend on the process
# that made it). Floating-point figures (timings, weights: sums in another order) are left out.
python3 - one.json two.json <<'PY' || fail "the report's counters under mpirun differ from one process's"
import json, sys
def ints(d, p=""):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from ints(v, p + k + ".")
        elif isinstance(v, int) and not isinstance(v, bool):
            yield p + k, v
one, two = (json.load(open(f)) for f in sys.argv[1:])
sets = ("hemicubes", "corrections.", "left_out.", "drawn.", "sub_hemicube_rows", "rows_not_rendered", "self_hits", "upload.",
        "analytic.")
a = {k: v for k, v in ints(one) if k.startswith(sets)}
b = {k: v for k, v in ints(two) if k.startswith(sets)}
assert len(a) > 30 and a == b, {k: (a.get(k), b.get(k)) for k in set(a) | set(b) if a.get(k) != b.get(k)}
assert a["hemicubes"] == 600, a["hemicubes"]  # one hemicube a patch: no row is sub-sampled here
assert a["analytic.calls"] > 0, a  # the near-field correction's exact values (the kernels' process totals)
PY
echo "ok: the report's counters under mpirun are every rank's, equal to one process's"
# The ray caster's too: at a fixed count each row traces its rays (and its re-traces past its own
# plane, a property of the row), so the rays traced over the ranks are the one-process total.
"$ffcube" formfactors $rows --method raycast --set rays=256 -o one-rays.ffm --report one-rays.json || fail "one-process rays"
mpi formfactors $rows --method raycast --set rays=256 -o two-rays.ffm --report two-rays.json || fail "mpirun rays"
cmp one-rays.ffm two-rays.ffm || fail "ray-cast .ffm differs"
python3 -c "import json,sys; a,b=(json.load(open(f)) for f in sys.argv[1:]); assert a['rays_traced']>=600*256 and a['rays_traced']==b['rays_traced'], (a['rays_traced'], b['rays_traced'])" \
    one-rays.json two-rays.json || fail "rays_traced under mpirun differs from one process's"
echo "ok: ray-cast rows byte-identical and rays_traced every rank's at -np 2"

# 1b. --enforce on the streamed path (out of core: 1 MiB of --stats-memory cuts the transpose of
# these 600 rows, about 3 MB of entries, into bands spilled to scratch files), against one process.
for e in reciprocity closure; do
    "$ffcube" formfactors $rows -o one-$e.ffm --enforce $e --stats-memory 1 || fail "one-process --enforce $e"
    mpi formfactors $rows -o two-$e.ffm --enforce $e --stats-memory 1 || fail "mpirun --enforce $e"
    cmp one-$e.ffm two-$e.ffm || fail "--enforce $e: .ffm differs"
done
echo "ok: --enforce reciprocity and closure byte-identical at -np 2 (streamed, out of core)"
# Closure is judged on every rank's rows: the cube with a plate outside it, whose rows (the last
# ones: rank 1's block) see nothing, is refused with the one-process error (rank 0's rows alone are
# closed: judged on them, the run went on to fail later with another message).
cp "$scene" open.obj
printf 'o outside\nv 3 0 0\nv 4 0 0\nv 4 1 0\nv 3 1 0\nf 25 26 27 28\n' >> open.obj
"$ffcube" formfactors open.obj --patches 600 --resolution 64 --threads 1 -q -o open-one.ffm --enforce closure 2> open-one.txt
rc=$?
one_err=$(grep "error:" open-one.txt) && grep -q "saw nothing" open-one.txt && [ "$rc" -eq 2 ] && [ ! -e open-one.ffm ] ||
    fail "open scene with --enforce closure, one process: rc $rc, $(cat open-one.txt)"
# Both outputs under mpirun (one path: rank 0 takes the ranks' rows in chunks for either).
for out in open-two.ffm open-two.mtx; do
    mpi formfactors open.obj --patches 600 --resolution 64 --threads 1 -q -o $out --enforce closure 2> open-two.txt
    rc=$?
    [ "$rc" -eq 2 ] && [ ! -e $out ] && grep -qF "$one_err" open-two.txt ||
        fail "open scene, -o $out at -np 2: rc $rc, $(cat open-two.txt), not: $one_err"
done
echo "ok: an open scene's closure refused at -np 2 as in one process"

# Bad input under mpirun: rank 0's error, exit 2 from mpirun (MPI_Abort(2) ends every rank).
mpi formfactors missing.obj -o bad.ffm 2> bad.txt
rc=$?
[ "$rc" -eq 2 ] && grep -q "missing.obj: cannot read" bad.txt && [ ! -e bad.ffm ] || fail "missing scene: rc $rc, $(cat bad.txt)"
mpi solve $rows --solver shoot 2> bad.txt
rc=$?
[ "$rc" -eq 2 ] && grep -q "only jacobi and gauss-seidel" bad.txt || fail "shoot under mpirun: rc $rc, $(cat bad.txt)"
mpi view --patches 50 2> bad.txt
rc=$?
[ "$rc" -eq 2 ] && grep -q "only formfactors and solve" bad.txt || fail "view under mpirun: rc $rc, $(cat bad.txt)"
echo "ok: bad input under mpirun exits 2 with the error"

# 2. Checkpoint shards, a killed rank, resume.
mpi formfactors $rows -o ck.ffm --checkpoint ck || fail "mpirun with --checkpoint"
cmp one.ffm ck.ffm || fail "checkpointed .ffm differs"
[ -f ck/rank-0-of-2/rows.log ] && [ -f ck/rank-1-of-2/rows.log ] || fail "no shard per rank"
# Big enough that rank 1 is still computing when killed (2,000 rows of N = 128 on one thread each,
# a few seconds on llvmpipe), small enough for a test.
big="$scene --patches 4000 --resolution 128 --threads 1 -q"
"$ffcube" formfactors $big -o big-one.ffm || fail "one-process formfactors (big)"
# Starts `mpi formfactors $big ARGS...` and kills rank 1 with SIGKILL as soon as the file its rows go
# to (a glob) has some: rank 1 is the descendant of mpirun whose environment says so. Sets rc to
# mpirun's exit status.
kill_rank1() {
    local rows_file=$1; shift
    mpi formfactors $big "$@" &
    local launcher=$! victim=""
    for _ in $(seq 1 3000); do
        if [ -z "$victim" ]; then
            for p in $(descendants "$launcher"); do
                { tr '\0' '\n' < "/proc/$p/environ" | grep -qx OMPI_COMM_WORLD_RANK=1; } 2>/dev/null && victim=$p
            done
        fi
        # shellcheck disable=SC2086 # the glob is meant to expand
        [ -n "$victim" ] && [ -s "$(ls $rows_file 2>/dev/null | head -n 1)" ] && break
        sleep 0.02
    done
    [ -n "$victim" ] || fail "rank 1 never started writing $rows_file"
    kill -9 "$victim"
    wait "$launcher"
    rc=$?
}
# Without --checkpoint rank 1 spools its rows in $TMPDIR: killed there, the run fails all the same.
kill_rank1 "tmp/.spool.ffm.scratch.*/rows/rows.log" -o spool.ffm
[ "$rc" -ne 0 ] || fail "mpirun exited 0 although rank 1 was killed (spooling)"
[ ! -e spool.ffm ] || fail "a final .ffm exists after the failed run (spooling)"
echo "ok: killed rank 1 while spooling -> mpirun exit $rc, no spool.ffm"
kill_rank1 "kill/rank-1-of-2/rows.log" -o big.ffm --checkpoint kill
[ "$rc" -ne 0 ] || fail "mpirun exited 0 although rank 1 was killed"
[ ! -e big.ffm ] || fail "a final .ffm exists after the failed run"
echo "ok: killed rank 1 -> mpirun exit $rc, no big.ffm"
mpi formfactors $big -o big.ffm --checkpoint kill --resume --report big.json || fail "resume"
cmp big-one.ffm big.ffm || fail "resumed .ffm differs"
# Rank 1's 2,000 rows came in several chunks (about 48 MB in all), none above rank 0's bound: the
# entries of kRowChunkBytes (8 MiB) plus one row (at most 3N² entries of 8 bytes: 393,216 at
# N = 128), and per row 4 bytes of count and 32 of side figures (four doubles; at most the
# block's 2,000 rows).
python3 -c "
import json, sys
m = json.load(open(sys.argv[1]))['mpi']
assert m['chunks_received'] > 1 and m['largest_chunk_bytes'] <= (8 << 20) + 3 * 128 * 128 * 8 + (4 + 32) * 2000, m
print('rank 1 sent', m['chunks_received'], 'chunks, the largest', m['largest_chunk_bytes'], 'bytes')" big.json ||
    fail "rank 1's rows not received in bounded chunks"
echo "ok: resumed run byte-identical"
# Resuming with another number of ranks is refused, naming the shards found.
"$mpirun" --oversubscribe -np 1 "$ffcube" formfactors $big -o big3.ffm --checkpoint kill --resume 2> refused.txt &&
    fail "resume at -np 1 of a 2-rank checkpoint accepted"
grep -q "rank-0-of-2" refused.txt || fail "refusal does not name the shards: $(cat refused.txt)"
echo "ok: resume with another -np refused"

# 3. Distributed Jacobi and Gauss–Seidel. Each run stops with Σ_i A_i |r_i| ≤ τ × emitted power and
# reports error_bound.mean_abs = Σ_i A_i |r_i| / ((1 − q) Σ A) per channel, a bound on the
# area-weighted mean of |B* − B| (docs/solvers.md). So Σ_i A_i |B_two − B_one| / Σ A ≤ bound_one +
# bound_two per channel: the test's tolerance, nothing widened.
# The built-in Cornell box (it has a light; cube.obj has none).
box="--patches 600 --resolution 64 --threads 1 -q"
for solver in jacobi gauss-seidel; do
    "$ffcube" solve $box --solver $solver --tolerance 1e-6 --radiosity one-$solver.csv --report one-$solver.json ||
        fail "one-process solve $solver"
    mpi solve $box --solver $solver --tolerance 1e-6 --radiosity two-$solver.csv --report two-$solver.json ||
        fail "mpirun solve $solver"
    python3 - one-$solver.csv two-$solver.csv one-$solver.json two-$solver.json <<'PY' || fail "solve $solver: B differs"
import csv, json, sys
one, two = (list(csv.DictReader(open(p))) for p in sys.argv[1:3])
b1, b2 = (json.load(open(p))["error_bound"]["mean_abs"] for p in sys.argv[3:5])
assert len(one) == len(two) and len(one) > 0
area = sum(float(r["area"]) for r in one)
for c, name in enumerate(("B_r", "B_g", "B_b")):
    diff = sum(float(a["area"]) * abs(float(a[name]) - float(b[name])) for a, b in zip(one, two)) / area
    print(f"{name}: area-weighted mean |B_two - B_one| = {diff:.3e}, bound {b1[c] + b2[c]:.3e}")
    assert diff <= b1[c] + b2[c], name
PY
done
echo "ok: distributed jacobi and gauss-seidel agree with one process within their error bounds"
