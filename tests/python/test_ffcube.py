"""Tests of the Python module `ffcube` (python/module.cpp), run by CTest (tests/CMakeLists.txt)
with PYTHONPATH=<build>/python, FFCUBE_BINARY (the command line) and FFCUBE_SOURCE_DIR set.
Small scenes, llvmpipe, no GPU. References: the command line's own output for the same options
(the module must give its rows), closed forms, and counts."""

import json
import math
import os
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import numpy as np
import scipy.io
import scipy.sparse

import ffcube

BINARY = os.environ["FFCUBE_BINARY"]
EXAMPLES = os.path.join(os.environ["FFCUBE_SOURCE_DIR"], "examples")
SQUARES = os.path.join(EXAMPLES, "parallel_squares.obj")
CUBE = os.path.join(EXAMPLES, "cube.obj")
L_ROOM = os.path.join(EXAMPLES, "l_shaped_room.vs3")


def run_cli(*args):
    return subprocess.run([BINARY, *map(str, args)], capture_output=True, text=True)


def ff_parallel_squares(x, y):
    """Howell C-11: opposed parallel rectangles x by y (in units of their distance)."""
    a, b = math.sqrt(1 + x * x), math.sqrt(1 + y * y)
    return 2 / (math.pi * x * y) * (math.log(a * b / math.sqrt(1 + x * x + y * y)) + x * b * math.atan(x / b)
                                    + y * a * math.atan(y / a) - x * math.atan(x) - y * math.atan(y))


def object_form_factor(scene, F, a, b):
    """Area-weighted F from object a to object b."""
    A = scene.areas
    ia, ib = scene.patch_object == a, scene.patch_object == b
    return float(A[ia] @ np.asarray(F[ia][:, ib].sum(axis=1)).ravel() / A[ia].sum())


class Scene(unittest.TestCase):
    def test_parallel_squares(self):
        s = ffcube.load_scene(SQUARES, max_patch_edge=0.25, quiet=True)
        # Two unit squares split so that no edge exceeds 0.25: 4 x 4 patches each.
        self.assertEqual(len(s), 32)
        self.assertEqual(s.objects, ["a", "b"])
        self.assertEqual(list(np.bincount(s.patch_object)), [16, 16])
        self.assertEqual(s.areas.dtype, np.float64)
        # Each square's patches tile it: area 1 (rounding of a few additions: 1e-12 is plenty).
        for o in (0, 1):
            self.assertAlmostEqual(s.areas[s.patch_object == o].sum(), 1.0, delta=1e-12)
        self.assertEqual(s.centroids.shape, (32, 3))
        # Square a lies at z = 0 facing +z, b at z = 1 facing -z.
        np.testing.assert_array_equal(s.normals[s.patch_object == 0][:, 2], 1.0)
        np.testing.assert_array_equal(s.normals[s.patch_object == 1][:, 2], -1.0)
        self.assertEqual(s.report["patches"], 32)

    def test_contact_cuts_are_the_command_lines(self):
        s = ffcube.load_scene(patches=200, contact_cuts="on", quiet=True)
        cuts = s.report["meshing"]["contact_cuts"]
        self.assertEqual((cuts["contacts"], cuts["receivers"]), (2, 1))  # both blocks on the floor
        with tempfile.TemporaryDirectory() as d:
            r = run_cli("formfactors", "--patches", 200, "--contact-cuts", "on", "--method", "raycast", "--rays", 1, "-q",
                        "--report", os.path.join(d, "r.json"))
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(d, "r.json")) as f:
                report = json.load(f)
        self.assertEqual(s.fingerprint, report["fingerprint"])
        # "auto", the default, cuts as "on" does (the blocks stand on the floor); "off" meshes another scene.
        self.assertEqual(s.fingerprint, ffcube.load_scene(patches=200, quiet=True).fingerprint)
        self.assertNotEqual(s.fingerprint, ffcube.load_scene(patches=200, contact_cuts="off", quiet=True).fingerprint)

    def test_builtin_cornell_box(self):
        s = ffcube.load_scene(patches=200, quiet=True)
        self.assertIn("light", s.objects)
        self.assertEqual(len(s.areas), len(s))
        # The same mesh as the command line's for --patches 200.
        with tempfile.TemporaryDirectory() as d:
            r = run_cli("formfactors", "--patches", 200, "--method", "raycast", "--rays", 1, "-q", "--report",
                        os.path.join(d, "r.json"))
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(d, "r.json")) as f:
                report = json.load(f)
        self.assertEqual(len(s), report["patches"])
        self.assertEqual(s.fingerprint, report["fingerprint"])


