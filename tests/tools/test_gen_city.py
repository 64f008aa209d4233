#!/usr/bin/env python3
"""tools/gen_city.py: the facet count is met exactly, the same seed gives the same bytes, ASCII
and binary hold the same facets, every facet's normal agrees with its winding, and ffcube loads
the city with one patch per facet, every building closed but for its base (each wall and roof
edge shared by exactly two facets wound opposite ways).

    python3 tests/tools/test_gen_city.py SOURCE_DIR FFCUBE
"""
import collections
import json
import math
import os
import struct
import subprocess
import sys
import tempfile


def read_binary(path):
    data = open(path, "rb").read()
    (n,) = struct.unpack_from("<I", data, 80)
    assert len(data) == 84 + 50 * n, (len(data), n)
    out = []
    for k in range(n):
        v = struct.unpack_from("<12f", data, 84 + 50 * k)
        out.append((v[0:3], (v[3:6], v[6:9], v[9:12])))
    return out


def read_ascii(path):
    out, normal, verts = [], None, []
    for line in open(path):
        w = line.split()
        if w[:2] == ["facet", "normal"]:
            normal, verts = tuple(map(float, w[2:5])), []
        elif w[:1] == ["vertex"]:
            verts.append(tuple(map(float, w[1:4])))
        elif w[:1] == ["endfacet"]:
            out.append((normal, tuple(verts)))
    return out


def winding_normal(t):
    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = t
    u, v = (bx - ax, by - ay, bz - az), (cx - ax, cy - ay, cz - az)
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    length = math.sqrt(sum(c * c for c in n))
    return tuple(c / length for c in n)


def main():
    src, ffcube = sys.argv[1], sys.argv[2]
    gen = os.path.join(src, "tools", "gen_city.py")
    failures = []

    def check(cond, what):
        if not cond:
            failures.append(what)

    with tempfile.TemporaryDirectory() as d:
        for ground in ("lots", "grid"):
            for count in (20, 37, 500, 1501):
                a, b, b2 = (os.path.join(d, f"{ground}{count}{s}.stl") for s in ("a", "b", "b2"))
                for path, extra in ((a, []), (b, ["--binary"]), (b2, ["--binary"])):
                    subprocess.run([sys.executable, gen, path, "--triangles", str(count), "--seed", "5", "--ground", ground]
                                   + extra, check=True, capture_output=True)
                fa, fb = read_ascii(a), read_binary(b)
                check(len(fa) == count and len(fb) == count, f"{ground} {count}: {len(fa)} / {len(fb)} facets")
                check(open(b, "rb").read() == open(b2, "rb").read(), f"{ground} {count}: same seed, other bytes")
                for k, ((na, ta), (nb, tb)) in enumerate(zip(fa, fb)):
                    # ASCII keeps 6 decimals (coordinates up to about 2,000 m: 5e-7 absolute);
                    # binary keeps float (2,000 × 6e-8 = 1.2e-4 absolute at most).
                    if any(abs(x - y) > 2e-4 for va, vb in zip(ta, tb) for x, y in zip(va, vb)):
                        failures.append(f"{ground} {count}: facet {k} differs between ASCII and binary")
                        break
                    w = winding_normal(ta)
                    # Unit normals written with 7 significant digits, against the winding's.
                    if sum(x * y for x, y in zip(w, na)) < 1 - 1e-6:
                        failures.append(f"{ground} {count}: facet {k} normal {na} against its winding {w}")
                        break
                # Closed buildings: an edge above the ground (z > 0 at an end) is used by exactly
                # two facets, once in each direction.
                edges = collections.Counter()
                for _, t in fa:
                    for i in range(3):
                        p, q = t[i], t[(i + 1) % 3]
                        if p[2] > 0 or q[2] > 0:
                            edges[(p, q)] += 1
                bad = [e for e, c in edges.items() if c != 1 or edges.get((e[1], e[0])) != 1]
                check(not bad, f"{ground} {count}: {len(bad)} building edges not shared by two facets, e.g. {bad[:1]}")
                if count != 500:
                    continue  # ffcube loads one of each kind (its start-up costs seconds on llvmpipe)
                r = subprocess.run([ffcube, "formfactors", b, "--no-subdivide", "--correct", "none", "--resolution", "16",
                                    "--report", os.path.join(d, "r.json"), "-q"], capture_output=True, text=True)
                check(r.returncode == 0, f"{ground} {count}: ffcube failed: {r.stderr}")
                if r.returncode == 0:
                    patches = json.load(open(os.path.join(d, "r.json")))["patches"]
                    check(patches == count, f"{ground} {count}: {patches} patches")
    for f in failures:
        print("FAIL:", f)
    print("ok" if not failures else f"{len(failures)} failures")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
