#!/usr/bin/env python3
"""Accuracy against cost on one scene: several ffcube settings, each timed end to end and compared
with a ray-cast reference (issue 15, part 3: what a user can have for a given run time).

Every setting runs `ffcube formfactors SCENE --no-subdivide -q -o F.mtx --sky sky.csv --report r.json
ARGS`; the table gives its wall and CPU seconds (user + sys of ffcube and the worker processes it
waits for), the hemicubes it drew, the rows measured by sub-hemicubes, and against the reference:
the mean signed sky-view-factor difference, its RMS and worst one, the mean and worst row L1
distance sum_j |F_ij - R_ij|, the RMS over rows of the row's L2 error, and the largest |dF| of any
entry. The reference is the ray caster (`--method raycast --rays RAYS`), cast twice, with seeds 1
and 2: half the mean squared difference of the two is its own variance (the ray caster stratifies its rays, so the
binomial sqrt(F(1 - F)/RAYS) overstates it). The two RMS columns marked * have that variance
taken out (E[(h - r)^2] = (h's own error)^2 + var r), so they estimate the setting's own error
even where it is below the reference's noise; L1 and the worst values include that noise. A
ray-cast setting compared here needs a --seed other than 1 and 2, or its rays repeat the
reference's.

    python3 tools/gen_city.py city.stl --binary --triangles 1500 --seed 3 --ground grid
    python3 tools/city_frontier.py city.stl --rays 65536 \\
        "default|" "none|--correct none" "N=64|--resolution 64" "rays 16k|--method raycast --rays 16384 --seed 7"
    python3 tools/city_frontier.py big.stl --no-reference "default|" "none|--correct none"   # times only

A setting is LABEL|ARGS (ARGS split on spaces; the resolution is 128 unless ARGS name one).
--reference DIR keeps (or reuses) the two reference runs in DIR/seed1 and DIR/seed2.
"""
import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time


def read_mtx(path):
    rows = {}
    with open(path) as f:
        for line in f:
            if not line.startswith("%"):
                break  # the size line
        for line in f:
            i, j, v = line.split()
            rows.setdefault(int(i), {})[int(j)] = float(v)
    return rows


def read_sky(path):
    with open(path) as f:
        next(f)
        return [float(line.rsplit(",", 1)[1]) for line in f]


def run(binary, scene, args, out):
    """Runs one setting into directory out; returns (wall s, CPU s)."""
    os.makedirs(out, exist_ok=True)
    cmd = [binary, "formfactors", scene, "--no-subdivide", "-q", "-o", os.path.join(out, "F.mtx"),
           "--sky", os.path.join(out, "sky.csv"), "--report", os.path.join(out, "r.json")]
    if "--resolution" not in args and "--method" not in args:
        cmd += ["--resolution", "128"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.monotonic()
    subprocess.run(cmd + args, check=True)
    wall = time.monotonic() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def errors(F, Fs, R, Rs):
    """A matrix and sky view factors against the reference: (SVF differences, row L1 distances,
    total squared entry error, largest |dF|)."""
    d = [f - r for f, r in zip(Fs, Rs)]
    l1, sq, worst = [], 0.0, 0.0
    for i in range(1, len(Rs) + 1):
        x, y = F.get(i, {}), R.get(i, {})
        e = [abs(x.get(j, 0.0) - y.get(j, 0.0)) for j in set(x) | set(y)]
        l1.append(sum(e))
        sq += sum(v * v for v in e)
        worst = max([worst] + e)
    return d, l1, sq, worst


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("settings", nargs="+", help="LABEL|ARGS")
    ap.add_argument("--rays", type=int, default=65536, help="the reference's rays per patch")
    ap.add_argument("--binary", default="./build/ffcube")
    ap.add_argument("--reference", help="directory for the reference runs (reused when present)")
    ap.add_argument("--no-reference", action="store_true", help="times and counts only")
    a = ap.parse_args()
    settings = []
    for s in a.settings:
        if "|" not in s:
            sys.exit(f"city_frontier: setting '{s}' is not LABEL|ARGS")
        label, args = s.split("|", 1)
        settings.append((label, args.split()))

    with tempfile.TemporaryDirectory() as tmp:
        R = Rs = None
        if not a.no_reference:
            ref = a.reference or os.path.join(tmp, "reference")
            refs = []
            for sub, seed in (("seed1", 1), ("seed2", 2)):
                where = os.path.join(ref, sub)
                if not os.path.exists(os.path.join(where, "sky.csv")):
                    wall, cpu = run(a.binary, a.scene,
                                    ["--method", "raycast", "--rays", str(a.rays), "--seed", str(seed)], where)
                    print(f"reference: ray caster, {a.rays} rays a patch, seed {seed}: {wall:.1f} s wall, {cpu:.1f} s CPU")
                refs.append((read_mtx(os.path.join(where, "F.mtx")), read_sky(os.path.join(where, "sky.csv"))))
            (R, Rs), (R2, Rs2) = refs
            n = len(Rs)
            # The reference's own noise: two seeds differ by twice its variance (they are independent).
            d, _, sq, _ = errors(R2, Rs2, R, Rs)
            noise_svf2, noise_sq = sum(v * v for v in d) / (2 * n), sq / (2 * n)
            print(f"reference noise (seed 1 against seed 2, / sqrt 2): SVF rms {math.sqrt(noise_svf2):.2e} a patch, "
                  f"row L2 rms {math.sqrt(noise_sq):.2e}")
        print(f"scene {a.scene}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
        head = f"{'setting':<14} {'wall s':>8} {'CPU s':>8} {'hemicubes':>10} {'sub-hemi rows':>13}"
        if R is not None:
            head += (f" {'SVF mean d':>11} {'SVF rms*':>9} {'worst |d|':>9} {'row L1 mean':>11} {'worst':>7}"
                     f" {'row L2 rms*':>11} {'max |dF|':>9}")
        print(head)
        for k, (label, args) in enumerate(settings):
            out = os.path.join(tmp, f"s{k}")
            wall, cpu = run(a.binary, a.scene, args, out)
            r = json.load(open(os.path.join(out, "r.json")))
            line = (f"{label:<14} {wall:>8.1f} {cpu:>8.1f} {r.get('hemicubes', 0):>10}"
                    f" {r.get('corrections', {}).get('rows_sub_hemicubes', 0):>13}")
            if R is not None:
                F, Fs = read_mtx(os.path.join(out, "F.mtx")), read_sky(os.path.join(out, "sky.csv"))
                if len(Fs) != len(Rs):
                    sys.exit(f"city_frontier: setting '{label}' has {len(Fs)} patches, the reference {len(Rs)}")
                d, l1, sq, worst = errors(F, Fs, R, Rs)
                # E[(h - r)^2] = (h's own error)^2 + the reference's variance: take the variance out.
                svf = math.sqrt(max(sum(v * v for v in d) / n - noise_svf2, 0.0))
                row = math.sqrt(max(sq / n - noise_sq, 0.0))
                line += (f" {sum(d) / n:>+11.2e} {svf:>9.2e} {max(map(abs, d)):>9.2e}"
                         f" {sum(l1) / n:>11.5f} {max(l1):>7.4f} {row:>11.2e} {worst:>9.2e}")
            print(line, flush=True)


if __name__ == "__main__":
    main()
