#!/usr/bin/env python3
"""Compares ffcube's default form factors and sky view factors with the ray caster's on one scene.

Runs `ffcube formfactors SCENE --no-subdivide` twice (hemicube defaults; --method raycast --rays N),
each writing Matrix Market and per-patch sky view factors, and prints the largest and mean
absolute differences of F (over every entry either run has) and of the sky view factors (mean
signed and mean absolute), with the ray caster's own noise for scale: a ray-cast F has standard
error sqrt(F(1-F)/N) or less.

    python3 tools/gen_vs3_blocks.py -o blocks.vs3
    python3 tools/compare_methods.py blocks.vs3 --rays 100000
"""
import argparse
import math
import os
import subprocess
import tempfile
import time


def read_mtx(path):
    F = {}
    with open(path) as f:
        for line in f:
            if line.startswith("%"):
                continue
            break
        for line in f:
            i, j, v = line.split()
            F[int(i), int(j)] = float(v)
    return F


def read_sky(path):
    with open(path) as f:
        next(f)
        return [float(line.rsplit(",", 1)[1]) for line in f]


def read_objects(path):
    with open(path) as f:
        next(f)
        return [line.split(",")[1] for line in f]


def surface_class(name):
    """gen_vs3_blocks.py's surface names: ground_I_J, bXYroof_I_J, bXY{s,n,w,e}_I_J."""
    return "ground" if name.startswith("ground") else "roof" if "roof" in name else "wall"


def run(binary, scene, extra, out):
    mtx, sky = os.path.join(out, "F.mtx"), os.path.join(out, "sky.csv")
    t = time.time()
    subprocess.run([binary, "formfactors", scene, "--no-subdivide", "-q", "-o", mtx, "--sky", sky] + extra, check=True)
    run.objects = read_objects(sky)
    return read_mtx(mtx), read_sky(sky), time.time() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--rays", type=int, default=100000)
    ap.add_argument("--binary", default="./build/ffcube")
    ap.add_argument("--hemicube-args", default="", help="extra options of the hemicube run, e.g. '--resolution 512'")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        os.makedirs(os.path.join(d, "h"))
        os.makedirs(os.path.join(d, "r"))
        H, hs, ht = run(a.binary, a.scene, a.hemicube_args.split(), os.path.join(d, "h"))
        R, rs, rt = run(a.binary, a.scene, ["--method", "raycast", "--rays", str(a.rays)], os.path.join(d, "r"))
    keys = set(H) | set(R)
    diffs = [abs(H.get(k, 0.0) - R.get(k, 0.0)) for k in keys]
    worst_key = max(keys, key=lambda k: abs(H.get(k, 0.0) - R.get(k, 0.0)))
    fw = R.get(worst_key, 0.0)
    sky = [h - r for h, r in zip(hs, rs)]
    n = len(hs)
    print(f"scene {a.scene}: {n} patches; hemicube {ht:.1f} s, raycast ({a.rays} rays/patch) {rt:.1f} s")
    print(f"F: max |dF| = {max(diffs):.2e} at {worst_key} (raycast F {fw:.4f}, its standard error "
          f"{math.sqrt(max(fw * (1 - fw), 1e-30) / a.rays):.1e}); mean |dF| over {len(keys)} entries = "
          f"{sum(diffs) / len(diffs):.2e}")
    print(f"SVF: mean (hemicube - raycast) = {sum(sky) / n:+.2e}, mean |d| = {sum(map(abs, sky)) / n:.2e}, "
          f"max |d| = {max(map(abs, sky)):.2e}; raycast noise per patch <= {0.5 / math.sqrt(a.rays):.1e}, "
          f"of the mean <= {0.5 / math.sqrt(a.rays * n):.1e}")
    by = {}
    for name, d in zip(run.objects, sky):
        by.setdefault(surface_class(name), []).append(d)
    for c, ds in sorted(by.items()):
        print(f"SVF by surface class: {c} ({len(ds)}): mean (hemicube - raycast) = {sum(ds) / len(ds):+.2e}, "
              f"max |d| = {max(map(abs, ds)):.2e}")
    w = max(range(n), key=lambda i: abs(sky[i]))
    print(f"mean SVF: hemicube {sum(hs) / n:.5f}, raycast {sum(rs) / n:.5f}; largest difference at patch {w} "
          f"(0-based): hemicube {hs[w]:.5f}, raycast {rs[w]:.5f}")


if __name__ == "__main__":
    main()