class FormFactors(unittest.TestCase):
    def assert_same_as_cli(self, scene_path, cli_args, **options):
        """The module's F against `ffcube formfactors ... -o F.mtx`: the .mtx prints each float32
        entry to 9 significant digits, which reads back to the same float32 (9 digits round-trip
        every binary32), so the entries must be equal bit for bit."""
        F = ffcube.form_factors(scene_path, quiet=True, **options)
        self.assertIsInstance(F, scipy.sparse.csr_matrix)
        self.assertEqual(F.dtype, np.float32)
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "F.mtx")
            r = run_cli("formfactors", scene_path, *cli_args, "-q", "-o", out)
            self.assertEqual(r.returncode, 0, r.stderr)
            M = scipy.io.mmread(out).tocsr()
        M.sort_indices()
        F.sort_indices()
        self.assertEqual(F.shape, M.shape)
        np.testing.assert_array_equal(F.indptr, M.indptr)
        np.testing.assert_array_equal(F.indices, M.indices)
        np.testing.assert_array_equal(F.data, M.data.astype(np.float32))
        return F

    def test_hemicube_rows_are_the_command_lines(self):
        self.assert_same_as_cli(CUBE, ["--max-patch-edge", 0.5, "--resolution", 32, "--threads", 2],
                                max_patch_edge=0.5, resolution=32, threads=2)

    def test_options_reach_the_pipeline(self):
        # Non-default options on both sides. Each of these changes F on its own (correct, rotate,
        # enforce, resolution; rays, seed, near_k, near_min_ff: checked when this test was written), so an
        # option the module dropped or misread would make its F differ from the command line's.
        self.assert_same_as_cli(CUBE, ["--max-patch-edge", 0.5, "--resolution", 16, "--correct", "none", "--no-rotate",
                                       "--enforce", "both", "--threads", 1],
                                max_patch_edge=0.5, resolution=16, correct="none", rotate=False, enforce="both", threads=1)
        self.assert_same_as_cli(SQUARES, ["--max-patch-edge", 0.5, "--method", "raycast", "--rays", 256, "--seed", 7,
                                          "--near-k", 2],
                                max_patch_edge=0.5, method="raycast", rays=256, seed=7, near_k=2)
        # near_min_ff 0.6 leaves 24 of the 32 near pairs to the rays (their bounds are 0.47 and
        # 0.29; straight across 0.93): F differs from the default's (0.03: all 32 exact).
        F = self.assert_same_as_cli(SQUARES, ["--max-patch-edge", 0.5, "--method", "raycast", "--rays", 256,
                                              "--near-min-ff", 0.6],
                                    max_patch_edge=0.5, method="raycast", rays=256, near_min_ff=0.6)
        F0 = ffcube.form_factors(SQUARES, max_patch_edge=0.5, method="raycast", rays=256, quiet=True)
        self.assertNotEqual((F != F0).nnz, 0)

    def test_tolerance_is_the_command_lines(self):
        # Ray rows refined to a target (docs/accuracy.md, "Accuracy by target"): the module's
        # tolerance= reaches the rows (2e-3 gives other rows than 1e-2, bit for bit the command
        # line's), and a target double precision cannot honour is refused as on the command line.
        # (Without the correction, which makes every pair of these squares exact.)
        F = self.assert_same_as_cli(SQUARES, ["--max-patch-edge", 0.5, "--method", "raycast", "--correct", "none",
                                              "--tolerance", 2e-3],
                                    max_patch_edge=0.5, method="raycast", correct="none", tolerance=2e-3)
        F0 = ffcube.form_factors(SQUARES, max_patch_edge=0.5, method="raycast", correct="none", tolerance=1e-2, quiet=True)
        self.assertNotEqual((F != F0).nnz, 0)
        for bad in (0.0, 1e-12, 1.0, float("nan")):
            with self.assertRaisesRegex(ValueError, "tolerance"):
                ffcube.form_factors(SQUARES, method="raycast", tolerance=bad, quiet=True)

    def test_exact_visibility_is_the_command_lines(self):
        # --exact-visibility changes F on the unsubdivided L-room (its refused near pairs get the
        # exact factor past their occluders, tests/cli/test_view3d_l_room_cli.cpp), so a dropped
        # keyword would differ from the command line's matrix.
        # Its default is "auto" (which makes those pairs exact here too); "off" and 0 turn it off.
        F = self.assert_same_as_cli(L_ROOM, ["--no-subdivide", "--exact-visibility", 8],
                                    no_subdivide=True, exact_visibility=8)
        F0 = self.assert_same_as_cli(L_ROOM, ["--no-subdivide", "--exact-visibility", "off"],
                                     no_subdivide=True, exact_visibility="off")
        self.assertNotEqual((F != F0).nnz, 0)
        self.assertEqual((F0 != ffcube.form_factors(L_ROOM, no_subdivide=True, exact_visibility=0, quiet=True)).nnz, 0)
        Fa = self.assert_same_as_cli(L_ROOM, ["--no-subdivide"], no_subdivide=True, exact_visibility="auto")
        self.assertEqual((Fa != ffcube.form_factors(L_ROOM, no_subdivide=True, quiet=True)).nnz, 0)

    def test_cost_model_is_the_command_lines(self):
        # A fast device's model (pixel_ns 0.001) turns the far field off on the parallel squares
        # (on with the built-in model: tests/cli/test_cost_model_cli.cpp), so the matrices differ
        # and a dropped keyword would give the built-in one.
        with tempfile.TemporaryDirectory() as d:
            model = os.path.join(d, "fast.json")
            with open(model, "w") as f:
                f.write('{"pixel_ns": 0.001, "cpu_scale": 1}')
            F = self.assert_same_as_cli(SQUARES, ["--resolution", 64, "--cost-model", model], resolution=64,
                                        cost_model=model)
            F0 = ffcube.form_factors(SQUARES, resolution=64, quiet=True)
            self.assertNotEqual((F != F0).nnz, 0)
            with self.assertRaises(ffcube.InputError):
                ffcube.form_factors(SQUARES, resolution=64, quiet=True, cost_model=os.path.join(d, "none.json"))

    def test_same_rows_for_any_thread_count(self):
        s = ffcube.load_scene(CUBE, max_patch_edge=0.5, quiet=True)
        F1 = ffcube.form_factors(s, resolution=32, threads=1, quiet=True)
        F2 = ffcube.form_factors(s, resolution=32, threads=2, quiet=True)
        self.assertEqual((F1 != F2).nnz, 0)
        # numpy's scalars are taken as the Python numbers they stand for.
        F3 = ffcube.form_factors(s, resolution=np.int64(32), threads=np.uint8(2), near_k=np.float32(3),
                                 quiet=np.bool_(True))
        self.assertEqual((F1 != F3).nnz, 0)

    def test_against_the_closed_form(self):
        s = ffcube.load_scene(SQUARES, max_patch_edge=0.25, quiet=True)
        exact = ff_parallel_squares(1.0, 1.0)
        self.assertAlmostEqual(exact, 0.19982, delta=5e-6)  # Howell C-11, as tabulated (5 digits)
        # far_field='on' proves the two planes see each other unoccluded, so every entry is an
        # analytic area-to-area value (near pairs exact to ~1e-12, far pairs integrated within
        # their quadrature bound) and no row is rendered; stored as float32, each entry is within
        # 2^-24 relative, 1.2e-8 of the 0.2 total. A rendered row at resolution 32 would be off by
        # about a pixel's delta-F (~1e-3), so 1e-6 tells the two apart with margin either way.
        F = ffcube.form_factors(s, resolution=32, far_field="on", quiet=True)
        self.assertAlmostEqual(object_form_factor(s, F, 0, 1), exact, delta=1e-6)
        self.assertAlmostEqual(object_form_factor(s, F, 1, 0), exact, delta=1e-6)
        # Rays: 4096 per patch, 16 patches: the standard error of the object's F is
        # sqrt(F(1 - F) / 65536) = 1.6e-3; 5 sigma.
        R = ffcube.form_factors(s, method="raycast", rays=4096, correct="none", quiet=True)
        sigma = math.sqrt(exact * (1 - exact) / (4096 * 16))
        self.assertAlmostEqual(object_form_factor(s, R, 0, 1), exact, delta=5 * sigma)

    def test_worker_processes_inside_python(self):
        # A fresh interpreter with one thread: the hemicube workers are forked processes (the
        # children run only ffcube's C++ worker loop and leave with _exit). With another Python
        # thread alive they are threads. Both give the command line's rows.
        code = ("import sys, threading, ffcube\n"
                "done = threading.Event()\n"
                "if sys.argv[1] == 'thread': threading.Thread(target=done.wait).start()\n"
                "F, report = ffcube.form_factors(sys.argv[2], max_patch_edge=0.5, resolution=32, threads=2, "
                "report=True, quiet=True)\n"
                "done.set()\n"
                "import numpy as np\n"  # after the call: numpy's BLAS may start threads
                "np.save(sys.argv[3], F.toarray())\n"
                "print(report['workers'], report['threads'])\n")
        results = {}
        with tempfile.TemporaryDirectory() as d:
            for mode in ("alone", "thread"):
                out = os.path.join(d, mode + ".npy")
                r = subprocess.run([sys.executable, "-c", code, mode, CUBE, out], capture_output=True, text=True)
                self.assertEqual(r.returncode, 0, r.stderr)
                results[mode] = (np.load(out), r.stdout.split())
        self.assertEqual(results["alone"][1], ["processes", "2"])
        self.assertEqual(results["thread"][1], ["threads", "2"])
        np.testing.assert_array_equal(results["alone"][0], results["thread"][0])
        F = self.assert_same_as_cli(CUBE, ["--max-patch-edge", 0.5, "--resolution", 32, "--threads", 2],
                                    max_patch_edge=0.5, resolution=32, threads=2)
        np.testing.assert_array_equal(F.toarray(), results["alone"][0])

    def test_report_is_the_command_lines(self):
        F, report = ffcube.form_factors(CUBE, max_patch_edge=0.5, resolution=16, enforce="closure", report=True,
                                        quiet=True)
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "r.json")
            r = run_cli("formfactors", CUBE, "--max-patch-edge", 0.5, "--resolution", 16, "--enforce", "closure", "-q",
                        "--report", out)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(out) as f:
                cli = json.load(f)
        # The same matrix: the same counts and checks, to the last bit (both are doubles computed
        # the same way from the same float32 entries).
        for r in (report, cli):
            del r["enforce"]["seconds"]
        for key in ("command", "patches", "fingerprint", "nnz", "row_sums", "reciprocity", "enforce", "method"):
            self.assertEqual(report[key], cli[key], key)
        self.assertEqual(report["nnz"], F.nnz)
        # The cube is closed and closure was enforced: rows sum to 1 up to float32 storage,
        # 2^-24 relative per entry, at most n entries per row.
        n = F.shape[0]
        self.assertAlmostEqual(report["row_sums"]["min"], 1.0, delta=n * 2.0**-24)
        # The report's row sums are F's (double sums of n terms <= 1 in another order: n x 2^-53).
        self.assertAlmostEqual(report["row_sums"]["min"], float(F.astype(np.float64).sum(axis=1).min()), delta=n * 2.0**-53)

    def test_gil_is_released(self):
        # A Python thread counts while form_factors runs. Holding the GIL, the call would let it
        # run only during the call's own Python work (argument parsing and building the
        # csr_matrix: milliseconds of a call of about a second), about 1% of its free rate; with
        # the GIL released it runs throughout, at its free rate less its share of the cores. Its
        # free rate is measured first, while the main thread sleeps; a tenth of it separates the
        # two cases with a margin of ten on either side.
        count = [0]
        stop = threading.Event()

        def counter():
            while not stop.is_set():
                count[0] += 1

        s = ffcube.load_scene(CUBE, max_patch_edge=0.25, quiet=True)
        ffcube.form_factors(s, resolution=16, threads=1, quiet=True)  # numpy, scipy imported; GL warm
        t = threading.Thread(target=counter)
        t.start()
        try:
            c0, t0 = count[0], time.perf_counter()
            time.sleep(0.5)
            free_rate = (count[0] - c0) / (time.perf_counter() - t0)
            c1, t1 = count[0], time.perf_counter()
            ffcube.form_factors(s, resolution=128, threads=1, quiet=True)
            call_rate = (count[0] - c1) / (time.perf_counter() - t1)
        finally:
            stop.set()
            t.join()
        self.assertGreater(call_rate, 0.1 * free_rate, f"counter rate {call_rate:.0f}/s during the call, {free_rate:.0f}/s free")


