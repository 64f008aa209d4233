#!/usr/bin/env python3
"""Checks ffcube's per-row error estimates (--tolerance, docs/accuracy.md "Accuracy by target")
against a reference: the ray caster with many rays (--method raycast --set rays=R).

For every row, the true error is the larger of its largest entry error and its sum error (one minus
the sky view factor), the quantity the estimate bounds. Prints the share of rows within their
estimate, the largest ratio true/estimate (issue 40: at least 95% within, none above 3), the true
errors (mean |error| and max) and the CPU time of the checked run.

  python3 tools/tolerance_honesty.py city.stl --tolerance 1e-3 [--reference-rays 4194304]
      [--ffcube build/ffcube] [--keep DIR] [-- more ffcube options, e.g. --no-subdivide]

The reference is about (R / R_checked)^0.63 times more accurate (the ray caster's rate on a city,
docs/accuracy.md); give --reference-rays large enough for the rows checked.
"""
import argparse
import csv
import os
import resource
import subprocess
import sys
import tempfile

import numpy as np
import scipy.io
import scipy.sparse as sp


def run(cmd):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime - before.ru_utime


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--tolerance", type=float, default=1e-3)
    ap.add_argument("--reference-rays", type=int, default=4194304)
    ap.add_argument("--ffcube", default=os.path.join(os.path.dirname(__file__), "..", "build", "ffcube"))
    ap.add_argument("--keep", help="directory for the matrices (reused: an existing reference.mtx is not recomputed)")
    a, extra = ap.parse_known_args()  # the rest: more ffcube options, e.g. --no-subdivide
    a.extra = [x for x in extra if x != "--"]
    d = a.keep or tempfile.mkdtemp()
    os.makedirs(d, exist_ok=True)
    ref_path = os.path.join(d, "reference.mtx")
    common = [a.ffcube, "formfactors", a.scene, "-q"] + a.extra
    if not os.path.exists(ref_path):
        run(common + ["--method", "raycast", "--set", f"rays={a.reference_rays}", "--set", "seed=11", "-o", ref_path])
    out, table = os.path.join(d, "checked.mtx"), os.path.join(d, "checked.csv")
    cpu = run(common + ["--tolerance", str(a.tolerance), "-o", out, "--patch-table", table])
    ref = sp.csr_matrix(scipy.io.mmread(ref_path))
    got = sp.csr_matrix(scipy.io.mmread(out))
    est = np.array([float(r["error_estimate"]) if r["error_estimate"] else np.nan for r in csv.DictReader(open(table))])
    diff = (got - ref).tocsr()
    diff.data = np.abs(diff.data)
    entry = np.array([diff[i].data.max() if diff[i].nnz else 0.0 for i in range(diff.shape[0])])
    total = np.abs(np.asarray(got.sum(1)).ravel() - np.asarray(ref.sum(1)).ravel())
    true = np.maximum(entry, total)
    ok = ~np.isnan(est)
    ratio = np.where(est[ok] > 0, true[ok] / np.maximum(est[ok], 1e-300), np.where(true[ok] > 0, np.inf, 0.0))
    print(f"{a.scene}: {got.shape[0]} rows at tolerance {a.tolerance:g}, reference {a.reference_rays} rays per row")
    print(f"  within their estimate: {np.mean(true[ok] <= est[ok]) * 100:.1f}%   largest true/estimate: {ratio.max():.2f}")
    print(f"  true error: mean {true.mean():.3g}, max {true.max():.3g}   (sum error mean {total.mean():.3g}, "
          f"largest entry error mean {entry.mean():.3g})")
    print(f"  estimates: median {np.median(est[ok]):.3g}, 95th percentile {np.percentile(est[ok], 95):.3g}, "
          f"max {est[ok].max():.3g}; rows above the target {int(np.sum(est[ok] > a.tolerance))}")
    print(f"  CPU of the checked run: {cpu:.1f} s (user)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
