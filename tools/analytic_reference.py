#!/usr/bin/env python3
"""Reference polygon-to-polygon form factors in 40-digit arithmetic (mpmath), independent of ffcube.

    python3 tools/analytic_reference.py PAIR_FILE [--digits 40]

PAIR_FILE holds two planar polygons, one vertex "x y z" per line, the polygons separated by a
blank line (or a line starting with "poly"); each polygon counter-clockwise seen from its front,
and each wholly in front of the other (ffcube's ff_polygon_polygon clips first; this does not).
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


def area_times_ff(p1, p2):
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("pair_file")
    parser.add_argument("--digits", type=int, default=40)
    args = parser.parse_args()
    mp.mp.dps = args.digits
    p1, p2 = read_pair(args.pair_file)
    a1f12, a2f21 = area_times_ff(p1, p2), area_times_ff(p2, p1)
    print("A1F12", mp.nstr(a1f12, 25))
    print("A2F21", mp.nstr(a2f21, 25))
    print("F12", mp.nstr(a1f12 / area(p1), 25))
    print("F21", mp.nstr(a2f21 / area(p2), 25))


if __name__ == "__main__":
    main()
