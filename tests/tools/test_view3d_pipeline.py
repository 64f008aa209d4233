#!/usr/bin/env python3
"""ffcube-view3d in an urban-climate pipeline's View3D step (docs/urban.md), on a generated city
of 1,000 facets, read and judged the way uDALES' preprocessing reads and judges View3D's output.

    python3 tests/tools/test_view3d_pipeline.py SOURCE_DIR FFCUBE_VIEW3D [FACETS]

1. tools/gen_city.py writes a binary STL city; it is converted to a .vs3 as uDALES'
   tools/python/udgeom/view3d.py `stl_to_view3d` writes one (CRLF lines, a bare T line,
   `C out=2 row=0 col=0`, `F 3`, comment lines, `V` lines with 6 decimals, one `S` line per
   triangle named `<n>f` with emissivity 0, `End of Data`), vertices shared where equal.
2. ffcube-view3d runs with View3D's two arguments, as `run_view3d` runs VIEW3D_EXE.
3. The output is read as `read_view3d_output(..., outformat=2)` reads it (whitespace-separated
   `i j F`, 1-based, duplicates summed) and judged by the acceptance rules of their
   `inspect_view_factors` / `validate_view_factors` with the defaults the preprocessing uses
   (tolerance 1e-3, reciprocity 1e-2 = ViewFactorRepairLimits.max_reciprocity_l1_relative):
   no non-finite value; no entry below -1e-3 or above 1 + 1e-3; sky view factors
   SVF = max(1 - row sum, 0) (their `compute_svf`) within [-1e-3, 1 + 1e-3]; every row's
   row sum + SVF within 1e-3 of 1; reciprocity L1 = sum|A_i F_ij - A_j F_ji| / sum|A_i F_ij|
   (over the stored entries, A from the STL's triangles) at most 1e-2.

The rules are re-implemented here from uDALES/u-dales at commit
2fe4df1b96eb0b3186f2d99e7c7d110006c6fcda (tools/python/udgeom/view3d.py: stl_to_view3d,
read_view3d_output, compute_svf, _reciprocity_l1_relative, inspect_view_factors); no code of
theirs is copied. When UDALES_TOOLS_PYTHON names a checkout's tools/python and numpy, scipy and
trimesh import, their own reader and validator run on the same files too; otherwise that part is
skipped with a line saying so.
"""
import math
import os
import struct
import subprocess
import sys
import tempfile
import time

TOL = 1.0e-3
RECIPROCITY_TOL = 1.0e-2


def read_binary_stl(path):
    data = open(path, "rb").read()
    (n,) = struct.unpack_from("<I", data, 80)
    assert len(data) == 84 + 50 * n, (len(data), n)
    return [struct.unpack_from("<12f", data, 84 + 50 * k)[3:12] for k in range(n)]


def write_vs3(triangles, path):
    """The .vs3 of uDALES' stl_to_view3d: returns the vertex list and the faces (0-based)."""
    index, vertices, faces = {}, [], []
    for t in triangles:
        face = []
        for c in range(3):
            p = (t[3 * c], t[3 * c + 1], t[3 * c + 2])
            if p not in index:
                index[p] = len(vertices)
                vertices.append(p)
            face.append(index[p])
        faces.append(face)
    with open(path, "w", encoding="ascii", newline="") as f:
        f.write("T\r\n")
        f.write("C out=2 row=0 col=0\r\n")
        f.write("F 3\r\n")
        f.write("!    #      x      y      z\r\n")
        for k, (x, y, z) in enumerate(vertices, start=1):
            f.write(f"V {k:4d} {x:6.6f} {y:6.6f} {z:6.6f}\r\n")
        f.write("!    #     v1     v2     v3     v4   base    cmb   emit   name\r\n")
        for k, (a, b, c) in enumerate(faces, start=1):
            f.write(f"S {k:4d} {a + 1:6d} {b + 1:6d} {c + 1:6d} {0:6d} {0:6d} {0:6d} {0:6d} {k:6d}f\r\n")
        f.write("End of Data\r\n")
    return vertices, faces


def triangle_area(p, q, r):
    u = [q[i] - p[i] for i in range(3)]
    v = [r[i] - p[i] for i in range(3)]
    c = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    return 0.5 * math.sqrt(c[0] ** 2 + c[1] ** 2 + c[2] ** 2)


def read_sparse(path, n):
    """read_view3d_output(outformat=2): whitespace-separated i j F, 1-based, duplicates summed."""
    F = {}
    for number, line in enumerate(open(path, encoding="ascii"), start=1):
        words = line.split()
        if not words:
            continue
        assert len(words) == 3, f"{path}:{number}: {line!r}"
        i, j, v = int(float(words[0])) - 1, int(float(words[1])) - 1, float(words[2])
        assert 0 <= i < n and 0 <= j < n, f"{path}:{number}: index out of 1..{n}: {line!r}"
        F[(i, j)] = F.get((i, j), 0.0) + v
    return F


