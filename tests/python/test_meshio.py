"""ffcube.load_scene(meshio.Mesh) (docs/fe-meshes.md, "From Python and meshio"), run by CTest
(tests/CMakeLists.txt) with PYTHONPATH=<build>/python, FFCUBE_BINARY, FFCUBE_GMSH_MODELS (the
program that writes the test models through Gmsh's API, tools/gmsh_models.cpp) and
FFCUBE_SOURCE_DIR set. References: Howell's closed forms, exact areas and normals, and the
command line's patch table for the same file (a different reader: Gmsh's own, not meshio's)."""

import csv
import math
import os
import subprocess
import tempfile
import unittest

import meshio
import numpy as np

import ffcube

BINARY = os.environ["FFCUBE_BINARY"]
BOX = (2.0, 1.0, 1.5)  # the box of gmsh_models
WALLS = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]
RAYS = 32768  # as GmshCli's check_box: well under a second on the box's 96 patches

_models = None


def models():
    """The directory of Gmsh-written models, made once per process."""
    global _models
    if _models is None:
        _models = tempfile.TemporaryDirectory()
        subprocess.run([os.environ["FFCUBE_GMSH_MODELS"], _models.name], check=True, capture_output=True)
    return _models.name


def ff_parallel(a, b, c):
    """Howell C-11: opposed parallel rectangles a x b, distance c."""
    x, y = a / c, b / c
    p, q = math.sqrt(1 + x * x), math.sqrt(1 + y * y)
    return 2 / (math.pi * x * y) * (math.log(p * q / math.sqrt(1 + x * x + y * y)) + x * q * math.atan(x / q)
                                    + y * p * math.atan(y / p) - x * math.atan(x) - y * math.atan(y))


def ff_perpendicular(l, w, h):
    """Howell C-14: rectangles at 90 degrees sharing an edge of length l; the first w wide, the second h high."""
    W, H = w / l, h / l
    s = W * W + H * H
    log = (math.log((1 + W * W) * (1 + H * H) / (1 + s))
           + W * W * math.log(W * W * (1 + s) / ((1 + W * W) * s))
           + H * H * math.log(H * H * (1 + s) / ((1 + H * H) * s)))
    return (W * math.atan(1 / W) + H * math.atan(1 / H) - math.sqrt(s) * math.atan(1 / math.sqrt(s)) + log / 4) / (math.pi * W)


def box_factor(a, b):
    """The exact factor from wall a to wall b of the box (names as WALLS)."""
    ia, ib = "xyz".index(a[0]), "xyz".index(b[0])
    if ia == ib:
        return ff_parallel(BOX[(ia + 1) % 3], BOX[(ia + 2) % 3], BOX[ia])
    return ff_perpendicular(BOX[3 - ia - ib], BOX[ib], BOX[ia])


def patch_table(path, *options):
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "t.csv")
        r = subprocess.run([BINARY, "formfactors", path, "--no-subdivide", "--method", "raycast", "-q", "--patch-table", out,
                            *options], capture_output=True, text=True)
        if r.returncode != 0:
            raise AssertionError(r.stderr)
        with open(out) as f:
            return list(csv.DictReader(f))


def patches_of(scene):
    """(object, centroid, normal, area, element id) per patch, sorted, rounded as the patch table prints (9 digits)."""
    rows = []
    for o, c, n, a, e in zip(scene.patch_object, scene.centroids, scene.normals, scene.areas, scene.element_ids):
        rows.append((scene.objects[o], *(float(f"{v:.9g}") for v in (*c, *n, a)), int(e)))
    return sorted(rows)


