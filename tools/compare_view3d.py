#!/usr/bin/env python3
"""Compare two View3D text view-factor files (out=0, as `ffcube formfactors --view3d` and View3D
write them): |F_a - F_b| over every surface pair, mean and largest, and the worst pair.

    python3 tools/compare_view3d.py test.txt reference.txt

docs/benchmarks.md uses it on examples/l_shaped_room.vs3 against the reference
`ffcube formfactors examples/l_shaped_room.vs3 --no-subdivide --exact-visibility 8 --view3d ref.txt`
(within 7.5e-7 of the room's exact factors: tests/cli/test_view3d_l_room_cli.cpp).
"""
import sys


def read(path):
    with open(path) as f:
        lines = f.read().split("\n")
    n = int(lines[0].split()[-1])  # "View3D 3.5 encl didemit ... n"
    values = []
    for line in lines[2:]:
        values += [float(x) for x in line.split()]
        if len(values) >= n * n:
            break
    if len(values) < n * n:
        sys.exit(f"{path}: {len(values)} factors, expected {n} x {n}")
    return n, [values[i * n:(i + 1) * n] for i in range(n)]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    n, a = read(sys.argv[1])
    m, b = read(sys.argv[2])
    if n != m:
        sys.exit(f"{n} surfaces against {m}")
    worst, total, at = 0.0, 0.0, (0, 0)
    for i in range(n):
        for j in range(n):
            d = abs(a[i][j] - b[i][j])
            total += d
            if d > worst:
                worst, at = d, (i, j)
    i, j = at
    print(f"mean |dF| {total / (n * n):.3g}, max {worst:.3g} at F({i + 1}->{j + 1}) = {a[i][j]} against {b[i][j]}")


if __name__ == "__main__":
    main()
