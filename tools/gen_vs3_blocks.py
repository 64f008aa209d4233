#!/usr/bin/env python3
"""A small urban-like scene as a View3D .vs3 file: box buildings on a ground plane.

Every face is split into a grid of quads no larger than --cell (one S surface each, so that with
--no-subdivide every surface is one row); building walls and roofs face outward, the ground faces
up, the buildings have no floors (they stand on the ground). Deterministic for a given --seed.

    python3 tools/gen_vs3_blocks.py -o blocks.vs3   # 1,188 surfaces
"""
import argparse
import random


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--blocks", type=int, default=3, help="buildings per side of the square grid (default 3)")
    ap.add_argument("--spacing", type=float, default=20.0, help="distance between building centres (default 20)")
    ap.add_argument("--cell", type=float, default=2.5, help="largest surface edge, and the ground grid's cell (default 2.5; spacing × blocks must be a multiple)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the building sizes (default 1)")
    ap.add_argument("-o", "--output", required=True)
    a = ap.parse_args()
    rng = random.Random(a.seed)
    verts, surfs = [], []

    def vertex(p):
        verts.append(p)
        return len(verts)

    def quad(p0, u, v, name, keep=lambda c: True):
        """Grid of quads over p0 + s u + t v, s, t in [0, 1]; front is u x v; keep(centre) filters."""
        lu = sum(x * x for x in u) ** 0.5
        lv = sum(x * x for x in v) ** 0.5
        nu, nv = max(1, int(-(-lu // a.cell))), max(1, int(-(-lv // a.cell)))
        ids = {}
        for j in range(nv + 1):
            for i in range(nu + 1):
                ids[i, j] = vertex(tuple(p0[k] + u[k] * i / nu + v[k] * j / nv for k in range(3)))
        for j in range(nv):
            for i in range(nu):
                c = [p0[k] + u[k] * (i + 0.5) / nu + v[k] * (j + 0.5) / nv for k in range(3)]
                if not keep(c):
                    continue
                surfs.append((ids[i, j], ids[i + 1, j], ids[i + 1, j + 1], ids[i, j + 1], f"{name}_{i}_{j}"))

    size = a.blocks * a.spacing
    buildings = []
    for bx in range(a.blocks):
        for by in range(a.blocks):
            # Footprints on the ground's grid (multiples of the cell), so that every ground cell is
            # wholly inside or outside a building: no surface passes through another.
            w, d = a.cell * rng.randint(3, 5), a.cell * rng.randint(3, 5)
            h = rng.uniform(5, 15)
            x0 = a.cell * round(((bx + 0.5) * a.spacing - w / 2) / a.cell)
            y0 = a.cell * round(((by + 0.5) * a.spacing - d / 2) / a.cell)
            buildings.append((f"b{bx}{by}", x0, y0, x0 + w, y0 + d, h))
    # Ground cells under a building are left out (they would only see the backs of its walls);
    # the vertices unused by them stay, unreferenced.
    outside = lambda c: not any(x0 < c[0] < x1 and y0 < c[1] < y1 for _, x0, y0, x1, y1, _ in buildings)
    quad((0.0, 0.0, 0.0), (size, 0.0, 0.0), (0.0, size, 0.0), "ground", outside)
    for b, x0, y0, x1, y1, h in buildings:
            w, d = x1 - x0, y1 - y0
            quad((x0, y0, h), (w, 0, 0), (0, d, 0), b + "roof")
            quad((x0, y0, 0), (w, 0, 0), (0, 0, h), b + "s")   # faces -y
            quad((x1, y1, 0), (-w, 0, 0), (0, 0, h), b + "n")  # faces +y
            quad((x0, y1, 0), (0, -d, 0), (0, 0, h), b + "w")  # faces -x
            quad((x1, y0, 0), (0, d, 0), (0, 0, h), b + "e")   # faces +x
    with open(a.output, "w") as f:
        f.write(f"T {a.blocks}x{a.blocks} box buildings on a ground plane (tools/gen_vs3_blocks.py, seed {a.seed})\n")
        f.write("C encl=0 emit=0\nF 3\n")
        for n, p in enumerate(verts, 1):
            f.write(f"V {n} {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}\n")
        for n, s in enumerate(surfs, 1):
            f.write(f"S {n} {s[0]} {s[1]} {s[2]} {s[3]} 0 0 0.9 {s[4]}\n")
        f.write("End of data\n")
    print(f"{a.output}: {len(surfs)} surfaces, {len(verts)} vertices")


if __name__ == "__main__":
    main()
