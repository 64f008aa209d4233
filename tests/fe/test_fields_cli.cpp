// Results back onto FE meshes (issue 39, docs/fe-meshes.md): `--fields OUT.msh` writes a Gmsh
// model with views that Gmsh itself reopens (tools/msh_views, linked against libgmsh, reads it
// back) with the input's element ids, groups and element centroids, and with the values the
// `.vtu` of the same run holds (read by meshio), element by element; `ffcube solve --fields`
// writes the radiosity of a closed box against its closed form. Runs are deterministic (the same
// input gives the same output), so two runs that differ only in the name after --fields are the
// "same run".
#include <gtest/gtest.h>

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

using test::csv;
using test::models;
using test::read_text;
using test::run_ffcube;
using test::TempDir;

const std::string kFlipBox = " --flip xmin,xmax,ymin,ymax,zmin,zmax";

// A table of named columns, one row per cell or element.
struct Table {
    std::vector<std::string> names;
    std::vector<std::vector<std::string>> rows;
    int column(const std::string& name) const {
        for (std::size_t k = 0; k < names.size(); ++k)
            if (names[k] == name) return int(k);
        return -1;
    }
};

Table table_of(const std::string& text) {
    Table t;
    std::istringstream in(text);
    std::string header, cell;
    std::getline(in, header);
    std::stringstream hs(header);
    while (std::getline(hs, cell, ',')) t.names.push_back(cell);
    t.rows = csv(text);
    return t;
}

// The .msh as Gmsh reads it: element,type,group,cx,cy,cz,<views...> (tools/msh_views.cpp).
Table msh_elements(const TempDir& dir, const std::string& msh) {
    const std::string out = dir / "views.csv";
    EXPECT_EQ(std::system((std::string(FFCUBE_MSH_VIEWS) + " " + msh + " > " + out).c_str()), 0) << msh;
    return table_of(read_text(out));
}

// The .vtu as meshio reads it: its cell arrays by name, 17 significant digits.
Table vtu_cells(const TempDir& dir, const std::string& vtu) {
    test::write_file(dir / "vtu.py", "import meshio,sys\nm=meshio.read(sys.argv[1])\nd=m.cell_data\nk=list(d)\n"
                                     "print(','.join(k))\n"
                                     "for i in range(len(d[k[0]][0])): print(','.join(repr(float(d[n][0][i])) for n in k))\n");
    const std::string out = dir / "vtu.csv";
    EXPECT_EQ(std::system(("/usr/bin/python3 " + (dir / "vtu.py") + " " + vtu + " > " + out).c_str()), 0) << vtu;
    return table_of(read_text(out));
}

// Every element of the .msh is the cell of the .vtu whose `patch` it names, with the same value
// in every array; its tag is the cell's element_id when `tags_are_ids`, else its patch + 1; its
// group is the object the patch table names for that patch, and its centroid the table's.
// Returns the .msh's elements by tag.
std::map<long, std::vector<std::string>> check_msh_against_vtu(const Table& msh, const Table& vtu, const std::string& patch_table,
                                                               bool tags_are_ids) {
    std::map<long, std::vector<std::string>> by_tag;
    const auto patches = csv(patch_table);
    EXPECT_EQ(msh.rows.size(), vtu.rows.size());
    EXPECT_EQ(msh.rows.size(), patches.size());
    // Every array of the .vtu is a view of the .msh (points and connectivity are not cell arrays).
    for (const std::string& name : vtu.names) EXPECT_GE(msh.column(name), 0) << "no view " << name;
    const int vtu_patch = vtu.column("patch"), msh_patch = msh.column("patch"), vtu_id = vtu.column("element_id");
    if (vtu_patch < 0 || msh_patch < 0) return by_tag;
    std::map<long, const std::vector<std::string>*> cell_of_patch;
    for (const auto& row : vtu.rows) cell_of_patch[std::lround(std::stod(row.at(std::size_t(vtu_patch))))] = &row;
    for (const auto& row : msh.rows) {
        const long tag = std::stol(row.at(0));
        EXPECT_TRUE(by_tag.emplace(tag, row).second) << "element " << tag << " twice";
        const long patch = std::lround(std::stod(row.at(std::size_t(msh_patch))));
        EXPECT_EQ(cell_of_patch.count(patch), 1u) << "element " << tag << " names patch " << patch;
        if (!cell_of_patch.count(patch)) return by_tag;
        const std::vector<std::string>& cell = *cell_of_patch[patch];
        if (tags_are_ids) {
            EXPECT_GE(vtu_id, 0);
            if (vtu_id >= 0) EXPECT_EQ(double(tag), std::stod(cell.at(std::size_t(vtu_id)))) << "element " << tag;
        } else {
            EXPECT_EQ(tag, patch + 1);
        }
        for (std::size_t k = 0; k < vtu.names.size(); ++k) {
            const double a = std::stod(row.at(std::size_t(msh.column(vtu.names[k])))), b = std::stod(cell.at(k));
            // Gmsh writes a view's values with 16 significant digits (relative rounding at most
            // 5e-16) and the .vtu has 17 (exact): 1e-15 of the value, and 1e-300 for zeros.
            EXPECT_NEAR(a, b, 1e-15 * std::abs(b) + 1e-300) << "element " << tag << ", " << vtu.names[k];
        }
        const auto& p = patches.at(std::size_t(patch));
        EXPECT_EQ(row.at(2), p.at(1)) << "element " << tag << ": its physical group is the patch's object";
        // The table prints 9 significant digits of coordinates of at most 2: 5e-9 each.
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(std::stod(row.at(3 + std::size_t(a))), std::stod(p.at(3 + std::size_t(a))), 1e-8);
    }
    return by_tag;
}

