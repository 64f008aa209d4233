// ffcube solve --target-error / --max-elements (docs/adaptive.md): bad values are refused before
// any work, and a run reports what it refined and each object's estimated error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/cli_util.hpp"

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

// A floor under a square light with a square occluder between them (a shadow to refine).
void write_shadow_scene(const TempDir& dir) {
    std::ofstream(dir / "s.mtl") << "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n";
    std::ofstream(dir / "s.obj") << "mtllib s.mtl\n"
                                    "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                    "v -0.25 -0.25 0.5\nv 0.25 -0.25 0.5\nv 0.25 0.25 0.5\nv -0.25 0.25 0.5\n"
                                    "v -0.5 -0.25 1\nv 0 -0.25 1\nv 0 0.25 1\nv -0.5 0.25 1\n"
                                    "o floor\nusemtl grey\nf 1 2 3 4\n"
                                    "o occluder\nf 5 6 7 8\n"
                                    "o light\nusemtl lamp\nf 9 12 11 10\n";
}

TEST(AdaptiveCli, BadValuesAreRefusedBeforeAnyWork) {
    TempDir dir;
    write_shadow_scene(dir);
    const std::string scene = dir / "s.obj";
    auto r = run_ffcube("solve " + scene + " --target-error 0 --objects " + (dir / "o.csv"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--target-error 0: must be a finite number > 0"), std::string::npos) << r.output;
    r = run_ffcube("solve " + scene + " --max-patch-edge 0.5 --max-elements 3 --objects " + (dir / "o.csv"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--max-elements 3: fewer than the"), std::string::npos) << r.output;
    r = run_ffcube("solve " + scene + " --target-error 1e-3 --matrix " + (dir / "none.ffm"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--matrix with --target-error"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "o.csv"));
}

TEST(AdaptiveCli, ReportSaysWhatWasRefinedAndEachObjectsError) {
    TempDir dir;
    write_shadow_scene(dir);
    const auto r = run_ffcube("solve " + (dir / "s.obj") + " --max-patch-edge 0.5 --resolution 32 --solver direct" +
                              " --target-error 1e-3 --max-elements 200 -q --radiosity " + (dir / "p.csv") + " --report " +
                              (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto rep = nlohmann::json::parse(test::read_text(dir / "r.json"));
    const auto& a = rep["adaptive"];
    const std::size_t elements = a["elements"];
    EXPECT_GT(elements, std::size_t{a["start_patches"]});
    EXPECT_LE(elements, 200u);
    // Each level's elements are the previous level's plus 3 per refined patch (factor 2).
    const auto& levels = a["levels"];
    ASSERT_GE(levels["elements"].size(), 2u);
    for (std::size_t k = 1; k < levels["elements"].size(); ++k)
        EXPECT_EQ(std::size_t{levels["elements"][k]}, std::size_t{levels["elements"][k - 1]} + 3 * std::size_t{levels["refined"][k - 1]});
    EXPECT_EQ(levels["elements"].back(), elements);
    // Elements per object add up; the floor (the shadow's receiver) got the most.
    const auto per_object = a["elements_per_object"];
    std::size_t sum = 0;
    for (const auto& n : per_object) sum += std::size_t{n};
    EXPECT_EQ(sum, elements);
    EXPECT_GT(per_object[0], per_object[1]);
    const auto& err = rep["discretisation_error"];
    EXPECT_EQ(err["basis"], "levels");
    ASSERT_EQ(err["objects"].size(), 3u);
    for (const auto& e : err["relative"]) EXPECT_GE(double{e}, 0.0);
    // The per-patch CSV lists the elements (a header and one line each).
    std::istringstream csv(test::read_text(dir / "p.csv"));
    std::size_t lines = 0;
    for (std::string line; std::getline(csv, line);) ++lines;
    EXPECT_EQ(lines, elements + 1);
}

// A 0.5 cube standing on a 2 × 2 floor under a light (contact cuts: scene/contact.hpp).
// `base`: the height of the block's bottom edges ("0": standing on the floor).
void write_block_scene(const TempDir& dir, const std::string& base = "0") {
    std::ofstream(dir / "b.mtl") << "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n";
    std::ofstream(dir / "b.obj") << "mtllib b.mtl\n"
                                    "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                    "v -0.25 -0.25 " + base + "\nv 0.25 -0.25 " + base + "\nv 0.25 0.25 " + base +
                                    "\nv -0.25 0.25 " + base + "\n"
                                    "v -0.25 -0.25 0.5\nv 0.25 -0.25 0.5\nv 0.25 0.25 0.5\nv -0.25 0.25 0.5\n"
                                    "v -0.5 -0.5 1.5\nv 0.5 -0.5 1.5\nv 0.5 0.5 1.5\nv -0.5 0.5 1.5\n"
                                    "o floor\nusemtl grey\nf 1 2 3 4\n"
                                    "o block\nf 5 6 10 9\nf 6 7 11 10\nf 7 8 12 11\nf 8 5 9 12\nf 9 10 11 12\n"
                                    "o light\nusemtl lamp\nf 13 16 15 14\n";
}

std::vector<std::vector<std::string>> csv_rows(const std::filesystem::path& path) {
    std::istringstream in(test::read_text(path));
    std::vector<std::vector<std::string>> rows;
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        std::vector<std::string> cells;
        std::istringstream l(line);
        for (std::string c; std::getline(l, c, ',');) cells.push_back(c);
        rows.push_back(cells);
    }
    return rows;
}

// The floor is cut along the block's footprint: the patches under the block receive nothing (the
// only paths to them pass through the block's back faces, and every pair with them fails the
// facing test), those around it do, and no patch straddles the contact line.
TEST(AdaptiveCli, ContactCutsLeaveTheCoveredFloorDark) {
    TempDir dir;
    write_block_scene(dir);
    const std::string mesh = (dir / "b.obj") + " --max-patch-edge 0.3 --contact-cuts on --resolution 32 -q";
    auto r = run_ffcube("solve " + mesh + " --solver direct --radiosity " + (dir / "p.csv") + " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto rep = nlohmann::json::parse(test::read_text(dir / "r.json"));
    EXPECT_EQ(rep["meshing"]["contact_cuts"]["contacts"], 1);
    EXPECT_EQ(rep["meshing"]["contact_cuts"]["receivers"], 1);
    EXPECT_NEAR(double{rep["meshing"]["contact_cuts"]["covered_area"]}, 0.25, 1e-12);
    // Where the patches lie: the same mesh's patch table.
    r = run_ffcube("formfactors " + mesh + " --patch-table " + (dir / "t.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto table = csv_rows(dir / "t.csv");
    const auto b = csv_rows(dir / "p.csv");
    ASSERT_EQ(table.size(), b.size());
    double covered = 0, max_lit = 0, min_lit = 1e300;
    for (std::size_t i = 0; i < b.size(); ++i) {
        if (table[i][1] != "floor") continue;
        const double x = std::stod(table[i][3]), y = std::stod(table[i][4]);
        const double B = std::stod(b[i][3]);
        // A centroid on the contact line would mean a patch straddling it.
        EXPECT_FALSE(std::abs(std::abs(x) - 0.25) < 1e-9 && std::abs(y) <= 0.25) << i;
        if (std::abs(x) < 0.25 && std::abs(y) < 0.25) {
            covered += std::stod(table[i][2]);
            EXPECT_EQ(B, 0.0) << "patch " << i << " under the block";
        } else {
            max_lit = std::max(max_lit, B);
            min_lit = std::min(min_lit, B);
        }
    }
    EXPECT_NEAR(covered, 0.25, 1e-12);  // the footprint, 0.5 × 0.5
    EXPECT_GT(min_lit, 0.0);
    // --no-subdivide refuses the cuts (the cut faces are n-gons, not one patch each).
    r = run_ffcube("solve " + (dir / "b.obj") + " --no-subdivide --contact-cuts on --objects " + (dir / "o.csv"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--contact-cuts on with --no-subdivide"), std::string::npos) << r.output;
}

// Contact cuts are on by default (--contact-cuts auto) for every command that meshes, fire only where
// an object stands on another, say so in the report and on stderr, and --no-contact-cuts (or
// --contact-cuts off) switches them off. The default run is the --contact-cuts on run, byte for
// byte; the uncut run meshes the floor as a plain 7 × 7 grid (2 / 0.3 → 7 cells a side).
TEST(AdaptiveCli, ContactCutsAreOnByDefaultWhereTheSceneHasContacts) {
    TempDir dir;
    write_block_scene(dir);
    const std::string mesh = (dir / "b.obj") + " --max-patch-edge 0.3 --resolution 32 --solver direct --threads 1";
    auto solve = [&](const std::string& name, const std::string& flags) {
        auto r = run_ffcube("solve " + mesh + " " + flags + " --radiosity " + (dir / (name + ".csv")) + " --report " +
                            (dir / (name + ".json")));
        EXPECT_EQ(r.code, 0) << r.output;
        return std::pair{r.output, nlohmann::json::parse(test::read_text(dir / (name + ".json")))};
    };
    const auto [log, rep] = solve("default", "");
    EXPECT_EQ(rep["meshing"]["contact_cuts"]["mode"], "auto");
    EXPECT_EQ(rep["meshing"]["contact_cuts"]["fired"], true);
    EXPECT_EQ(rep["meshing"]["contact_cuts"]["contacts"], 1);
    EXPECT_EQ(rep["meshing"]["contact_cuts"]["receivers"], 1);
    EXPECT_NE(log.find("contact cuts (auto; off: --contact-cuts off): 1 contact polygons cut 1 faces"), std::string::npos) << log;
    solve("on", "-q --contact-cuts on");
    EXPECT_EQ(test::read_text(dir / "default.csv"), test::read_text(dir / "on.csv"));
    const auto [off_log, off_rep] = solve("off", "--no-contact-cuts");
    EXPECT_EQ(off_rep["meshing"]["contact_cuts"]["enabled"], false);
    EXPECT_EQ(off_rep["meshing"]["contact_cuts"]["fired"], false);
    EXPECT_EQ(off_log.find("contact cuts"), std::string::npos) << off_log;
    const auto b = csv_rows(dir / "off.csv");
    EXPECT_EQ(std::count_if(b.begin(), b.end(), [](const auto& row) { return row[1] == "floor"; }), 49);
    // A block raised off the floor stands on nothing: the cuts run, find no contact, and say so.
    write_block_scene(dir, "0.1");
    const auto [raised_log, raised] = solve("raised", "");
    EXPECT_EQ(raised["meshing"]["contact_cuts"]["enabled"], true);
    EXPECT_EQ(raised["meshing"]["contact_cuts"]["fired"], false);
    EXPECT_EQ(raised["meshing"]["contact_cuts"]["contacts"], 0);
    EXPECT_NE(raised_log.find("contact cuts (auto): no object stands on another, nothing cut"), std::string::npos) << raised_log;
    // --no-subdivide with the default: no cuts and no refusal (only an explicit --contact-cuts on refuses).
    auto r = run_ffcube("solve " + (dir / "b.obj") + " -q --no-subdivide --resolution 32 --threads 1 --report " + (dir / "n.json"));
    EXPECT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(nlohmann::json::parse(test::read_text(dir / "n.json"))["meshing"]["contact_cuts"]["enabled"], false);
}

}  // namespace
}  // namespace ffcube