class Solve(unittest.TestCase):
    def test_radiosity_is_the_command_lines(self):
        B, report = ffcube.solve(None, patches=200, resolution=32, threads=2, tolerance=1e-6, quiet=True)
        self.assertEqual(B.shape, (len(ffcube.load_scene(patches=200, quiet=True)), 3))
        self.assertTrue(report["converged"])
        self.assertEqual(report["solver"]["batch"], 16)
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "B.csv")
            r = run_cli("solve", "--patches", 200, "--resolution", 32, "--threads", 2, "--tolerance", 1e-6, "-q",
                        "--radiosity", out)
            self.assertEqual(r.returncode, 0, r.stderr)
            cli = np.loadtxt(out, delimiter=",", skiprows=1, usecols=(3, 4, 5))
        # The same rows and the same shooting order give the same B; the CSV prints 9 significant
        # digits, so each value is within 5e-9 relative of B (1e-8 allows the decimal conversion).
        np.testing.assert_allclose(B, cli, rtol=1e-8, atol=0)
        # Energy balance as the report gives it (the solver's own check, to its tolerance).
        self.assertLess(report["energy"]["relative_error"], 1e-6)

    def test_far_field_emitters_as_the_command_line(self):
        # solve()'s default is `ffcube solve`'s: the far field kept on the emitting rows where it is
        # over budget for every row (docs/adaptive.md, "The default within 0.1%"); False turns it off.
        for flag, start in ((True, "on for the"), (False, "off")):
            _, report = ffcube.solve(None, patches=200, resolution=32, threads=2, far_field_emitters=flag, quiet=True)
            self.assertTrue(report["corrections"]["far_field"].startswith(start), report["corrections"]["far_field"])

    def test_not_converged(self):
        with self.assertRaises(ffcube.NotConvergedError) as e:
            ffcube.solve(None, patches=200, resolution=16, max_iterations=1, quiet=True)
        self.assertIsInstance(e.exception, RuntimeError)
        self.assertIn("shot", str(e.exception))
        B, report = ffcube.solve(None, patches=200, resolution=16, max_iterations=1, allow_unconverged=True,
                                 overshoot=True, quiet=True)
        self.assertFalse(report["converged"])
        self.assertEqual(report["iterations"], 1)
        self.assertEqual(report["solver"]["overshoot"], 1.2)  # True: the command line's --overshoot alone
        self.assertTrue(np.isfinite(B).all())
        with self.assertRaises(TypeError):
            ffcube.solve(None, enforce="both")  # acts on a finished matrix: form_factors only