// The box of gmsh_models, each triangle one patch: the .msh of --fields reopens in Gmsh with the
// input file's element tags, each in the physical group it had and at the centroid it had, and
// with the sky view factor and row sum of the .vtu of the same run, element by element.
TEST(GmshFields, MshReopensWithTheInputsElementsAndTheVtusValues) {
    const TempDir& m = models();
    TempDir out;
    const std::string run = "formfactors " + (m / "box_41.msh") + " --no-subdivide --method raycast --rays 1024 -q" + kFlipBox +
                            " --patch-table " + (out / "t.csv") + " --fields ";
    auto r = run_ffcube(run + (out / "f.msh"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube(run + (out / "f.vtu"));
    ASSERT_EQ(r.code, 0) << r.output;
    const Table msh = msh_elements(out, out / "f.msh");
    const Table vtu = vtu_cells(out, out / "f.vtu");
    for (const char* name : {"patch", "object", "element_id", "area", "sky_view_factor", "row_sum"})
        EXPECT_GE(vtu.column(name), 0) << name;
    const auto written = check_msh_against_vtu(msh, vtu, read_text(out / "t.csv"), true);
    // The input as Gmsh reads it: the same triangles (tags), groups and centroids. Both files
    // carry Gmsh's 16 digits of coordinates of at most 2; ffcube's recentring adds and takes off
    // its origin, a few ulps of 2 (4.4e-16 each): 1e-12.
    const Table input = msh_elements(out, m / "box_41.msh");
    std::size_t triangles = 0;
    for (const auto& row : input.rows) {
        if (row.at(1) != "2") continue;  // lines and points of the input are not patches
        ++triangles;
        const auto it = written.find(std::stol(row.at(0)));
        ASSERT_NE(it, written.end()) << "element " << row.at(0) << " of the input is not in the output";
        EXPECT_EQ(it->second.at(1), "2");
        EXPECT_EQ(it->second.at(2), row.at(2)) << "element " << row.at(0);
        for (std::size_t a = 3; a < 6; ++a) EXPECT_NEAR(std::stod(it->second.at(a)), std::stod(row.at(a)), 1e-12) << "element " << row.at(0);
    }
    EXPECT_EQ(triangles, written.size());
    EXPECT_GT(triangles, 50u);
    // ffcube reads its .msh back as the scene it wrote (walls already facing in): the same
    // patches, objects, areas, centroids, normals and element ids, to the table's 9 digits.
    r = run_ffcube("formfactors " + (out / "f.msh") + " --no-subdivide --method raycast --rays 64 -q --patch-table " + (out / "t2.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    auto before = csv(read_text(out / "t.csv")), after = csv(read_text(out / "t2.csv"));
    for (auto* t : {&before, &after})
        for (auto& row : *t) row.resize(10);  // patch .. element_id; the error estimate depends on the rays
    EXPECT_EQ(after, before);
}

// Quadratic triangles are split into linear pieces that share their element's id: the .msh's
// elements are then the patches (tag = patch + 1) and the id is in the view element_id.
TEST(GmshFields, PiecesOfQuadraticElementsCarryTheirIdsInAView) {
    const TempDir& m = models();
    TempDir out;
    const std::string run = "formfactors " + (m / "cylinder_o2.msh") + " --no-subdivide --method raycast --rays 1024 -q" +
                            " --patch-table " + (out / "t.csv") + " --fields ";
    auto r = run_ffcube(run + (out / "f.msh"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube(run + (out / "f.vtu"));
    ASSERT_EQ(r.code, 0) << r.output;
    const Table msh = msh_elements(out, out / "f.msh");
    const auto written = check_msh_against_vtu(msh, vtu_cells(out, out / "f.vtu"), read_text(out / "t.csv"), false);
    // Each 6-node triangle of the input is 4 patches with its id.
    std::map<long, int> pieces;
    for (const auto& [tag, row] : written) ++pieces[std::lround(std::stod(row.at(std::size_t(msh.column("element_id")))))];
    for (const auto& [id, k] : pieces) EXPECT_EQ(k, 4) << "element " << id;
    EXPECT_GT(pieces.size(), 10u);
}

// radiate's fields (temperature, heat flux, radiosity, irradiation, sky view factor) in the .msh
// are those of the .vtu, element by element.
TEST(GmshFields, RadiateMshAgreesWithItsVtu) {
    const TempDir& m = models();
    TempDir out;
    test::write_file(out / "s.csv", "object,emissivity,temperature,heat_flux\nzmin,0.5,400,\n");
    const std::string run = "radiate " + (m / "box_41.msh") + " --no-subdivide --method raycast --rays 1024 -q" + kFlipBox +
                            " --surfaces " + (out / "s.csv") + " --default-surface 1,300 --fields ";
    auto r = run_ffcube(run + (out / "f.msh"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube(run + (out / "f.vtu"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("formfactors " + (m / "box_41.msh") + " --no-subdivide -q --method raycast --rays 1024" + kFlipBox +
                   " --patch-table " + (out / "t.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const Table vtu = vtu_cells(out, out / "f.vtu");
    for (const char* name : {"temperature", "heat_flux", "radiosity", "irradiation", "sky_view_factor"})
        EXPECT_GE(vtu.column(name), 0) << name;
    check_msh_against_vtu(msh_elements(out, out / "f.msh"), vtu, read_text(out / "t.csv"), true);
}

// ffcube solve --fields: every wall of the closed box emits Ke = (1, 2, 3) and reflects
// Kd = (0.5, 0.25, 0). With rows summing to 1, B = Ke / (1 - Kd) = (2, 8/3, 3) on every patch
// whatever F is. The .msh and the .vtu carry it per element with the element ids of the input.
TEST(GmshFields, SolveWritesTheRadiosityOntoTheElements) {
    const TempDir& m = models();
    TempDir out;
    std::string materials = "object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b\n";
    for (const char* wall : {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"}) materials += std::string(wall) + ",0.5,0.25,0,1,2,3\n";
    test::write_file(out / "m.csv", materials);
    const std::string run = "solve " + (m / "box_41.msh") + " --no-subdivide --method raycast --rays 1024 -q --solver direct" +
                            kFlipBox + " --materials " + (out / "m.csv") + " --sky " + (out / "sky.csv") + " --fields ";
    auto r = run_ffcube(run + (out / "f.msh"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube(run + (out / "f.vtu"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("formfactors " + (m / "box_41.msh") + " --no-subdivide -q --method raycast --rays 1024" + kFlipBox +
                   " --patch-table " + (out / "t.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const Table vtu = vtu_cells(out, out / "f.vtu");
    check_msh_against_vtu(msh_elements(out, out / "f.msh"), vtu, read_text(out / "t.csv"), true);
    // Closed form. A row summing to 1 - d gives B = Ke / (1 - Kd (1 - d)), off by at most
    // Kd d / (1 - Kd) of B (to first order); every ray of a closed box hits it, so d is the float
    // storage of the row, under 1e-6: 1e-6 of B (Kd <= 1/2), and the direct solve's rounding far below.
    const double exact[3] = {2.0, 8.0 / 3.0, 3.0};
    const char* channel[3] = {"radiosity_r", "radiosity_g", "radiosity_b"};
    for (int c = 0; c < 3; ++c) {
        const int k = vtu.column(channel[c]);
        ASSERT_GE(k, 0) << channel[c];
        for (const auto& row : vtu.rows) EXPECT_NEAR(std::stod(row.at(std::size_t(k))), exact[c], 1e-6 * exact[c]) << channel[c];
    }
    // The sky view factor of a closed box is 0 (to the rows' storage, 1e-6).
    const int s = vtu.column("sky_view_factor");
    ASSERT_GE(s, 0);
    for (const auto& row : vtu.rows) EXPECT_NEAR(std::stod(row.at(std::size_t(s))), 0.0, 1e-6);
}

// Two unit squares facing each other 1 apart, as quads in an OBJ whose object names hold a double
// quote and a space: the .msh holds 4-node quadrangles (Gmsh type 3), the name with its quote
// written as a single one (the format has no escape), and each square's row sum, Howell's C-11
// for parallel unit squares at distance 1.
TEST(GmshFields, QuadsAndQuotedNamesReopenInGmsh) {
    TempDir out;
    test::write_file(out / "q.obj", "o we\"ird name\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"
                                    "o other\nv 0 0 1\nv 0 1 1\nv 1 1 1\nv 1 0 1\nf 5 6 7 8\n");
    constexpr int kRaysHere = 4096;
    const auto r = run_ffcube("formfactors " + (out / "q.obj") + " --no-subdivide --method raycast -q --rays " +
                              std::to_string(kRaysHere) + " --fields " + (out / "q.msh"));
    ASSERT_EQ(r.code, 0) << r.output;
    const Table msh = msh_elements(out, out / "q.msh");
    ASSERT_EQ(msh.rows.size(), 2u);
    const int row_sum = msh.column("row_sum");
    ASSERT_GE(row_sum, 0);
    const double exact = ff_parallel_rectangles(1.0, 1.0, 1.0);
    // A ray-cast row of R rays has a standard error of at most sqrt(F (1 - F) / R): 5 of them.
    const double tol = 5.0 * std::sqrt(exact * (1.0 - exact) / kRaysHere);
    std::vector<std::string> groups;
    for (const auto& row : msh.rows) {
        EXPECT_EQ(row.at(1), "3");
        groups.push_back(row.at(2));
        EXPECT_NEAR(std::stod(row.at(std::size_t(row_sum))), exact, tol) << row.at(2);
    }
    EXPECT_EQ(groups, (std::vector<std::string>{"we'ird name", "other"}));
}

// A name that is neither .vtu nor .msh is refused before any work, naming the option; so is a
// .msh into a directory that does not exist (no file, no temporary left behind).
TEST(GmshFields, BadFieldsPathsAreRefused) {
    const TempDir& m = models();
    TempDir out;
    for (const std::string cmd : {"formfactors", "solve"}) {
        auto r = run_ffcube(cmd + " " + (m / "box_41.msh") + " --no-subdivide --method raycast -q --fields " + (out / "f.vtk"));
        EXPECT_EQ(r.code, 2) << r.output;
        EXPECT_NE(r.output.find("--fields " + (out / "f.vtk") + ": the name must end in .vtu"), std::string::npos) << r.output;
    }
    test::write_file(out / "s.csv", "object,emissivity,temperature,heat_flux\nzmin,0.5,400,\n");
    auto r = run_ffcube("radiate " + (m / "box_41.msh") + " --no-subdivide --method raycast -q --surfaces " + (out / "s.csv") +
                        " --default-surface 1,300 --fields " + (out / "f.txt"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("the name must end in .vtu (VTK, for ParaView) or .msh"), std::string::npos) << r.output;
    r = run_ffcube("formfactors " + (m / "box_41.msh") + " --no-subdivide --method raycast --rays 256 -q --fields " +
                   (out / "no/such/dir/f.msh"));
    EXPECT_NE(r.code, 0) << r.output;
    EXPECT_NE(r.output.find(out / "no/such/dir"), std::string::npos) << r.output;
    std::size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(out.path())) files += e.path().filename() != "s.csv";
    EXPECT_EQ(files, 0u);
}

}  // namespace
}  // namespace ffcube
