#!/usr/bin/env python3
"""The midpoint rule's error on the point-to-area form factor, integrated over the sender
(docs/accuracy.md, "Which near pairs need sub-hemicubes"): a hemicube measures
g(x) = F_{dx→j} at the sender's centre c; the area-to-area value is the mean of g over the
sender. For a unit square sender and random square receivers (0.1 to 50 sender sizes, any
distance and orientation facing it, clipped to the sender's front), it prints the largest
absolute error |g(c) − mean g| times (δ/size_i)², δ the distance from c to the receiver,
by bands of δ, separately for receivers whose plane cuts the sender (there g is 0 behind the
plane and the rule is only first order: there it also prints the error over the first-order
bound (size_i/δ)·min(1, A_j/(πδ²)), which must stay below 1). Needs numpy (python3-numpy, tools/setup.sh).

    python3 tools/midpoint_error_study.py [SAMPLES] [SEED]      (default 12000 1)
"""
import sys

import numpy as np


def clip_front(p):
    """The part of polygon p with z >= 0 (in front of the sender's plane)."""
    out = []
    for a in range(len(p)):
        u, v = p[a], p[(a + 1) % len(p)]
        if u[2] >= 0:
            out.append(u)
        if (u[2] >= 0) != (v[2] >= 0):
            out.append(u + u[2] / (u[2] - v[2]) * (v - u))
    return np.array(out)


def lambert(x, p):
    """Point-to-polygon factors from the points x (rows, in the plane z = 0, normal +z)."""
    f = np.zeros(len(x))
    for a in range(len(p)):
        u, v = p[a] - x, p[a - 1] - x
        c = np.cross(u, v)
        nc = np.linalg.norm(c, axis=1)
        g = np.arctan2(nc, np.sum(u * v, 1))
        f += np.where(nc > 1e-300, g * c[:, 2] / np.maximum(nc, 1e-300), 0)
    return np.abs(f) / (2 * np.pi)


def distance(x, p):
    """Distance from the point x to the planar convex polygon p."""
    n = np.cross(p[1] - p[0], p[2] - p[0])
    n /= np.linalg.norm(n)
    q = x - np.dot(x - p[0], n) * n
    side = [np.dot(np.cross(p[(a + 1) % len(p)] - p[a], q - p[a]), n) for a in range(len(p))]
    if min(side) >= 0 or max(side) <= 0:
        return abs(np.dot(x - p[0], n))
    best = np.inf
    for a in range(len(p)):
        e = p[(a + 1) % len(p)] - p[a]
        t = np.clip(np.dot(x - p[a], e) / np.dot(e, e), 0, 1)
        best = min(best, np.linalg.norm(p[a] + t * e - x))
    return best


def main():
    samples = int(sys.argv[1]) if len(sys.argv) > 1 else 12000
    rng = np.random.default_rng(int(sys.argv[2]) if len(sys.argv) > 2 else 1)
    gx, gw = np.polynomial.legendre.leggauss(24)
    X, Y = np.meshgrid(gx / 2, gx / 2)
    pts = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], 1)
    wts = np.outer(gw / 2, gw / 2).ravel()
    corners = [np.array([a, b, 0.0]) for a in (-0.5, 0.5) for b in (-0.5, 0.5)]
    rows = []
    for _ in range(samples):
        side = 10 ** rng.uniform(-1, 1.7)
        c = rng.normal(size=3)
        c[2] = abs(c[2])
        c *= 10 ** rng.uniform(-0.2, 1.3) * max(1, side * rng.uniform(0, 1)) / np.linalg.norm(c)
        n = rng.normal(size=3)
        if np.dot(n, -c) < 0:
            n = -n
        n /= np.linalg.norm(n)
        t1 = np.cross(n, rng.normal(size=3))
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(n, t1)
        p = clip_front(np.array([c + side / 2 * (a * t1 + b * t2) for a, b in [(-1, -1), (1, -1), (1, 1), (-1, 1)]]))
        if len(p) < 3 or (np.min(p[:, 2]) < 1e-9 and np.min(np.max(np.abs(p[:, :2]), 1)) < 0.6):
            continue  # nothing in front, or cutting into the sender's plane over the sender
        if all(np.dot(x - c, n) <= 0 for x in corners):
            continue  # not facing
        straddles = any(np.dot(x - c, n) < 0 for x in corners)
        # One-sided: points behind the receiver's plane see nothing of it.
        seen = np.where((pts - c) @ n > 0, lambert(pts, p), 0.0)
        mean = np.dot(wts, seen)
        if mean < 1e-12:
            continue
        error = abs((lambert(np.zeros((1, 3)), p)[0] if np.dot(-c, n) > 0 else 0.0) - mean)
        delta = distance(np.zeros(3), p)
        first_order = min(1.0, side * side / (np.pi * delta * delta)) / delta  # (size_i/δ)·min(1, A_j/(πδ²))
        rows.append((delta, error, straddles, error / first_order))
    r = np.array(rows)
    print(f"{len(r)} facing configurations; sender: unit square; error × (δ/size_i)² by band of δ")
    for cut, label in [(0, "sender in front of the receiver's plane"), (1, "receiver's plane cuts the sender")]:
        print(label)
        for lo, hi in [(0.5, 1), (1, 2), (2, 4), (4, 10), (10, 1000)]:
            m = (r[:, 2] == cut) & (r[:, 0] >= lo) & (r[:, 0] < hi)
            if m.any():
                print(f"  δ in [{lo}, {hi}): {m.sum():5d} cases, max error {r[m, 1].max():.2e},"
                      f" max error·δ² {np.max(r[m, 1] * r[m, 0] ** 2):.4f} (1/{1 / np.max(r[m, 1] * r[m, 0] ** 2):.1f})"
                      + (f", max error / ((1/δ)·min(1, A_j/(πδ²))) {r[m, 3].max():.3f}" if cut else ""))


if __name__ == "__main__":
    main()