class Errors(unittest.TestCase):
    def cli_message(self, *args):
        r = run_cli(*args)
        self.assertEqual(r.returncode, 2, r.stderr)
        prefix = "ffcube: error: "
        self.assertTrue(r.stderr.startswith(prefix), r.stderr)
        return r.stderr[len(prefix):].strip()

    def test_bad_path_carries_the_command_lines_message(self):
        missing = os.path.join(EXAMPLES, "no_such_scene.obj")
        with self.assertRaises(ffcube.InputError) as e:
            ffcube.form_factors(missing, quiet=True)
        self.assertIsInstance(e.exception, ValueError)
        self.assertEqual(str(e.exception), self.cli_message("formfactors", missing, "-q"))
        with tempfile.TemporaryDirectory() as d:
            bad = os.path.join(d, "bad.obj")
            with open(bad, "w") as f:
                f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
            with self.assertRaises(ffcube.InputError) as e:
                ffcube.load_scene(bad)
            self.assertEqual(str(e.exception), self.cli_message("formfactors", bad, "-q"))
            self.assertIn("bad.obj:4", str(e.exception))

    def test_bad_option_value(self):
        with self.assertRaises(ffcube.InputError) as e:
            ffcube.form_factors(CUBE, resolution=7, quiet=True)
        self.assertEqual(str(e.exception), self.cli_message("formfactors", CUBE, "--resolution", 7, "-q"))
        # The range of --exact-visibility is checked in one place (validate(RowOptions)) for both.
        with self.assertRaises(ffcube.InputError) as e:
            ffcube.form_factors(CUBE, exact_visibility=65, quiet=True)
        self.assertEqual(str(e.exception), self.cli_message("formfactors", CUBE, "--exact-visibility", 65, "-q"))
        self.assertIn("--exact-visibility 65: must be within 0..64", str(e.exception))
        with self.assertRaises(ValueError) as e:
            ffcube.form_factors(CUBE, exact_visibility=-1, quiet=True)
        self.assertIn("--exact-visibility -1", str(e.exception))
        self.assertNotEqual(run_cli("formfactors", CUBE, "--exact-visibility", -1, "-q").returncode, 0)
        # A word that is neither auto, off nor a number: the same rule (parse_exact_visibility);
        # the command line reports it as CLI11 reports a bad value (exit 2).
        with self.assertRaises(ffcube.InputError) as e:
            ffcube.form_factors(CUBE, exact_visibility="sometimes", quiet=True)
        rule = "--exact-visibility sometimes: must be auto, off or a number of occluders 0..64"
        self.assertEqual(str(e.exception), rule)
        r = run_cli("formfactors", CUBE, "--exact-visibility", "sometimes", "-q")
        self.assertEqual(r.returncode, 2)
        self.assertIn(rule, r.stderr)
        with self.assertRaises(ValueError) as e:
            ffcube.form_factors(CUBE, method="radiance", quiet=True)
        self.assertIn("--method radiance", str(e.exception))
        with self.assertRaises(ValueError) as e:
            ffcube.form_factors(CUBE, threads=-1)
        self.assertIn("--threads -1", str(e.exception))
        with self.assertRaises(ValueError) as e:
            ffcube.solve(CUBE, solver="newton")
        self.assertIn("newton", str(e.exception))

    def test_unknown_or_misplaced_option(self):
        with self.assertRaises(TypeError) as e:
            ffcube.form_factors(CUBE, resolutoin=64)
        self.assertIn("'resolutoin'", str(e.exception))
        self.assertIn("resolution", str(e.exception))  # the list of accepted names
        with self.assertRaises(TypeError) as e:
            ffcube.form_factors(CUBE, resolution="64")
        self.assertIn("resolution", str(e.exception))
        s = ffcube.load_scene(CUBE, quiet=True)
        with self.assertRaises(TypeError) as e:
            ffcube.form_factors(s, max_patch_edge=0.5)
        self.assertIn("max_patch_edge", str(e.exception))
        with self.assertRaises(TypeError):
            ffcube.load_scene(CUBE, resolution=64)
        with self.assertRaises(TypeError):
            ffcube.form_factors(42)


