#!/usr/bin/env python3
"""Reference polygon-to-polygon form factors in 40-digit arithmetic (mpmath), independent of ffcube.

    python3 tools/analytic_reference.py PAIR_FILE [--digits 40]
    ./build/tools/analytic_pairs --count 40 > pairs.txt && python3 tools/analytic_reference.py --pairs pairs.txt

PAIR_FILE holds two planar polygons, one vertex "x y z" per line, the polygons separated by a
blank line (or a line starting with "poly"); each polygon counter-clockwise seen from its front.
Each is first clipped to the front of the other's plane, as ff_polygon_polygon does; a vertex
within ffcube's tolerance of that plane (1e-12 of the pair's longest edge, or 16 ulps of the
largest coordinate) counts as on it.
Prints A1 F12, A2 F21 (equal in exact arithmetic), F12 and F21.

Method (Sparrow 1963): A1 F12 = 1/(2 pi) sum over edge pairs of (dp . dq) int_0^1 int_0^1 ln r.
The inner integral along edge q is the closed form of int ln sqrt(a^2 (t - t0)^2 + h^2) dt; the
outer one along edge p is mpmath's tanh-sinh quadrature, split where the inner integral is not
smooth: at the points of p nearest q's ends and at the lines' closest approach. Tanh-sinh
integrates the remaining endpoint log singularities to full precision, so the two directions agree
to about 30 digits; ffcube's tests take the values it prints as exact (tests/geometry/test_analytic.cpp,
"near misses"). mpmath is Debian's python3-mpmath (tools/setup.sh installs it).
"""
import argparse
import sys

import mpmath as mp


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def area(poly):
    n = [mp.mpf(0)] * 3
    for i in range(len(poly)):
        n = [x + y for x, y in zip(n, cross(poly[i], poly[(i + 1) % len(poly)]))]
    return mp.sqrt(dot(n, n)) / 2


def log_along(point, q0, d):
    """int_0^1 ln|point - q0 - t d| dt in closed form."""
    a2 = dot(d, d)
    a = mp.sqrt(a2)
    w = sub(point, q0)
    t0 = dot(w, d) / a2
    h2 = max(dot(w, w) - a2 * t0 * t0, mp.mpf(0))
    h = mp.sqrt(h2)

    def primitive(t):
        u = t - t0
        r2 = a2 * u * u + h2
        v = (u * mp.log(r2) / 2 if r2 > 0 else mp.mpf(0)) - u
        if h > 0:
            v += h / a * mp.atan(a * u / h)
        return v

    return primitive(1) - primitive(0)


def edge_pair(p0, p1, q0, q1):
    """(dp . dq) int_0^1 int_0^1 ln|p(s) - q(t)| ds dt."""
    e, d = sub(p1, p0), sub(q1, q0)
    c = dot(e, d)
    if c == 0:
        return mp.mpf(0)
    e2 = dot(e, e)
    cuts = {mp.mpf(0), mp.mpf(1)}
    for q in (q0, q1):
        s = dot(sub(q, p0), e) / e2
        if 0 < s < 1:
            cuts.add(s)
    n = cross(e, d)
    nn = dot(n, n)
    if nn > 0:
        s = dot(cross(sub(q0, p0), d), n) / nn
        if 0 < s < 1:
            cuts.add(s)
    f = lambda s: log_along([p0[i] + s * e[i] for i in range(3)], q0, d)
    return c * mp.quad(f, sorted(cuts))


def normal(poly):
    n = [mp.mpf(0)] * 3
    for i in range(len(poly)):
        n = [x + y for x, y in zip(n, cross(poly[i], poly[(i + 1) % len(poly)]))]
    length = mp.sqrt(dot(n, n))
    return [x / length for x in n]


def clip_to_front(poly, origin, n, on_plane):
    """The part of poly where dot(v - origin, n) >= 0 (Sutherland-Hodgman against one plane); a
    vertex within on_plane of the plane counts as on it."""
    out = []
    for i in range(len(poly)):
        a, b = poly[i], poly[(i + 1) % len(poly)]
        da, db = dot(sub(a, origin), n), dot(sub(b, origin), n)
        da = mp.mpf(0) if abs(da) <= on_plane else da
        db = mp.mpf(0) if abs(db) <= on_plane else db
        if da >= 0:
            out.append(a)
        if (da > 0 and db < 0) or (da < 0 and db > 0):
            t = da / (da - db)
            out.append([a[k] + t * (b[k] - a[k]) for k in range(3)])
    return out


