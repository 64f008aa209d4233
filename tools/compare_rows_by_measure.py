#!/usr/bin/env python3
"""Two form-factor matrices (A, B: Matrix Market, `ffcube formfactors -o F.mtx`) against a ray-cast
reference with RAYS rays per patch, by how each row was measured (the report's
corrections.row_measure; 4 = 4 x 4 sub-hemicubes): per class of rows, the mean and worst row L1
distance from the reference and the L1 the reference's own noise alone would give
(sqrt(2/pi) sum_j sqrt(F(1-F)/RAYS), approximate), the hemicube's own squared row error with the
reference's variance taken out (sum_j (h - r)^2 - sum_j r(1-r)/(RAYS-1): unbiased for the
hemicube's error, whatever the reference's noise), row sums, and the L1 between A and B.
Needs numpy and scipy.

    python3 tools/compare_rows_by_measure.py ray.mtx before.mtx after.mtx after.json 65536
"""
import json
import sys

import numpy as np
import scipy.sparse as sp


def load(path):
    skip = 0
    with open(path) as f:
        for line in f:
            skip += 1
            if not line.startswith("%"):
                n = int(line.split()[0])
                break
    a = np.loadtxt(path, skiprows=skip, dtype=np.float64, ndmin=2)
    return sp.csr_matrix((a[:, 2], (a[:, 0].astype(np.int64) - 1, a[:, 1].astype(np.int64) - 1)), shape=(n, n))


def rows(m):
    return np.asarray(m.sum(axis=1)).ravel()


def main():
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    ref, a, b = (load(p) for p in sys.argv[1:4])
    rays = float(sys.argv[5])
    code = np.array(json.load(open(sys.argv[4]))["corrections"]["row_measure"])
    var, sd = ref.copy(), ref.copy()
    var.data = var.data * (1 - var.data) / (rays - 1)
    sd.data = np.sqrt(sd.data * (1 - sd.data) / rays)
    var_r, noise = rows(var), np.sqrt(2 / np.pi) * rows(sd)
    l1a, l1b, l1ab = rows(abs(a - ref)), rows(abs(b - ref)), rows(abs(a - b))
    sqa = rows((a - ref).multiply(a - ref)) - var_r
    sqb = rows((b - ref).multiply(b - ref)) - var_r
    sum_r, sum_a, sum_b = rows(ref), rows(a), rows(b)
    for name, m in (("4 x 4 rows", code == 4), ("other rows", code != 4), ("all rows", np.ones(len(code), bool))):
        if not m.any():
            continue
        print(f"{name} ({m.sum()}): row L1 from the reference, mean A {l1a[m].mean():.5f} B {l1b[m].mean():.5f} "
              f"(the reference's noise alone about {noise[m].mean():.5f}); worst A {l1a[m].max():.4f} B {l1b[m].max():.4f}")
        print(f"  hemicube's own row error, RMS over rows of its L2 norm: A {np.sqrt(max(sqa[m].mean(), 0)):.2e} "
              f"B {np.sqrt(max(sqb[m].mean(), 0)):.2e} (the reference's own {np.sqrt(var_r[m].mean()):.2e})")
        print(f"  row sum minus the reference's: mean A {np.mean(sum_a[m] - sum_r[m]):+.2e} B {np.mean(sum_b[m] - sum_r[m]):+.2e}, "
              f"mean |.| A {np.mean(abs(sum_a[m] - sum_r[m])):.2e} B {np.mean(abs(sum_b[m] - sum_r[m])):.2e}")
        print(f"  row L1 between A and B: mean {l1ab[m].mean():.5f}")


if __name__ == "__main__":
    main()
