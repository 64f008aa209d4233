// FE and CAD meshes through Gmsh (issue 39), through the real binary, on models that Gmsh itself
// writes at run time (tools/gmsh_models.cpp): a closed box with six named walls in every format
// gives Howell's closed forms (C-11, C-14), a tetrahedral box with a cavity radiates from its
// boundary only, quadratic triangles of a cylinder come closer to the curved value than the
// linear ones, and malformed files end with exit 2, a message naming the file, and no output.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "fe/fe_util.hpp"
#include "ffcube/reference/closed_forms.hpp"

namespace ffcube {
namespace {

using test::read_text;
using test::run_ffcube;
using test::TempDir;

constexpr double kBox[3] = {2.0, 1.0, 1.5};  // the box of gmsh_models
// The patch table prints 9 significant digits: each area is rounded by at most 5e-9 of itself, so
// a sum of areas by at most 5e-9 of the sum (1e-8 leaves room for the last digit of the nodes).
constexpr double kAreaPrinted = 1e-8;
constexpr int kRays = 32768;  // well under 1 s per run on the models' 100 to 200 patches

using test::csv;
using test::models;

struct ObjectShape {
    double area = 0.0, largest_patch = 0.0;
    double c[3] = {0, 0, 0}, n[3] = {0, 0, 0};  // area-weighted centroid and normal
};

std::map<std::string, ObjectShape> shapes(const std::string& patch_table) {
    std::map<std::string, ObjectShape> out;
    for (const auto& r : csv(patch_table)) {
        ObjectShape& s = out[r.at(1)];
        const double a = std::stod(r.at(2));
        s.area += a;
        s.largest_patch = std::max(s.largest_patch, a);
        for (int k = 0; k < 3; ++k) s.c[k] += a * std::stod(r.at(3 + k)), s.n[k] += a * std::stod(r.at(6 + k));
    }
    for (auto& [name, s] : out)
        for (int k = 0; k < 3; ++k) s.c[k] /= s.area, s.n[k] /= s.area;
    return out;
}

// The axis a wall of the box is perpendicular to.
int axis_of(const ObjectShape& s) {
    int a = 0;
    for (int k = 1; k < 3; ++k)
        if (std::abs(s.n[k]) > std::abs(s.n[a])) a = k;
    return a;
}

// Reads the box in `file` (with the reading `options`) with its walls flipped to face into the box
// and checks every object-to-object factor against Howell's closed forms.
void check_box(const std::string& file, const std::string& options = "") {
    const TempDir& m = models();
    TempDir out;
    // A first run learns the object names (they differ by format: groups, pid_N, surface_N).
    auto r = run_ffcube("formfactors " + (m / file) + options + " --no-subdivide --method raycast -q --patch-table " + (out / "t0.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    std::string names;
    for (const auto& [name, s] : shapes(read_text(out / "t0.csv"))) names += (names.empty() ? "" : ",") + name;
    r = run_ffcube("formfactors " + (m / file) + options + " --no-subdivide --method raycast -q --rays " + std::to_string(kRays) +
                   " --flip " + names + " --patch-table " + (out / "t.csv") + " --groups " + (out / "g.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto walls = shapes(read_text(out / "t.csv"));
    ASSERT_EQ(walls.size(), 6u) << names;
    std::map<std::pair<std::string, std::string>, double> f;
    for (const auto& row : csv(read_text(out / "g.csv"))) f[{row.at(0), row.at(1)}] = std::stod(row.at(2));
    double worst = 0.0;
    for (const auto& [from, a] : walls) {
        const int ia = axis_of(a);
        EXPECT_NEAR(std::abs(a.n[ia]), 1.0, 1e-9) << file << " " << from;
        EXPECT_NEAR(a.area, kBox[(ia + 1) % 3] * kBox[(ia + 2) % 3], kAreaPrinted * a.area) << file << " " << from;
        // Standard error of a ray-cast object factor: each patch's row is a mean of kRays
        // Bernoulli draws (variance F(1-F)/kRays <= 1/(4 kRays)), and the object's factor an
        // area-weighted mean of its patches' rows (weights w_i, sum 1), so its variance is at most
        // sum w_i^2 / (4 kRays) <= max w_i / (4 kRays). 5 standard errors, plus the float storage
        // of the factors (1e-6).
        const double tol = 5.0 * std::sqrt(a.largest_patch / a.area / (4.0 * kRays)) + 1e-6;
        for (const auto& [to, b] : walls) {
            if (from == to) continue;
            const int ib = axis_of(b);
            double exact;
            if (ia == ib) {
                exact = ff_parallel_rectangles(kBox[(ia + 1) % 3], kBox[(ia + 2) % 3], kBox[ia]);  // C-11
            } else {
                const int edge = 3 - ia - ib;  // the common edge's axis
                exact = ff_perpendicular_rectangles_common_edge(kBox[edge], kBox[ib], kBox[ia]);  // C-14
            }
            const double got = f.count({from, to}) ? f[{from, to}] : 0.0;
            EXPECT_NEAR(got, exact, tol) << file << ": " << from << " -> " << to;
            worst = std::max(worst, std::abs(got - exact));
        }
    }
    std::printf("%s: max |F - closed form| over 30 wall pairs = %.2e\n", file.c_str(), worst);
}

TEST(GmshCli, BoxMsh41Ascii) { check_box("box_41.msh"); }
TEST(GmshCli, BoxMsh41Binary) { check_box("box_41b.msh"); }
TEST(GmshCli, BoxMsh22Ascii) { check_box("box_22.msh"); }
TEST(GmshCli, BoxMsh22Binary) { check_box("box_22b.msh"); }
TEST(GmshCli, BoxUnv) { check_box("box.unv"); }
TEST(GmshCli, BoxNastran) { check_box("box.bdf"); }
TEST(GmshCli, BoxStepMeshedByGmsh) { check_box("box.step"); }
// IGES B-spline walls (written by gmsh_models itself: Gmsh 4.8 writes no IGES), read by OpenCASCADE and meshed by Gmsh.
TEST(GmshCli, BoxIgesMeshedByGmsh) { check_box("box.igs"); }

TEST(GmshCli, GroupNamesAndIdsOfFormats) {
    const TempDir& m = models();
    TempDir out;
    for (const auto& [file, first] : std::vector<std::pair<std::string, std::string>>{
             {"box_41.msh", "xmin"}, {"box.unv", "xmin"}, {"box.bdf", "pid_1"}, {"box.step", "surface_1"}, {"box.vtk", "surface_1"}}) {
        const auto r = run_ffcube("formfactors " + (m / file) + " --no-subdivide --method raycast -q --patch-table " + (out / "t.csv"));
        ASSERT_EQ(r.code, 0) << r.output;
        EXPECT_EQ(shapes(read_text(out / "t.csv")).count(first), 1u) << file;
    }
    // --objects-by element: one object per element.
    const auto r = run_ffcube("formfactors " + (m / "box_41.msh") + " --no-subdivide --method raycast -q --objects-by element "
                              "--patch-table " + (out / "t.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto by_element = shapes(read_text(out / "t.csv"));
    EXPECT_EQ(by_element.size(), csv(read_text(out / "t.csv")).size());
    // The box's surface area: 2 (2x1 + 2x1.5 + 1x1.5).
    double area = 0.0;
    for (const auto& [n, s] : by_element) area += s.area;
    EXPECT_NEAR(area, 2 * (2 + 3 + 1.5), kAreaPrinted * area);
}

// The cube [0,3]^3 less [1,2]^3 in tetrahedra: only the outer walls (area 54, facing out, so
// seeing nothing) and the cavity's walls (area 6, facing into the cavity, which they close)
// radiate; the internal faces of the tetrahedra (thousands) do not.
TEST(GmshCli, TetrahedralBoxWithCavityRadiatesFromItsBoundary) {
    const TempDir& m = models();
    TempDir out;
    const auto r = run_ffcube("formfactors " + (m / "cavity.msh") + " --no-subdivide --method raycast -q --patch-table " +
                              (out / "t.csv") + " --groups " + (out / "g.csv") + " --sky " + (out / "sky.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto objects = shapes(read_text(out / "t.csv"));
    ASSERT_EQ(objects.size(), 2u);
    EXPECT_NEAR(objects.at("outer").area, 54.0, kAreaPrinted * 54.0);
    EXPECT_NEAR(objects.at("cavity").area, 6.0, kAreaPrinted * 6.0);
    // Facing out of the material: the outer walls' normals point away from the centre (1.5,1.5,1.5),
    // the cavity's towards it.
    for (const auto& row : csv(read_text(out / "t.csv"))) {
        double d = 0.0;
        for (int k = 0; k < 3; ++k) d += (std::stod(row.at(3 + k)) - 1.5) * std::stod(row.at(6 + k));
        EXPECT_EQ(d > 0, row.at(1) == "outer") << "patch " << row.at(0);
    }
    // The cavity is closed: its rows sum to 1 (rays cannot escape a closed box; float storage 1e-6);
    // the outer walls see nothing of the convex solid: their rows are 0 exactly.
    for (const auto& row : csv(read_text(out / "sky.csv"))) {
        const double sky = std::stod(row.at(3));  // patch,object,area,sky_view_factor,element_id
        if (row.at(1) == "cavity")
            EXPECT_NEAR(sky, 0.0, 1e-6) << "patch " << row.at(0);
        else
            EXPECT_EQ(sky, 1.0) << "patch " << row.at(0);
    }
    const auto g = csv(read_text(out / "g.csv"));
    ASSERT_EQ(g.size(), 1u);
    EXPECT_EQ(g[0].at(0), "cavity");
    EXPECT_NEAR(std::stod(g[0].at(2)), 1.0, 1e-6);
}

// The closed cylinder (radius 1, height 2) faced inwards: F(side -> side) = 1 - 2 F(side -> top),
// F(side -> top) = (A_top / A_side) (1 - F(top -> bottom)) = (1 - C-41(1, 1, 2)) / 4. The linear
// mesh is a prism inside the cylinder; its 6-node version puts the mid-side nodes on the cylinder,
// split into 4 triangles each, which halves the chords' sagitta: closer to the curved value.
TEST(GmshCli, QuadraticCylinderComesCloserToTheCurvedValue) {
    const TempDir& m = models();
    TempDir out;
    const double exact = 1.0 - 2.0 * (1.0 - ff_coaxial_disks(1.0, 1.0, 2.0)) / 4.0;
    double err[2], noise[2];
    std::size_t patches[2];
    for (int order = 1; order <= 2; ++order) {
        const std::string file = m / ("cylinder_o" + std::to_string(order) + ".msh");
        const auto r = run_ffcube("formfactors " + file + " --no-subdivide --method raycast -q --rays " + std::to_string(kRays) +
                                  " --flip side,top,bottom --patch-table " + (out / "t.csv") + " --groups " + (out / "g.csv"));
        ASSERT_EQ(r.code, 0) << r.output;
        double f = 0.0;
        for (const auto& row : csv(read_text(out / "g.csv")))
            if (row.at(0) == "side" && row.at(1) == "side") f = std::stod(row.at(2));
        err[order - 1] = std::abs(f - exact);
        patches[order - 1] = csv(read_text(out / "t.csv")).size();
        const ObjectShape side = shapes(read_text(out / "t.csv")).at("side");
        noise[order - 1] = 5.0 * std::sqrt(side.largest_patch / side.area / (4.0 * kRays));  // as in check_box
    }
    std::printf("cylinder F(side->side): exact %.6f, |error| linear %.2e (%zu patches), quadratic %.2e (%zu patches)\n", exact,
                err[0], patches[0], err[1], patches[1]);
    EXPECT_EQ(patches[1], 4 * patches[0]);  // each 6-node triangle in 4
    // Each estimate is within its 5-standard-error bound of the mesh's own value (see check_box),
    // so the linear mesh's error exceeds the quadratic one's by more than both bounds together
    // only when its geometry is truly farther from the cylinder.
    std::printf("noise bounds: linear %.2e, quadratic %.2e\n", noise[0], noise[1]);
    EXPECT_LT(err[1] + noise[0] + noise[1], err[0]);
}

// The box in hexahedra, prisms, and tetrahedra with pyramids (tools/gmsh_models.cpp): the walls'
// surface elements lie on the volume's boundary faces, which give the patches; Howell's closed
// forms as for the surface meshes (an internal face would add a seventh object or area).
TEST(GmshCli, HexPrismPyramidBoxesGiveTheClosedForms) {
    for (const char* kind : {"hex", "prism", "pyramid"}) check_box(std::string("box_") + kind + ".msh");
}

// Patches of a patch table as rows; the patch count of a file read with --no-subdivide.
std::vector<std::vector<std::string>> patch_rows(const std::string& file, const std::string& options, const TempDir& out) {
    const auto r = run_ffcube("formfactors " + file + " --no-subdivide --method raycast -q --rays 256 " + options +
                              " --patch-table " + (out / "t.csv") + " --groups " + (out / "g.csv"));
    EXPECT_EQ(r.code, 0) << r.output;
    return csv(read_text(out / "t.csv"));
}

// Every patch lies on a wall of the box: its normal is a unit axis (printed to 9 digits: 1e-8),
// pointing out of the box (away from the centre (1, 0.5, 0.75)) or into it (`inward`); the walls'
// areas are exact. Returns the patch count.
std::size_t expect_box_walls(const std::vector<std::vector<std::string>>& rows, bool inward, const std::string& what) {
    double area[3] = {0, 0, 0};
    for (const auto& row : rows) {
        int axis = 0;
        double n[3], d = 0.0;
        for (int k = 0; k < 3; ++k) {
            n[k] = std::stod(row.at(6 + k));
            if (std::abs(n[k]) > std::abs(n[axis])) axis = k;
            d += (std::stod(row.at(3 + k)) - kBox[k] / 2) * n[k];
        }
        EXPECT_NEAR(std::abs(n[axis]), 1.0, 1e-8) << what << " patch " << row.at(0);
        EXPECT_EQ(d < 0, inward) << what << " patch " << row.at(0);
        area[axis] += std::stod(row.at(2));
    }
    for (int a = 0; a < 3; ++a) {
        const double exact = 2.0 * kBox[(a + 1) % 3] * kBox[(a + 2) % 3];
        EXPECT_NEAR(area[a], exact, kAreaPrinted * exact) << what << " axis " << a;
    }
    return rows.size();
}

// meshio (Debian's python3-meshio, an independent writer) writes the box of box_41.msh and the
// box in prisms as legacy VTK, in its default version 5.1 and in 4.2, binary and ASCII, with
// each cell's physical group as the integer cell array "wall". --objects-by field:wall names the
// walls wall_<tag>, which give Howell's closed forms; the prisms radiate from the box's walls only
// (unit axis normals facing out of the material, the walls' exact areas: an internal face would
// add area). Each triangle's element
// id is 1 + its index among the file's cells, at the centroid meshio's arrays give that cell.
TEST(GmshCli, VtkCellArrayNamesTheObjects) {
    const TempDir& m = models();
    TempDir out;
    test::write_file(out / "w.py",
                     "import meshio,sys,numpy as np\nd=sys.argv[1]\n"
                     "for src in ['box_41','box_prism']:\n"
                     "  m=meshio.read(d+'/'+src+'.msh')\n"
                     "  cells=[(c.type,c.data) for c in m.cells]\n"
                     "  wall=[p.astype(np.int32) for p in m.cell_data['gmsh:physical']]\n"
                     "  v=meshio.Mesh(m.points,cells,cell_data={'wall':wall})\n"
                     "  meshio.vtk.write(d+'/'+src+'_51.vtk',v,fmt_version='5.1',binary=True)\n"
                     "  meshio.vtk.write(d+'/'+src+'_51a.vtk',v,fmt_version='5.1',binary=False)\n"
                     "  meshio.vtk.write(d+'/'+src+'_42.vtk',v,fmt_version='4.2',binary=True)\n"
                     "  meshio.vtk.write(d+'/'+src+'_42a.vtk',v,fmt_version='4.2',binary=False)\n"
                     "  if src=='box_41':\n"
                     "    k=0\n"
                     "    for t,c in cells:\n"
                     "      for e in c:\n"
                     "        k+=1\n"
                     "        if t=='triangle': print(k,*(repr(float(x)) for x in m.points[e].mean(axis=0)))\n");
    ASSERT_EQ(std::system(("/usr/bin/python3 " + (out / "w.py") + " " + m.path().string() + " > " + (out / "c.txt") + " 2>/dev/null").c_str()), 0);
    check_box("box_41_51.vtk", " --objects-by field:wall");
    // The other versions and encodings give the same patches, ids and names.
    const auto patches = patch_rows(m / "box_41_51.vtk", "--objects-by field:wall", out);
    for (const char* v : {"box_41_51a.vtk", "box_41_42.vtk", "box_41_42a.vtk"}) EXPECT_EQ(patch_rows(m / v, "--objects-by field:wall", out), patches) << v;
    const auto prisms = patch_rows(m / "box_prism_42.vtk", "--objects-by field:wall", out);
    EXPECT_GT(expect_box_walls(prisms, false, "box_prism_42.vtk"), 20u);
    for (const auto& row : prisms) EXPECT_EQ(row.at(1).rfind("wall_", 0), 0u) << row.at(1);
    for (const char* v : {"box_prism_51.vtk"})
        EXPECT_EQ(patch_rows(m / v, "--objects-by field:wall", out), prisms) << v;
    std::map<long, std::array<double, 3>> centroid;
    std::istringstream c(read_text(out / "c.txt"));
    for (long id; c >> id;) c >> centroid[id][0] >> centroid[id][1] >> centroid[id][2];
    ASSERT_EQ(centroid.size(), patches.size());
    for (const auto& row : patches) {
        EXPECT_EQ(row.at(1).rfind("wall_", 0), 0u) << row.at(1);
        const long id = std::stol(row.at(9));
        ASSERT_EQ(centroid.count(id), 1u) << "element " << id;
        // The table prints 9 significant digits of coordinates of at most 2: 5e-9 each.
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(std::stod(row.at(3 + std::size_t(a))), centroid[id][std::size_t(a)], 1e-8) << "element " << id;
        centroid.erase(id);  // each element once
    }
}

// Volume elements alone (no surface elements in the file): their boundary faces are the patches,
// facing out of the material, named by the volume's group; flipped into the box they close it,
// so the group's factor to itself is 1 (every ray hits the box; float storage 1e-6). Raised to
// order 2, each wall's pieces tile it exactly: a wrong mid-side node would overlap or flip them.
TEST(GmshCli, VolumeElementsRadiateFromTheirBoundaryAtOrders1And2) {
    const TempDir& m = models();
    TempDir out;
    for (const std::string kind : {"hex", "prism", "pyramid"}) {
        const std::size_t linear = expect_box_walls(patch_rows(m / ("box_" + kind + ".msh"), "", out), false, kind);
        const auto rows = patch_rows(m / ("box_" + kind + "_solid.msh"), "--flip solid", out);
        EXPECT_EQ(expect_box_walls(rows, true, kind + " solid"), linear);
        for (const auto& row : rows) EXPECT_EQ(row.at(1), "solid");
        const auto g = csv(read_text(out / "g.csv"));
        ASSERT_EQ(g.size(), 1u) << kind;
        EXPECT_NEAR(std::stod(g[0].at(2)), 1.0, 1e-6) << kind;
        // Complete quadratic faces split in 4 (6-node triangles, 9-node quadrangles); incomplete
        // 8-node quadrangles in 5.
        EXPECT_EQ(expect_box_walls(patch_rows(m / ("box_" + kind + "_o2.msh"), "", out), false, kind + " o2"), 4 * linear);
        EXPECT_GT(expect_box_walls(patch_rows(m / ("box_" + kind + "_o2i.msh"), "", out), false, kind + " o2i"), 4 * linear - 1);
    }
}

// A malformed file: exit 2, a message naming the file and what is wrong, no output file.
void expect_refused(const std::string& path, const std::string& words) {
    TempDir out;
    const auto r = run_ffcube("formfactors " + path + " -q --method raycast -o " + (out / "F.ffm"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(path), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(words), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out / "F.ffm"));
}

TEST(GmshCli, MalformedFilesAreRefused) {
    const TempDir& m = models();
    TempDir dir;
    const std::string ascii = read_text(m / "box_22.msh");
    const std::string binary = read_text(m / "box_41b.msh");
    const auto write = [&](const std::string& name, const std::string& text) {
        test::write_file(dir / name, text);
        return dir / name;
    };
    expect_refused(write("cut.msh", ascii.substr(0, ascii.size() / 3)), "Gmsh cannot read it");
    expect_refused(write("cutb.msh", binary.substr(0, binary.size() * 2 / 3)), "Gmsh cannot read it");
    expect_refused(write("garbage.msh", std::string("\x13\x7f garbage \x01\x02 ]]]\n", 17)), "Gmsh cannot read it");
    // The first element's type (2: triangle) replaced by an unknown one, and its last node by a missing one.
    const std::size_t elements = ascii.find("$Elements\n");
    ASSERT_NE(elements, std::string::npos);
    const std::size_t first = ascii.find('\n', ascii.find('\n', elements) + 1) + 1;  // the line after the count
    const std::size_t end = ascii.find('\n', first);
    std::istringstream words(ascii.substr(first, end - first));
    std::vector<std::string> w;
    for (std::string s; words >> s;) w.push_back(s);
    const auto line = [&](std::size_t k, const std::string& v) {
        std::string s;
        for (std::size_t i = 0; i < w.size(); ++i) s += (i ? " " : "") + (i == k ? v : w[i]);
        return ascii.substr(0, first) + s + ascii.substr(end);
    };
    expect_refused(write("type.msh", line(1, "150")), "element 1 is of type 150, which Gmsh does not know");
    expect_refused(write("node.msh", line(w.size() - 1, "99999")), "node");
    std::string twice = ascii;
    twice.replace(twice.find("\"ymin\""), 6, "\"xmin\"");
    expect_refused(write("twice.msh", twice), "the physical group name \"xmin\" is used twice");
    std::string bdf = read_text(m / "box.bdf");
    bdf.insert(bdf.find("GRID"), "CORD2R  9       0       0.      0.      0.      0.      0.      1.\n");
    expect_refused(write("card.bdf", bdf), "card 'CORD2R' is not read");
    expect_refused(write("stl.step", "solid x\nendsolid x\n"), "not a STEP file");
    expect_refused(write("bad.step", "ISO-10303-21;\nHEADER;\nnonsense\n"), "Gmsh cannot read it");
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// Element ids come back: with --no-subdivide each triangle of the .msh is one patch, and the
// patch table, the per-patch sky file and the .vtu of --fields (read back by meshio, an
// independent reader) carry its id. The .msh is parsed here (version 2.2 ASCII: "id x y z" node
// lines, "id type ntags tags... nodes" element lines) for each element's centroid.
TEST(GmshCli, ElementIdsRoundTripThroughPatchTableAndVtu) {
    const TempDir& m = models();
    TempDir out;
    const std::string msh = read_text(m / "box_22.msh");
    std::map<long, std::array<double, 3>> nodes;
    std::map<long, std::array<double, 3>> centroid;  // triangle id -> centroid
    {
        std::istringstream in(msh.substr(msh.find("$Nodes\n") + 7));
        std::size_t n = 0;
        in >> n;
        for (std::size_t i = 0; i < n; ++i) {
            long id;
            std::array<double, 3> p;
            in >> id >> p[0] >> p[1] >> p[2];
            nodes[id] = p;
        }
        std::istringstream el(msh.substr(msh.find("$Elements\n") + 10));
        el >> n;
        std::string line;
        std::getline(el, line);
        for (std::size_t i = 0; i < n && std::getline(el, line);) {
            std::istringstream ls(line);
            long id, type, ntags, v;
            ls >> id >> type >> ntags;
            for (long t = 0; t < ntags; ++t) ls >> v;
            ++i;
            if (type != 2) continue;
            std::array<double, 3> c{0, 0, 0};
            for (int k = 0; k < 3; ++k) {
                ls >> v;
                for (int a = 0; a < 3; ++a) c[a] += nodes.at(v)[a] / 3.0;
            }
            centroid[id] = c;
        }
    }
    ASSERT_GT(centroid.size(), 50u);
    const auto r = run_ffcube("formfactors " + (m / "box_22.msh") + " --no-subdivide --method raycast -q --flip " +
                              "xmin,xmax,ymin,ymax,zmin,zmax --patch-table " + (out / "t.csv") + " --sky " + (out / "s.csv") +
                              " --fields " + (out / "f.vtu"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto table = csv(read_text(out / "t.csv"));
    ASSERT_EQ(table.size(), centroid.size());
    std::map<long, double> sky;
    for (const auto& row : table) {
        ASSERT_EQ(row.size(), 11u);  // patch .. nz, element_id, error_estimate (docs/accuracy.md)
        const long id = std::stol(row.at(9));
        ASSERT_EQ(centroid.count(id), 1u) << "element " << id;
        // The table prints 9 significant digits of coordinates at most 2: 5e-9 each.
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(std::stod(row.at(3 + a)), centroid[id][a], 1e-8) << "element " << id;
        centroid.erase(id);  // each element once
    }
    for (const auto& row : csv(read_text(out / "s.csv"))) sky[std::stol(row.at(4))] = std::stod(row.at(3));
    EXPECT_EQ(sky.size(), table.size());
    // meshio reads the .vtu: element ids and sky view factors per cell.
    const std::string script = "import meshio,sys\nm=meshio.read(sys.argv[1])\nd=m.cell_data\n"
                               "for i,s in zip(d['element_id'][0],d['sky_view_factor'][0]): print(int(i),repr(float(s)))\n";
    test::write_file(out / "read.py", script);
    ASSERT_EQ(std::system(("/usr/bin/python3 " + (out / "read.py") + " " + (out / "f.vtu") + " > " + (out / "v.txt")).c_str()), 0);
    std::istringstream v(read_text(out / "v.txt"));
    std::size_t cells = 0;
    for (long id; v >> id;) {
        double s;
        v >> s;
        ++cells;
        ASSERT_EQ(sky.count(id), 1u) << "element " << id;
        EXPECT_NEAR(s, sky[id], 5e-9) << "element " << id;  // the CSV's 9 digits of a value <= 1
    }
    EXPECT_EQ(cells, table.size());
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// The mesh options name what they apply to when given for another format.
// ffcube radiate on the box, walls flipped in: the floor (zmin) at 400 K with emissivity 0.5, the
// other walls black at 300 K. The floor sees only black walls (F to itself is 0: it is flat), so
// its irradiation is sigma 300^4 times its row sum and its net flux leaving is exactly
// q = 0.5 sigma (400^4 - 300^4) whatever F is, as long as rows sum to 1 (a closed box); a black
// wall's radiosity is sigma 300^4. The per-patch file and the .vtu carry each element's id.
TEST(GmshCli, RadiateWritesHeatFluxOntoTheElements) {
    const TempDir& m = models();
    TempDir out;
    test::write_file(out / "s.csv", "object,emissivity,temperature,heat_flux\nzmin,0.5,400,\n");
    // Few rays: the floor's flux does not depend on F's accuracy, only on its rows summing to 1.
    const auto r = run_ffcube("radiate " + (m / "box_41.msh") + " --no-subdivide --method raycast --rays 1024 -q --flip " +
                              "xmin,xmax,ymin,ymax,zmin,zmax --surfaces " + (out / "s.csv") + " --default-surface 1,300 " +
                              "--patch-out " + (out / "p.csv") + " --fields " + (out / "f.vtu"));
    ASSERT_EQ(r.code, 0) << r.output;
    constexpr double sigma = 5.670374419e-8;
    const double q_floor = 0.5 * sigma * (std::pow(400.0, 4) - std::pow(300.0, 4));
    const double black = sigma * std::pow(300.0, 4);
    // The floor's error: (1 - 0.5) sigma 300^4 |1 - row sum|, the row sum within 1e-6 of 1 (every
    // ray hits the closed box; float storage of F), plus the 10 printed digits (5e-10 relative).
    const double tol = 0.5 * black * 1e-6 + 5e-10 * q_floor;
    std::map<long, double> flux;
    std::size_t floor_patches = 0;
    for (const auto& row : csv(read_text(out / "p.csv"))) {
        ASSERT_EQ(row.size(), 8u);  // patch,object,area,temperature,heat_flux,radiosity,irradiation,element_id
        const double q = std::stod(row.at(4)), j = std::stod(row.at(5));
        if (row.at(1) == "zmin") {
            EXPECT_NEAR(q, q_floor, tol) << "patch " << row.at(0);
            ++floor_patches;
        } else {
            EXPECT_NEAR(j, black, 5e-10 * black) << "patch " << row.at(0);
        }
        EXPECT_TRUE(flux.emplace(std::stol(row.at(7)), q).second) << "element " << row.at(7) << " twice";
    }
    EXPECT_GT(floor_patches, 5u);
    // meshio reads the .vtu: each element's heat flux as the patch table has it (17 digits there, 10 here).
    const std::string script = "import meshio,sys\nm=meshio.read(sys.argv[1])\nd=m.cell_data\n"
                               "for i,q in zip(d['element_id'][0],d['heat_flux'][0]): print(int(i),repr(float(q)))\n";
    test::write_file(out / "read.py", script);
    ASSERT_EQ(std::system(("/usr/bin/python3 " + (out / "read.py") + " " + (out / "f.vtu") + " > " + (out / "v.txt")).c_str()), 0);
    std::istringstream v(read_text(out / "v.txt"));
    std::size_t cells = 0;
    for (long id; v >> id; ++cells) {
        double q = 0.0;
        v >> q;
        ASSERT_EQ(flux.count(id), 1u) << "element " << id;
        EXPECT_NEAR(q, flux[id], 5e-10 * std::abs(q_floor)) << "element " << id;
    }
    EXPECT_EQ(cells, flux.size());
}

TEST(GmshCli, MeshOptionsOnOtherFormatsAreRefused) {
    const std::string obj = test::example("cube.obj");
    auto r = run_ffcube("formfactors " + obj + " -q --method raycast --flip a");
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--flip reverses groups of a mesh read through Gmsh"), std::string::npos) << r.output;
    r = run_ffcube("formfactors " + obj + " -q --method raycast --objects-by element");
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("apply to meshes read through Gmsh"), std::string::npos) << r.output;
    r = run_ffcube("formfactors " + (models() / "box_41.msh") + " -q --method raycast --objects-by g");
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("apply to OBJ files"), std::string::npos) << r.output;
    // VTK XML: not read here (Gmsh reads legacy .vtk only); the message names the Python route.
    TempDir dir;
    test::write_file(dir / "box.vtu", "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\"></VTKFile>\n");
    r = run_ffcube("formfactors " + (dir / "box.vtu") + " -q --method raycast -o " + (dir / "F.ffm"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find((dir / "box.vtu") + ": VTK XML (.vtu) is not read by the command line"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("ffcube.load_scene(meshio.read("), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "F.ffm"));
}

}  // namespace
}  // namespace ffcube
