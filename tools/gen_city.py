#!/usr/bin/env python3
"""A synthetic city as STL, the way CAD/GIS exports write one (issue 15, part 3).

Buildings are extruded footprints of varying height (rectangles, and some L shapes), standing
on a ground plane split into triangles. Every facet is written on its own: no shared-vertex
indexing, outward normals, counter-clockwise from the outside. Deterministic from --seed
(Python's own random.Random, whose sequence is fixed across versions for a given seed).

    python3 tools/gen_city.py city.stl                    # 22,881 triangles, ASCII
    python3 tools/gen_city.py city.stl --binary --triangles 5000 --seed 7
    ffcube formfactors city.stl --no-subdivide --resolution 256 -o city.ffm

--triangles is met exactly: buildings (10 facets for a rectangle, 16 for an L) fill what the
ground (2 triangles a rectangle) leaves, and the few left over split ground triangles at an edge
midpoint (a T-junction, as exports leave them). The ground is cut along the lots and streets
(--ground lots, the default: every lot's ground runs on under its building, as a parcel layer
does), or is a square grid over the whole city (--ground grid: its triangles cross streets and
run on under several buildings).
"""
import argparse
import math
import random
import struct
import sys

LOT = 20.0     # lot side, metres
STREET = 10.0  # street width between lots


def quad(a, b, c, d):
    """Two triangles of the planar quad a b c d (counter-clockwise from its front)."""
    return [(a, b, c), (a, c, d)]


def building(x0, y0, rng):
    """Facets of one building on the lot whose corner is (x0, y0)."""
    h = rng.uniform(6.0, 60.0) if rng.random() < 0.85 else rng.uniform(60.0, 120.0)
    m = rng.uniform(1.0, 4.0)
    w, d = rng.uniform(8.0, LOT - 2 * m), rng.uniform(8.0, LOT - 2 * m)
    ax, ay = x0 + m, y0 + m
    if rng.random() < 0.35:
        # L: the rectangle less its top-right corner, counter-clockwise from above.
        cw, cd = rng.uniform(0.3, 0.7) * w, rng.uniform(0.3, 0.7) * d
        foot = [(ax, ay), (ax + w, ay), (ax + w, ay + d - cd), (ax + w - cw, ay + d - cd), (ax + w - cw, ay + d),
                (ax, ay + d)]
        p = [(x, y, h) for x, y in foot]
        roof = roof_l(p, ax, ay, w, d, cw, cd, h)
    else:
        foot = [(ax, ay), (ax + w, ay), (ax + w, ay + d), (ax, ay + d)]
        p = [(x, y, h) for x, y in foot]
        roof = quad(p[0], p[1], p[2], p[3])
    tris = []
    n = len(foot)
    for k in range(n):
        (xa, ya), (xb, yb) = foot[k], foot[(k + 1) % n]
        # Outward wall: footprint CCW from above, so (a, b, b up, a up) faces outward.
        tris += quad((xa, ya, 0.0), (xb, yb, 0.0), (xb, yb, h), (xa, ya, h))
    return tris + roof


def roof_l(p, ax, ay, w, d, cw, cd, h):
    """The L roof (footprint corners p[0..5], CCW from above) as a fan of 4 triangles facing up
    from p[0], the corner opposite the notch: the L is star-shaped from there."""
    return [(p[0], p[k], p[k + 1]) for k in range(1, 5)]


def ground(extent, cells):
    s = extent / cells
    tris = []
    for i in range(cells):
        for j in range(cells):
            a = (i * s, j * s, 0.0)
            b = ((i + 1) * s, j * s, 0.0)
            c = ((i + 1) * s, (j + 1) * s, 0.0)
            d = (i * s, (j + 1) * s, 0.0)
            tris += quad(a, b, c, d) if (i + j) % 2 == 0 else quad(b, c, d, a)
    return tris


def normal(t):
    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = t
    ux, uy, uz = bx - ax, by - ay, bz - az
    vx, vy, vz = cx - ax, cy - ay, cz - az
    n = (uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)
    length = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
    return tuple(c / length for c in n)