SIGMA = 5.670374419e-8


def dense_radiation(F, area, eps, temperature, heat_flux):
    """Independent dense solve of the net radiation method (docs/radiate.md) on the float rows:
    T given: J - (1 - eps) F J = eps sigma T^4; q given: J - F J = q. Returns (q, T, J)."""
    F = np.asarray(F.todense(), dtype=np.float64)
    n = len(area)
    held = ~np.isnan(temperature)
    c = np.where(held, 1.0 - eps, 1.0)
    b = np.where(held, eps * SIGMA * np.nan_to_num(temperature) ** 4, np.nan_to_num(heat_flux))
    J = np.linalg.solve(np.eye(n) - c[:, None] * F, b)
    G = F @ J
    q = np.where(held, eps * (SIGMA * np.nan_to_num(temperature) ** 4 - G), heat_flux)
    T = np.where(held, temperature, ((G + np.nan_to_num(heat_flux) / eps) / SIGMA) ** 0.25)
    return q, T, J


class Radiate(unittest.TestCase):
    # The cube of examples/cube.obj at 0.25: 96 patches; examples/cube_surfaces.csv holds three walls
    # and leaves three adiabatic (eps down to 0.05).
    SURFACES = os.path.join(EXAMPLES, "cube_surfaces.csv")

    def test_radiate_matches_a_dense_solve_and_the_command_line(self):
        res, report = ffcube.radiate(CUBE, max_patch_edge=0.25, surfaces=self.SURFACES, quiet=True)
        self.assertEqual(report["command"], "radiate")
        self.assertTrue(report["converged"])
        scene = ffcube.load_scene(CUBE, max_patch_edge=0.25, quiet=True)
        F = ffcube.form_factors(scene, quiet=True)
        eps_obj = {"x0": 0.9, "x1": 0.8, "y0": 0.5, "y1": 0.5, "z0": 0.05, "z1": 0.9}
        t_obj = {"x0": 400.0, "x1": 300.0, "z1": 350.0}
        names = scene.objects
        eps = np.array([eps_obj[names[o]] for o in scene.patch_object])
        T = np.array([t_obj.get(names[o], np.nan) for o in scene.patch_object])
        Q = np.where(np.isnan(T), 0.0, np.nan)
        q, t, J = dense_radiation(F, scene.areas, eps, T, Q)
        # GMRES stops at a relative residual 1e-10; J's error <= cond(A) 1e-10 <= (2/eps_min) 1e-10 =
        # 4e-9 of ||J|| at eps_min = 0.05; q = eps (sigma T^4 - G) carries that of J_max: 4e-9 J_max.
        jmax = np.abs(J).max()
        np.testing.assert_allclose(res["heat_flux"], q, rtol=0, atol=4e-9 * jmax)
        np.testing.assert_allclose(res["radiosity"], J, rtol=0, atol=4e-9 * jmax)
        # T from sigma T^4 = G + q/eps: dT/T = (1/4) dG/(sigma T^4), G's error 4e-9 J_max, / eps_min.
        np.testing.assert_allclose(res["temperature"], t, rtol=4e-9 / 0.05, atol=0)
        # The command line's Q.csv (10 significant digits) for the same inputs.
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "q.csv")
            r = run_cli("radiate", CUBE, "--max-patch-edge", "0.25", "--surfaces", self.SURFACES, "-o", out, "-q")
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(out) as f:
                rows = [line.split(",") for line in f.read().splitlines()[1:]]
        for k, row in enumerate(rows):
            self.assertEqual(row[0], res["objects"][k])
            self.assertAlmostEqual(float(row[5]), res["object_power"][k], delta=1e-9 * max(1.0, abs(float(row[5]))))
        # A dict of surfaces is the CSV.
        surf = {name: {"emissivity": eps_obj[name], "temperature": t_obj[name]} if name in t_obj
                else {"emissivity": eps_obj[name], "heat_flux": 0.0} for name in names}
        res2, _ = ffcube.radiate(scene, surfaces=surf, quiet=True)
        np.testing.assert_array_equal(res2["heat_flux"], res["heat_flux"])

    def test_radiation_solves_again_without_rebuilding(self):
        scene = ffcube.load_scene(CUBE, max_patch_edge=0.25, quiet=True)
        F = ffcube.form_factors(scene, quiet=True)
        eps = {"x0": 0.9, "x1": 0.8, "y0": 0.5, "y1": 0.5, "z0": 0.02, "z1": 0.9}
        rad = ffcube.Radiation(F, scene, eps)
        self.assertEqual(rad.objects, scene.objects)
        e = np.array([eps[scene.objects[o]] for o in scene.patch_object])
        rng = np.random.default_rng(3)
        for step in range(5):
            # Per patch: random temperatures, and the z0 wall adiabatic (NaN: not given).
            T = rng.uniform(250.0, 900.0, len(scene))
            z0 = scene.patch_object == scene.objects.index("z0")
            T[z0] = np.nan
            q_given = np.where(z0, 0.0, np.nan)
            res = rad.solve(temperature=T, heat_flux=q_given)
            q, t, J = dense_radiation(F, scene.areas, e, T, q_given)
            # As above, at eps_min = 0.02: 1e-8 of J_max.
            jmax = np.abs(J).max()
            np.testing.assert_allclose(res["heat_flux"], q, rtol=0, atol=1e-8 * jmax)
            np.testing.assert_allclose(res["temperature"], t, rtol=1e-8 / 0.02, atol=0)
            # Energy: closed cube with hemicube rows, balance to the rows' reciprocity (report).
            self.assertLess(res["balance_error"], 1e-3)
        # Per-object dicts and a sky temperature for an open scene are accepted the same way.
        res = rad.solve(temperature={"x0": 400.0, "x1": 300.0, "y0": 350.0, "y1": 350.0, "z1": 350.0},
                        heat_flux={"z0": 0.0})
        self.assertEqual(res["heat_flux"].shape, (len(scene),))
        with self.assertRaises(ValueError) as err:
            rad.solve(temperature={"x0": 400.0}, heat_flux={"x0": 10.0})
        self.assertIn("both a temperature and a heat flux", str(err.exception))
        with self.assertRaises(ValueError) as err:
            rad.solve(temperature={"lid": 400.0})
        self.assertIn("no object 'lid'", str(err.exception))
        with self.assertRaises(ValueError):
            ffcube.Radiation(F, scene, 1.5)

    def test_command_line_mesh_is_coloured_by_heat_flux(self):
        # `ffcube radiate --mesh OUT.ply`: one flat colour per patch (faces in patch order, each with its
        # own vertices), white at 0, red to +qmax, blue to -qmax, fade = round(255 (1 - |q|/qmax)).
        with tempfile.TemporaryDirectory() as d:
            ply, patches = os.path.join(d, "heat.ply"), os.path.join(d, "p.csv")
            r = run_cli("radiate", CUBE, "--max-patch-edge", "0.5", "--surfaces", self.SURFACES, "--mesh", ply,
                        "--patch-out", patches, "-q")
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(patches) as f:
                q = np.array([float(line.split(",")[4]) for line in f.read().splitlines()[1:]])
            with open(ply, "rb") as f:
                data = f.read()
        head, body = data.split(b"end_header\n", 1)
        nv = int(head.split(b"element vertex ")[1].split(b"\n")[0])
        self.assertIn(b"red +", head)
        vertex = np.frombuffer(body[:nv * 15], dtype=[("p", "<f4", 3), ("c", "u1", 3)])
        qmax = np.abs(q).max()
        # Faces: a uchar count then uint32 indices; flat shading gives each patch its own vertices.
        faces, at = [], nv * 15
        while at < len(body):
            k = body[at]
            faces.append(np.frombuffer(body[at + 1:at + 1 + 4 * k], dtype="<u4"))
            at += 1 + 4 * k
        self.assertEqual(len(faces), len(q))
        for i, face in enumerate(faces):
            t = q[i] / qmax
            fade = round(255 * (1 - abs(t)))
            want = [255, fade, fade] if t >= 0 else [fade, fade, 255]
            for v in face:
                # The CSV's 10 digits can move the fade by one step at a .5 boundary.
                np.testing.assert_allclose(vertex["c"][v], want, atol=1)

    def test_conductances_match_a_dense_gebhart_solve(self):
        scene = ffcube.load_scene(CUBE, max_patch_edge=0.5, quiet=True)
        F = ffcube.form_factors(scene, quiet=True)
        eps = np.where(scene.patch_object % 2 == 0, 0.3, 0.8)
        GR, sky = ffcube.Radiation(F, scene, eps).conductances()
        # Gebhart: B = F diag(eps) + F diag(1 - eps) B, so B = (I - F diag(1 - eps))^-1 F diag(eps);
        # GR_kl = sum_{i in k} eps_i A_i sum_{j in l} B_ij.
        Fd = np.asarray(F.todense(), dtype=np.float64)
        n = len(scene)
        B = np.linalg.solve(np.eye(n) - Fd * (1 - eps)[None, :], Fd * eps[None, :])
        K = len(scene.objects)
        M = np.zeros((K, n))
        M[scene.patch_object, np.arange(n)] = 1.0
        ref = M @ ((eps * scene.areas)[:, None] * B) @ M.T
        # One GMRES solve per object to 1e-10, cond <= 2/0.3: 1e-9 of the largest GR.
        np.testing.assert_allclose(GR, ref, rtol=0, atol=1e-9 * ref.max())


if __name__ == "__main__":
    unittest.main()
