#!/usr/bin/env python3
"""A day of shortwave on a generated city: the step rate of `ffcube sun --sun-series` once F is
known (issue 41, part 3; docs/urban.md, "A day of shortwave"; numbers in docs/benchmarks.md).

    python3 tools/bench_shortwave.py build/ffcube /tmp/sw --triangles 22881 --seed 1

Makes (or reuses) WORKDIR/city.stl (tools/gen_city.py) and WORKDIR/F.ffm (`ffcube formfactors
--no-subdivide`), writes a 96-step day (quarter hours; the sun from east to west up to 60 degrees;
DNI and DHI of a clear day) and one albedo for the city, runs `ffcube sun --sun-series --matrix`
and prints the report's timings: the reflections' step rate (the solve alone, F known), the
direct beam (shadow polygons, or with --extra "--set sun-method=pixels" the item buffers and
their parts), the sweeps and the worst energy balance. The machine's load average
is printed before and after (the development machine is shared).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time


def day(path, steps):
    with open(path, "w") as f:
        f.write("time,azimuth,elevation,direct_normal_irradiance,diffuse_horizontal_irradiance\n")
        for k in range(steps):
            h = 24.0 * k / steps
            el = 60.0 * math.sin(math.pi * (h - 6.0) / 12.0)
            az = (180.0 + 15.0 * (h - 12.0)) % 360.0
            s = math.sin(math.radians(el))
            dni = 850.0 * s ** 0.3 if el > 0 else 0.0
            dhi = 110.0 * s + 5.0 if el > 0 else 0.0
            f.write(f"{h:05.2f},{az:.6f},{el:.6f},{dni:.6f},{dhi:.6f}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("ffcube")
    ap.add_argument("workdir")
    ap.add_argument("--triangles", type=int, default=22881)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--steps", type=int, default=96)
    ap.add_argument("--albedo", type=float, default=0.3)
    ap.add_argument("--sky-patches", default="isotropic")
    ap.add_argument("--extra", default="", help="more options for ffcube sun, e.g. '--set batch=16'")
    a = ap.parse_args()
    os.makedirs(a.workdir, exist_ok=True)
    city, ffm = os.path.join(a.workdir, "city.stl"), os.path.join(a.workdir, "F.ffm")
    here = os.path.dirname(os.path.abspath(__file__))
    if not os.path.exists(city):
        subprocess.run([sys.executable, os.path.join(here, "gen_city.py"), city, "--binary", "--triangles",
                        str(a.triangles), "--seed", str(a.seed)], check=True)
    if not os.path.exists(ffm):
        t0 = time.time()
        subprocess.run([a.ffcube, "formfactors", city, "--no-subdivide", "-q", "-o", ffm], check=True)
        print(f"F: {time.time() - t0:.1f} s (formfactors --no-subdivide)")
    sun, albedo = os.path.join(a.workdir, "sun.csv"), os.path.join(a.workdir, "albedo.csv")
    day(sun, a.steps)
    with open(albedo, "w") as f:
        f.write(f"object,albedo\ncity,{a.albedo}\n")
    report = os.path.join(a.workdir, "report.json")
    print("load average before:", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    t0 = time.time()
    subprocess.run([a.ffcube, "sun", city, "--no-subdivide", "-q", "--sun-series", sun, "--albedo", albedo, "--matrix", ffm,
                    "--sky-patches", a.sky_patches, "-o", os.path.join(a.workdir, "sw.csv"), "--report", report]
                   + a.extra.split(), check=True)
    wall = time.time() - t0
    print("load average after: ", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    r = json.load(open(report))
    rf, t = r["reflections"], r["time"]
    print(f"patches {r['patches']}, steps {r['steps']} ({rf['steps_solved']} with light), sky {r['sky']['model']}")
    print(f"reflections: {rf['steps_solved']} steps in {t['reflections']:.3f} s = {rf['steps_per_second']:.1f} steps/s, "
          f"at most {rf['max_sweeps']} passes over F, contraction {rf['contraction']:.3f}")
    what = "shadow polygons" if r['sun'].get('method', 'pixels') == 'clip' else "item buffers"
    print(f"direct beam: {r['sun']['renders']} {what} in {t['sun']:.1f} s ({t['sun'] / max(1, r['sun']['renders']):.3f} s each)")
    if 'sun_parts' in t and t['sun_parts'].get('draw', 0) > 0:
        p = t['sun_parts']
        print("item buffers: " + ", ".join(f"{k} {p[k]:.2f} s" for k in ('setup', 'project', 'draw', 'readback', 'count')))
    print(f"sky: {t['sky']:.2f} s; loading {t['loading']:.1f} s, F read {t['rows']:.1f} s, writing {t['writing']:.1f} s; "
          f"whole run {wall:.1f} s")
    print(f"energy balance: worst |absorbed + escaped - incident| / incident = {r['energy']['max_relative_error']:.2e}")


if __name__ == "__main__":
    main()