def lot_ground(k):
    """The ground cut along the lots' and streets' edges: (2k + 1)² rectangles, 2 triangles each."""
    cuts = [0.0]
    for _ in range(k):
        cuts += [cuts[-1] + STREET, cuts[-1] + STREET + LOT]
    cuts.append(cuts[-1] + STREET)
    tris = []
    for i in range(len(cuts) - 1):
        for j in range(len(cuts) - 1):
            a, b = (cuts[i], cuts[j], 0.0), (cuts[i + 1], cuts[j], 0.0)
            c, d = (cuts[i + 1], cuts[j + 1], 0.0), (cuts[i], cuts[j + 1], 0.0)
            tris += quad(a, b, c, d)
    return tris


def city(triangles, seed, ground_kind):
    rng = random.Random(seed)
    if ground_kind == "grid":
        # About 20 % of the facets: a square grid over the whole city, its cells crossing streets
        # and running on under the buildings.
        cells = max(1, int(math.sqrt(max(2, int(0.2 * triangles)) / 2)))
        budget = triangles - 2 * cells * cells
    else:
        # The fewest lots per side k whose ground, 2 (2k + 1)², and k² buildings of the largest
        # kind (16 facets) reach the count: the buildings then never run out of lots.
        k = 1
        while 2 * (2 * k + 1) ** 2 + 16 * k * k < triangles:
            k += 1
        if k > 1 and 2 * (2 * k + 1) ** 2 > triangles:  # a tiny city: fewer lots, splits make up the rest
            k -= 1
        budget = triangles - 2 * (2 * k + 1) ** 2
    shapes = []
    used = 0
    while budget > 0 and (ground_kind == "grid" or len(shapes) < k * k):
        b = building(0.0, 0.0, random.Random(rng.random()))
        if used + len(b) > budget:
            break
        shapes.append(b)
        used += len(b)
    if ground_kind == "grid":
        k = max(1, math.ceil(math.sqrt(len(shapes))))
        g = ground(STREET + k * (LOT + STREET), cells)
    else:
        g = lot_ground(k)
    pitch = LOT + STREET
    tris = []
    for n, b in enumerate(shapes):
        x0, y0 = STREET + (n % k) * pitch, STREET + (n // k) * pitch
        tris += [tuple((x + x0, y + y0, z) for x, y, z in t) for t in b]
    # Split ground triangles at the midpoint of their first edge until the count is met (the
    # list grows by one each time, so g[i] exists).
    extra = triangles - len(tris) - len(g)
    for i in range(extra):
        a, b, c = g[i]
        mid = tuple((u + v) / 2 for u, v in zip(a, b))
        g[i] = (a, mid, c)
        g.append((mid, b, c))
    return g + tris


def write_ascii(path, tris):
    with open(path, "w") as f:
        f.write("solid city\n")
        for t in tris:
            n = normal(t)
            f.write(f"  facet normal {n[0]:.6e} {n[1]:.6e} {n[2]:.6e}\n    outer loop\n")
            for v in t:
                f.write(f"      vertex {v[0]:.6f} {v[1]:.6f} {v[2]:.6f}\n")
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid city\n")


def write_binary(path, tris):
    with open(path, "wb") as f:
        f.write(b"ffcube tools/gen_city.py".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<12fH", *normal(t), *t[0], *t[1], *t[2], 0))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("output")
    ap.add_argument("--triangles", type=int, default=22881, help="facet count (default 22881)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--binary", action="store_true", help="binary STL (default ASCII)")
    ap.add_argument("--ground", choices=["lots", "grid"], default="lots",
                    help="lots: the ground cut along lots and streets (default); grid: a square grid "
                    "whose cells cross streets and run on under buildings")
    a = ap.parse_args()
    if a.triangles < 20:
        sys.exit("gen_city.py: --triangles must be at least 20")
    tris = city(a.triangles, a.seed, a.ground)
    assert len(tris) == a.triangles, (len(tris), a.triangles)
    (write_binary if a.binary else write_ascii)(a.output, tris)
    print(f"{a.output}: {len(tris)} triangles", file=sys.stderr)


if __name__ == "__main__":
    main()