def area_times_ff(p1, p2):
    """A1 F12: each polygon first clipped to the front of the other's plane (cos > 0 there only)."""
    n1, n2 = normal(p1), normal(p2)
    o1, o2 = p1[0], p2[0]
    # ffcube's definition of "on the other's plane" (ff_polygon_polygon's in_plane,
    # geometric_tolerance(1e-12, size, max |coordinate|)): within 1e-12 of the pair's longest
    # edge, or 16 ulps of the largest coordinate, the input being known to rounding only. Cutting
    # exactly there would cut a shared hinge edge whose ends round to either side of the other
    # plane, leaving out a sliver along the hinge, where the kernel is strongest.
    coord = max(abs(x) for v in p1 + p2 for x in v)
    size = max(mp.sqrt(dot(sub(p[(i + 1) % len(p)], p[i]), sub(p[(i + 1) % len(p)], p[i])))
               for p in (p1, p2) for i in range(len(p)))
    on_plane = max(mp.mpf("1e-12") * size, 16 * mp.mpf(2) ** -52 * coord)
    p1, p2 = clip_to_front(p1, o2, n2, on_plane), clip_to_front(p2, o1, n1, on_plane)
    if len(p1) < 3 or len(p2) < 3:
        return mp.mpf(0)
    # A polygon whose front part lies in the other's plane sees it at cos = 0 (the contour form
    # does not vanish there by itself).
    if max(dot(sub(v, o2), n2) for v in p1) <= on_plane or max(dot(sub(v, o1), n1) for v in p2) <= on_plane:
        return mp.mpf(0)
    total = mp.mpf(0)
    for i in range(len(p1)):
        for j in range(len(p2)):
            total += edge_pair(p1[i], p1[(i + 1) % len(p1)], p2[j], p2[(j + 1) % len(p2)])
    return total / (2 * mp.pi)


def read_pair(path):
    polys, current = [], []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("poly"):
                if current:
                    polys.append(current)
                current = []
                continue
            fields = line.split()
            if len(fields) != 3:
                sys.exit(f"{path}:{number}: expected 3 coordinates 'x y z', got {len(fields)} fields")
            try:
                current.append([mp.mpf(x) for x in fields])
            except ValueError:
                sys.exit(f"{path}:{number}: not a number: {line!r}")
    if current:
        polys.append(current)
    if len(polys) != 2 or any(len(p) < 3 for p in polys):
        sys.exit(f"{path}: expected two polygons of at least 3 vertices, separated by a blank line")
    return polys


def check_pairs(path):
    """--pairs: the output of tools/analytic_pairs; each direction's error against its stated bound."""
    blocks, current = [], None
    with open(path, encoding="utf-8") as f:
        for line in f:
            fields = line.split()
            if not fields:
                continue
            if fields[0] == "pair":
                current = {"name": " ".join(fields[1:]), "polys": []}
                blocks.append(current)
            elif fields[0] == "poly:":
                current["polys"].append([])
            elif fields[0] == "ffcube":
                current["ffcube"] = [mp.mpf(x) for x in fields[1:5]]
            else:
                current["polys"][-1].append([mp.mpf(x) for x in fields])
    worst, over = 0.0, 0
    for b in blocks:
        p1, p2 = b["polys"]
        ref = area_times_ff(p1, p2)
        a1f12, a2f21, bound12, bound21 = b["ffcube"]
        ratios = [float(abs(a1f12 - ref) / bound12), float(abs(a2f21 - ref) / bound21)]
        over += sum(r > 1 for r in ratios)
        worst = max(worst, *ratios)
        print(f"{b['name']:<16} A1F12 {mp.nstr(ref, 17):<24} error/bound {ratios[0]:.3g} {ratios[1]:.3g}")
    print(f"{len(blocks)} pairs, {over} directions over their stated error, worst error/bound {worst:.3g}")
    return 1 if over else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("pair_file")
    parser.add_argument("--digits", type=int, default=40)
    parser.add_argument("--pairs", action="store_true",
                        help="PAIR_FILE is tools/analytic_pairs' output: check each pair's values against the reference")
    args = parser.parse_args()
    mp.mp.dps = args.digits
    if args.pairs:
        sys.exit(check_pairs(args.pair_file))
    p1, p2 = read_pair(args.pair_file)
    a1f12, a2f21 = area_times_ff(p1, p2), area_times_ff(p2, p1)
    print("A1F12", mp.nstr(a1f12, 25))
    print("A2F21", mp.nstr(a2f21, 25))
    print("F12", mp.nstr(a1f12 / area(p1), 25))
    print("F21", mp.nstr(a2f21 / area(p2), 25))


if __name__ == "__main__":
    main()