class Meshio(unittest.TestCase):
    def test_box_gives_howells_closed_forms(self):
        mesh = meshio.read(os.path.join(models(), "box_41.msh"))
        s = ffcube.load_scene(mesh, no_subdivide=True, flip=WALLS, quiet=True)
        self.assertEqual(sorted(s.objects), sorted(WALLS))
        F = ffcube.form_factors(s, method="raycast", rays=RAYS, quiet=True)
        A = s.areas
        for i, a in enumerate(s.objects):
            ia = s.patch_object == i
            # Exact areas and inward normals (the walls flipped into the box); 1e-12: a sum of
            # about 20 triangle areas of size 0.1 in double precision.
            axis = "xyz".index(a[0])
            self.assertAlmostEqual(A[ia].sum(), BOX[(axis + 1) % 3] * BOX[(axis + 2) % 3], delta=1e-12)
            inward = 1.0 if a.endswith("min") else -1.0
            np.testing.assert_allclose(s.normals[ia][:, axis], inward, atol=1e-12)
            # 5 standard errors of an area-weighted mean of ray-cast rows (each a mean of RAYS
            # Bernoulli draws, variance <= 1/(4 RAYS)): sqrt(max w_i / (4 RAYS)), plus float storage 1e-6.
            tol = 5 * math.sqrt(A[ia].max() / A[ia].sum() / (4 * RAYS)) + 1e-6
            for j, b in enumerate(s.objects):
                if a == b:
                    continue
                ib = s.patch_object == j
                f = float(A[ia] @ np.asarray(F[ia][:, ib].sum(axis=1)).ravel() / A[ia].sum())
                self.assertAlmostEqual(f, box_factor(a, b), delta=tol, msg=f"{a} -> {b}")

    def test_same_patches_as_the_command_line(self):
        # Gmsh's reader on the file (the command line) and meshio's reader then ffcube's cells
        # path give the same patches: objects, centroids, normals, areas, and element ids up to a
        # constant: meshio drops Gmsh's element tags, which here are consecutive in the order
        # meshio lists the cells (from 1, or after the unsaved surface elements in *_solid.msh).
        for name in ("box_41.msh", "cylinder_o2.msh", "cavity.msh", "box_hex_o2.msh", "box_prism_o2.msh", "box_pyramid_o2.msh",
                     "box_hex_o2i.msh", "box_pyramid_solid.msh"):
            path = os.path.join(models(), name)
            cli = sorted((r["object"], *(float(r[k]) for k in ("cx", "cy", "cz", "nx", "ny", "nz", "area")), int(r["element_id"]))
                         for r in patch_table(path))
            py = patches_of(ffcube.load_scene(meshio.read(path), no_subdivide=True, quiet=True))
            self.assertEqual(len(py), len(cli), name)
            for p, c in zip(py, cli):
                self.assertEqual(p[0], c[0], name)
                # Both printed to 9 significant digits: they differ by at most one unit in the
                # 9th digit of the larger (coordinates up to 3: 3e-8 absolute, and 1e-8 near 0).
                np.testing.assert_allclose(p[1:8], c[1:8], rtol=1e-8, atol=3e-8, err_msg=name)
            self.assertEqual(len({c[8] - p[8] for p, c in zip(py, cli)}), 1, name)

    def test_volume_and_quadratic_cells(self):
        # The tetrahedral cube [0,3]^3 less [1,2]^3: only its boundary radiates (outer 54, cavity
        # 6, exact), facing out of the material: away from the centre outside, towards it inside.
        s = ffcube.load_scene(meshio.read(os.path.join(models(), "cavity.msh")), no_subdivide=True, quiet=True)
        self.assertEqual(sorted(s.objects), ["cavity", "outer"])
        for i, name in enumerate(s.objects):
            mine = s.patch_object == i
            self.assertAlmostEqual(s.areas[mine].sum(), 54.0 if name == "outer" else 6.0, delta=1e-12)
            d = np.einsum("ij,ij->i", s.centroids[mine] - 1.5, s.normals[mine])
            self.assertTrue(np.all(d > 0) if name == "outer" else np.all(d < 0), name)
        # Quadratic triangles: 4 patches each, and the curved cylinder's area (6 pi) is closer
        # than the linear mesh of the same corner nodes gets.
        o1 = ffcube.load_scene(meshio.read(os.path.join(models(), "cylinder_o1.msh")), no_subdivide=True, quiet=True)
        o2 = ffcube.load_scene(meshio.read(os.path.join(models(), "cylinder_o2.msh")), no_subdivide=True, quiet=True)
        self.assertEqual(len(o2), 4 * len(o1))
        self.assertLess(abs(o2.areas.sum() - 6 * math.pi), abs(o1.areas.sum() - 6 * math.pi))

    def test_vtu_with_an_integer_cell_array(self):
        # The box written as .vtu and legacy .vtk by meshio, its walls numbered 1..6 in the cell
        # array "wall" (no names): objects_by="field:wall" makes them objects wall_1 .. wall_6.
        box = meshio.read(os.path.join(models(), "box_41.msh"))
        wall = [np.full(len(c.data), k + 1, dtype=np.int32) for k, c in enumerate(box.cells)]
        with tempfile.TemporaryDirectory() as d:
            for ext in ("vtu", "vtk"):
                path = os.path.join(d, "box." + ext)
                meshio.write(path, meshio.Mesh(box.points, box.cells, cell_data={"wall": wall}))
                s = ffcube.load_scene(meshio.read(path), objects_by="field:wall", no_subdivide=True, quiet=True)
                self.assertEqual(sorted(s.objects), [f"wall_{k}" for k in range(1, 7)], ext)
                for k, name in enumerate(WALLS):  # box_41.msh's blocks are the walls in WALLS order
                    axis = "xyz".index(name[0])
                    self.assertAlmostEqual(s.areas[s.patch_object == s.objects.index(f"wall_{k + 1}")].sum(),
                                           BOX[(axis + 1) % 3] * BOX[(axis + 2) % 3], delta=1e-12, msg=ext)
                if ext == "vtk":
                    # The file itself (ffcube's legacy VTK reader): the same elements, objects and areas.
                    f = ffcube.load_scene(path, objects_by="field:wall", no_subdivide=True, quiet=True)
                    self.assertEqual(sorted(f.objects), sorted(s.objects))
                    def by_id(x):
                        return {int(e): (x.objects[o], a) for e, o, a in zip(x.element_ids, x.patch_object, x.areas)}
                    self.assertEqual(by_id(f), by_id(s))

    def test_results_go_back_onto_the_cells(self):
        mesh = meshio.read(os.path.join(models(), "box_41.msh"))
        # One patch per cell: a cell's value is its patch's; element ids are 1 + the cell's index.
        s = ffcube.load_scene(mesh, no_subdivide=True, quiet=True)
        back = s.cell_data(s.element_ids.astype(float))
        self.assertEqual([len(b) for b in back], [len(c.data) for c in mesh.cells])
        np.testing.assert_array_equal(np.concatenate(back), np.arange(1, len(s) + 1))
        # Subdivided: the area-weighted mean of a cell's patch centroids is the cell's centroid
        # (the patches tile the triangle), exact up to rounding (1e-12 on coordinates up to 2).
        fine = ffcube.load_scene(mesh, max_patch_edge=0.2, quiet=True)
        self.assertGreater(len(fine), 2 * len(s))
        centroids = fine.cell_data(fine.centroids)
        for block, c in zip(mesh.cells, centroids):
            np.testing.assert_allclose(c, mesh.points[block.data].mean(axis=1), atol=1e-12)
        # Written onto the mesh and read back from a .vtu (as ParaView would).
        mesh.cell_data["cx"] = [c[:, 0] for c in centroids]
        mesh.cell_sets = {}  # a .vtu has none (meshio would convert them, with a note)
        with tempfile.TemporaryDirectory() as d:
            meshio.write(os.path.join(d, "out.vtu"), mesh)
            again = meshio.read(os.path.join(d, "out.vtu"))
            np.testing.assert_array_equal(np.concatenate(again.cell_data["cx"]), np.concatenate(mesh.cell_data["cx"]))
        # Lines are skipped and get NaN; the volume's interior cells too.
        cavity = meshio.read(os.path.join(models(), "cavity.msh"))
        cs = ffcube.load_scene(cavity, no_subdivide=True, quiet=True)
        tets = cs.cell_data(np.ones(len(cs)))[-1]
        self.assertEqual(cavity.cells[-1].type, "tetra")
        self.assertTrue(np.isnan(tets).any() and (tets[~np.isnan(tets)] == 1).all())
        with self.assertRaisesRegex(ValueError, "not loaded from a meshio.Mesh"):
            ffcube.load_scene(os.path.join(models(), "box_41.msh"), quiet=True).cell_data(np.ones(1))

    def test_bad_meshes_name_the_block_and_the_rule(self):
        pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
        tri = np.array([[0, 1, 2], [0, 2, 3]])

        # Planar points (n x 2) lie at z = 0; with no groups the block is one object. The two
        # triangles tile the unit square: areas 0.5 each, exact in binary.
        flat = ffcube.load_scene(meshio.Mesh(pts[:, :2], [("triangle", tri)]), no_subdivide=True, quiet=True)
        self.assertEqual((len(flat), flat.objects), (2, ["surface_1"]))
        self.assertEqual(list(flat.areas), [0.5, 0.5])
        np.testing.assert_array_equal(flat.normals[:, 2], 1.0)

        def refused(mesh, *words, **options):
            with self.assertRaises(ffcube.InputError) as e:
                ffcube.load_scene(mesh, quiet=True, **options)
            for w in words:
                self.assertIn(w, str(e.exception))

        refused(meshio.Mesh(pts, [("triangle", tri), ("triangle10", np.zeros((1, 10), dtype=int))]), "cells[1] ('triangle10')",
                "does not read this cell type")
        refused(meshio.Mesh(pts, [("triangle", tri), ("quad", np.array([[0, 1, 2, 9]]))]), "cells[1] ('quad')", "cell 0",
                "point 9", "4 points")
        bad = pts.copy()
        bad[2, 1] = np.nan
        refused(meshio.Mesh(bad, [("triangle", tri)]), "points[2]", "not finite")
        refused(meshio.Mesh(pts, [("triangle", tri)], cell_sets={"a": [np.array([0, 1])], "b": [np.array([1])]}),
                "cells[0] ('triangle'): cell 1 is in two cell sets ('a' and 'b')")
        refused(meshio.Mesh(pts, [("triangle", tri)], cell_sets={"a": [np.array([5])]}), "cell_sets['a'][0]", "cell 5")
        refused(meshio.Mesh(pts, [("triangle", tri)]), "no cell data 'mat'", objects_by="field:mat")
        refused(meshio.Mesh(pts, [("triangle", tri)], cell_data={"mat": [np.array([0.5, 1.5])]}), "cell_data['mat'][0]",
                "one integer per cell", objects_by="field:mat")
        refused(meshio.Mesh(pts, [("triangle", tri)]), "--flip zz: no object of that name", flip="zz")
        refused(meshio.Mesh(pts, [("line", np.array([[0, 1]]))]), "no surface or volume elements")
        with self.assertRaises(ffcube.InputError):
            ffcube.load_scene(os.path.join(models(), "box_41.msh"), objects_by="field:mat", quiet=True)
        with self.assertRaisesRegex(TypeError, r"load_scene\(mesh\) first"):
            ffcube.form_factors(meshio.Mesh(pts, [("triangle", tri)]))


if __name__ == "__main__":
    unittest.main()
