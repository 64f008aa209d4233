#!/usr/bin/env python3
"""Two form-factor matrices against a reference, row by row (Matrix Market, as `ffcube
formfactors -o F.mtx` writes them): how many rows differ between A and B, and each one's mean
and worst row L1 distance Σ_j |F_ij − R_ij| from the reference (the ray caster with many rays,
say), over all rows and over the rows that differ, and the mean row-sum distance.

    python3 tools/compare_mtx.py ray.mtx before.mtx after.mtx
"""
import collections
import sys


def load(path):
    rows = collections.defaultdict(dict)
    with open(path) as f:
        header = False
        for line in f:
            if line.startswith("%"):
                continue
            parts = line.split()
            if not header:  # the size line: rows, columns, entries
                header = True
                continue
            rows[int(parts[0])][int(parts[1])] = float(parts[2])
    return rows


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    ref, a, b = (load(p) for p in sys.argv[1:])
    rows = sorted(set(ref) | set(a) | set(b))

    def l1(m, i):
        x, r = m.get(i, {}), ref.get(i, {})
        return sum(abs(x.get(j, 0.0) - r.get(j, 0.0)) for j in set(x) | set(r))

    ea, eb = [l1(a, i) for i in rows], [l1(b, i) for i in rows]
    changed = [k for k, i in enumerate(rows) if a.get(i) != b.get(i)]
    print(f"rows {len(rows)}, differing between A and B {len(changed)}")
    print(f"row L1 from the reference, mean: A {sum(ea) / len(ea):.5f}  B {sum(eb) / len(eb):.5f}")
    print(f"row L1 from the reference, worst: A {max(ea):.5f}  B {max(eb):.5f}")
    if changed:
        ca, cb = [ea[k] for k in changed], [eb[k] for k in changed]
        worse = sum(1 for x, y in zip(ca, cb) if y > x + 0.01)
        print(f"differing rows, mean L1: A {sum(ca) / len(ca):.5f}  B {sum(cb) / len(cb):.5f}; B worse by > 0.01: {worse}")
    sums = {name: [sum(m.get(i, {}).values()) for i in rows] for name, m in (("R", ref), ("A", a), ("B", b))}
    da = sum(abs(x - r) for x, r in zip(sums["A"], sums["R"])) / len(rows)
    db = sum(abs(x - r) for x, r in zip(sums["B"], sums["R"])) / len(rows)
    print(f"row sum distance from the reference, mean: A {da:.5f}  B {db:.5f}")


if __name__ == "__main__":
    main()