def judge(F, n, areas):
    """inspect_view_factors' counts; returns the list of problems (empty: valid) and figures."""
    problems = []
    values = list(F.values())
    nonfinite = sum(1 for v in values if not math.isfinite(v))
    negative = sum(1 for v in values if v < -TOL)
    above_one = sum(1 for v in values if v > 1.0 + TOL)
    row_sum = [0.0] * n
    for (i, _), v in F.items():
        row_sum[i] += v
    svf = [max(1.0 - s, 0.0) for s in row_sum]
    sky_outside = sum(1 for s in svf if s < -TOL or s > 1.0 + TOL)
    closure = [row_sum[i] + svf[i] for i in range(n)]
    bad_closure = sum(1 for c in closure if abs(c - 1.0) > TOL)
    exchange = {k: areas[k[0]] * v for k, v in F.items()}
    denominator = sum(abs(x) for x in exchange.values())
    residual = 0.0
    for (i, j), x in exchange.items():  # (A F) - (A F)^T over the union of stored entries
        residual += abs(x - exchange.get((j, i), 0.0))
    for (i, j), x in exchange.items():
        if (j, i) not in exchange:
            residual += abs(x)  # the transpose's entry where (i, j) has none
    reciprocity = residual / denominator if denominator else 0.0
    for count, what in ((nonfinite, "non-finite values"), (negative, f"entries below {-TOL:g}"),
                        (above_one, f"entries above {1 + TOL:g}"), (sky_outside, "sky factors out of bounds"),
                        (bad_closure, f"rows failing sum(Fij) + SVF = 1 within {TOL:g}")):
        if count:
            problems.append(f"{count} {what}")
    if reciprocity > RECIPROCITY_TOL:
        problems.append(f"reciprocity L1 error {reciprocity:.6g} exceeds {RECIPROCITY_TOL:g}")
    figures = dict(nnz=len(values), max=max(values) if values else 0.0, row_sum_max=max(row_sum),
                   svf_mean=sum(svf) / n, reciprocity_l1=reciprocity)
    return problems, figures


def their_own(tools_python, vf_path, n, areas):
    """uDALES' reader and validator, where a checkout and their dependencies are present."""
    if not tools_python:
        return "skipped: UDALES_TOOLS_PYTHON is not set (a checkout's tools/python)"
    sys.path.insert(0, tools_python)
    try:
        import numpy as np
        from udgeom.view3d import compute_svf, read_view3d_output, validate_view_factors
    except Exception as e:  # numpy, scipy, trimesh or the checkout missing
        return f"skipped: cannot import uDALES' udgeom.view3d from {tools_python}: {e}"
    vf = read_view3d_output(vf_path, nfacets=n, outformat=2)
    report = validate_view_factors(vf, compute_svf(vf), areas=np.asarray(areas, dtype=float))
    return f"passed (their validator: nnz {report.nnz}, reciprocity L1 {report.reciprocity_l1_relative:.3g})"


def main():
    source, exe = sys.argv[1], sys.argv[2]
    facets = int(sys.argv[3]) if len(sys.argv) > 3 else 1000
    with tempfile.TemporaryDirectory(prefix="ffcube_view3d_pipeline_") as tmp:
        stl = os.path.join(tmp, "city.stl")
        subprocess.run([sys.executable, os.path.join(source, "tools", "gen_city.py"), stl, "--binary", "--triangles",
                        str(facets), "--seed", "7"], check=True, stdout=subprocess.DEVNULL)
        triangles = read_binary_stl(stl)
        assert len(triangles) == facets, len(triangles)
        vs3 = os.path.join(tmp, f"facets.{facets}.vs3")
        vertices, faces = write_vs3(triangles, vs3)
        areas = [triangle_area(*(vertices[v] for v in f)) for f in faces]
        vf = os.path.join(tmp, "vfsparse.inp")
        start = time.perf_counter()
        run = subprocess.run([exe, vs3, vf], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        seconds = time.perf_counter() - start
        assert run.returncode == 0, run.stdout
        F = read_sparse(vf, facets)
        # The forks' lines: "%d %d %.6f", F >= 5e-7 (so at least 0.000001 printed).
        for line in open(vf, encoding="ascii"):
            i, j, v = line.rstrip("\n").split(" ")
            assert len(v.split(".")[1]) == 6 and float(v) > 0.0, line
        problems, fig = judge(F, facets, areas)
        print(f"{facets} facets: ffcube-view3d {seconds:.1f} s, {fig['nnz']} entries, largest {fig['max']:.6f}, "
              f"largest row sum {fig['row_sum_max']:.6f}, mean SVF {fig['svf_mean']:.4f}, "
              f"reciprocity L1 {fig['reciprocity_l1']:.3e}")
        assert not problems, "; ".join(problems)
        print("acceptance rules (uDALES' validate_view_factors, re-implemented): passed")
        print("uDALES' own reader and validator:", their_own(os.environ.get("UDALES_TOOLS_PYTHON", ""), vf, facets, areas))
    return 0


if __name__ == "__main__":
    sys.exit(main())
