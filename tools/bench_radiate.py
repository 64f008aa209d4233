#!/usr/bin/env python3
"""Scale of `ffcube radiate` (docs/benchmarks.md, "radiate at 20,000 patches"): F computed once into
a .ffm for a closed box of PATCHES patches (examples/cube.obj), then
  1. `ffcube radiate --matrix F.ffm` (wall seconds, peak RSS by GNU time, the report's phases);
  2. ffcube.Radiation(F.ffm, scene, emissivity): new temperatures solved again and again on the F
     kept in memory (seconds per solve(), GMRES products), as a transient model's steps would.
Usage: PYTHONPATH=build/python /usr/bin/python3 tools/bench_radiate.py [PATCHES] [RESOLUTION] [FFM]
(default 20000 32; FFM: reuse an F.ffm made with the same PATCHES). Prints the load average, since
the machine is shared."""

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import ffcube

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BINARY = os.environ.get("FFCUBE", os.path.join(ROOT, "build", "ffcube"))
CUBE = os.path.join(ROOT, "examples", "cube.obj")
EPS = {"x0": 0.9, "x1": 0.8, "y0": 0.5, "y1": 0.5, "z0": 0.05, "z1": 0.9}


def timed(cmd):
    """Runs cmd under GNU time: (seconds, peak MB)."""
    with tempfile.NamedTemporaryFile("r") as t:
        subprocess.run(["/usr/bin/time", "-f", "%e %M", "-o", t.name, *cmd], check=True)
        secs, kib = t.read().split()
    return float(secs), int(kib) / 1024


def main():
    patches = int(sys.argv[1]) if len(sys.argv) > 1 else 20000
    resolution = int(sys.argv[2]) if len(sys.argv) > 2 else 32
    ffm = sys.argv[3] if len(sys.argv) > 3 else None
    print(f"load average at start: {os.getloadavg()}")
    with tempfile.TemporaryDirectory() as d:
        if ffm is None:
            ffm = os.path.join(d, "F.ffm")
            secs, mb = timed([BINARY, "formfactors", CUBE, "--patches", str(patches), "--resolution", str(resolution),
                              "-q", "-o", ffm])
            print(f"formfactors: {secs:.1f} s, peak {mb:.0f} MB, {os.path.getsize(ffm) / 1e6:.0f} MB file")
        surfaces = os.path.join(d, "s.csv")
        with open(surfaces, "w") as f:
            f.write("object,emissivity,temperature,heat_flux\n")
            f.write("x0,0.9,400,\nx1,0.8,300,\ny0,0.5,,0\ny1,0.5,,0\nz0,0.05,,0\nz1,0.9,350,\n")
        report = os.path.join(d, "r.json")
        secs, mb = timed([BINARY, "radiate", CUBE, "--patches", str(patches), "--matrix", ffm, "--surfaces", surfaces,
                          "-q", "-o", os.path.join(d, "q.csv"), "--report", report])
        with open(report) as f:
            r = json.load(f)
        print(f"ffcube radiate --matrix: {secs:.2f} s wall, peak {mb:.0f} MB; patches {r['patches']}, "
              f"nnz {r.get('nnz', '?')}; loading {r['time']['loading']:.2f} s, rows (reading F) {r['time']['rows']:.2f} s, "
              f"matrix checks {r['time']['matrix_checks']:.2f} s, "
              f"solve {r['time']['solve']:.3f} s ({r['solver']['iterations']} GMRES products, residual "
              f"{r['solver']['residual']:.2e}), energy balance {r['energy']['relative_error']:.2e}")

        secs, mb = timed([BINARY, "radiate", CUBE, "--patches", str(patches), "--matrix", ffm, "--surfaces", surfaces,
                          "--set", "stream-matrix=true", "-q", "-o", os.path.join(d, "qs.csv"), "--report", report])
        with open(report) as f:
            r = json.load(f)
        with open(os.path.join(d, "q.csv")) as a, open(os.path.join(d, "qs.csv")) as b:
            same = a.read() == b.read()
        print(f"ffcube radiate --matrix --set stream-matrix=true: {secs:.2f} s wall, peak {mb:.0f} MB; solve "
              f"{r['time']['solve']:.2f} s, {r['matrix_passes']} passes over the file; Q.csv {'identical' if same else 'DIFFERENT'}")

        scene = ffcube.load_scene(CUBE, patches=patches, quiet=True)
        t0 = time.perf_counter()
        rad = ffcube.Radiation(ffm, scene, EPS)
        print(f"Radiation(F.ffm, ...): {time.perf_counter() - t0:.2f} s to read F once")
        rng = np.random.default_rng(1)
        names = scene.objects
        z0 = scene.patch_object == names.index("z0")
        for tolerance in (1e-10, 1e-6):
            seconds, cpu, products = [], [], []
            for _ in range(10):
                T = rng.uniform(280.0, 420.0, len(names))[scene.patch_object]
                T = T * rng.uniform(0.99, 1.01, len(scene))  # a non-uniform field, as a thermal model gives
                T[z0] = np.nan
                q = np.where(z0, 0.0, np.nan)
                t0, c0 = time.perf_counter(), time.process_time()
                res = rad.solve(temperature=T, heat_flux=q, tolerance=tolerance)
                seconds.append(time.perf_counter() - t0)
                cpu.append(time.process_time() - c0)
                products.append(res["iterations"])
            print(f"Radiation.solve(tolerance={tolerance:g}), 10 new temperature fields: median {np.median(seconds):.3f} s, "
                  f"max {max(seconds):.3f} s wall per solve; CPU {np.median(cpu):.3f} s (all threads); GMRES products "
                  f"{min(products)}..{max(products)}")
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
