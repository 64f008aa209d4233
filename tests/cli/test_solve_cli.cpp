// `ffcube solve` end to end: the furnace through real hemicube rows, the picture against the
// radiosity it shows, rows from a .ffm file against rows computed directly, outputs consistent
// with each other, and bad input refused with exit 2 and no output file.
#include <gtest/gtest.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "cli/cli_util.hpp"
#include "ffcube/io/ffm.hpp"

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

// The closed unit cube of examples/cube.obj (inward faces, objects x0..z1) with every face of
// one material "m" (Kd kd, Ke ke), and the .mtl beside it.
std::string write_cube(const TempDir& dir, const std::string& kd, const std::string& ke) {
    std::ofstream(dir / "m.mtl") << "newmtl m\nKd " << kd << "\nKe " << ke << "\n";
    std::string obj = test::read_text(test::example("cube.obj"));
    obj = "mtllib m.mtl\nusemtl m\n" + obj;
    std::ofstream(dir / "cube.obj") << obj;
    return dir / "cube.obj";
}

struct PatchRow {
    std::string object;
    double area;
    double B[3];
};

std::vector<PatchRow> read_patch_csv(const std::string& path) {
    std::istringstream in(test::read_text(path));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "patch,object,area,B_r,B_g,B_b");
    std::vector<PatchRow> rows;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream ss(line);
        std::string item;
        while (std::getline(ss, item, ',')) f.push_back(item);
        EXPECT_EQ(f.size(), 6u) << line;
        if (f.size() != 6) continue;
        EXPECT_EQ(std::stoul(f[0]), rows.size());
        rows.push_back({f[1], std::stod(f[2]), {std::stod(f[3]), std::stod(f[4]), std::stod(f[5])}});
    }
    return rows;
}

// Furnace: a closed box, every face E = 1 and ρ, has B* = E/(1 − ρ) everywhere when the rows
// are exact. With hemicube rows, what the method solves differs from B* by:
//  (a) the rows' sums s_i (gathering solves B_i = E + ρ Σ_j F_ij B_j, whose uniform solution is
//      E/(1 − ρs)), or for shooting the received sums c_j = Σ_i A_i F_ij / A_j (a shot gives j
//      ρ ΔB_i F_ij A_i / A_j, the transpose, so non-reciprocal rows count): with every sum within
//      [1 − γ, 1 + γ] the solution lies within E/(1 − ρ(1 ± γ)), i.e. ργ/((1 − ρ)(1 − ρ(1 + γ)))
//      relative. γ is measured here from the same rows written by `ffcube formfactors` (same
//      seed and resolution), plus 1e-7 for their float storage;
//  (b) stopping at unshot power ≤ τ × emitted leaves |B − B_solved| ≤ q/(1 − q) × τ × emitted /
//      min A (docs/solvers.md), q = ρ(1 + γ), emitted = 6, min A = 0.25;
//  (c) the CSV's 9 significant digits (5e-9 relative).
struct FurnaceCase {
    double rho;
    double tol;
    const char* solver;
};
class SolveFurnace : public testing::TestWithParam<FurnaceCase> {};

TEST_P(SolveFurnace, EveryPatchHoldsEOverOneMinusRho) {
    const auto [rho, tau, solver] = GetParam();
    TempDir dir;
    const std::string scene = write_cube(dir, fmt::format("{0} {0} {0}", rho), "1 1 1");
    const std::string mesh = " --max-patch-edge 0.5 --resolution 64 -q";
    ASSERT_EQ(run_ffcube("formfactors " + scene + mesh + " -o " + (dir / "F.ffm")).code, 0);
    const FfmFile f = read_ffm(dir / "F.ffm");
    std::vector<double> received(f.matrix.size(), 0.0);
    double gamma = 0.0;
    for (std::uint32_t i = 0; i < f.matrix.size(); ++i) {
        const RowView row = f.matrix.row(i);
        gamma = std::max(gamma, std::abs(row.sum() - 1.0));
        for (std::size_t k = 0; k < row.col.size(); ++k) received[row.col[k]] += f.areas[i] * row.val[k];
    }
    if (std::string(solver) == "shoot")
        for (std::uint32_t j = 0; j < f.matrix.size(); ++j) gamma = std::max(gamma, std::abs(received[j] / f.areas[j] - 1.0));
    gamma += 1e-7;

    const auto r = run_ffcube("solve " + scene + mesh + " --solver " + solver + fmt::format(" --tolerance {}", tau) +
                              " --radiosity " + (dir / "p.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto rows = read_patch_csv(dir / "p.csv");
    ASSERT_EQ(rows.size(), 24u);
    const double exact = 1.0 / (1.0 - rho), q = rho * (1.0 + gamma);
    const double bound = exact * rho * gamma / (1.0 - q) + 24.0 * tau * q / (1.0 - q) + 5e-9 * exact;
    for (const PatchRow& p : rows)
        for (double b : p.B) EXPECT_NEAR(b, exact, bound) << p.object << " gamma " << gamma;
}

INSTANTIATE_TEST_SUITE_P(Rho, SolveFurnace,
                         testing::Values(FurnaceCase{0.5, 1e-8, "shoot"}, FurnaceCase{0.9, 1e-8, "shoot"},
                                         FurnaceCase{0.99, 1e-9, "shoot"}, FurnaceCase{0.9, 1e-8, "gauss-seidel"},
                                         FurnaceCase{0.9, 1e-8, "jacobi"}, FurnaceCase{0.9, 1e-8, "direct"}));

// A camera straight at a unit square split into two objects, each emitting a known Ke with
// ρ = 0: B = Ke exactly, and with --flat a pixel on a half shows L = B/π as a float, exactly
// (one rounding of the double B/π to float, nothing interpolated).
TEST(SolveCli, ExrPixelsShowThePatchRadianceExactly) {
    TempDir dir;
    std::ofstream(dir / "e.mtl") << "newmtl a\nKd 0 0 0\nKe 1 2 3\nnewmtl b\nKd 0 0 0\nKe 0.5 7 0.25\n";
    std::ofstream(dir / "e.obj") << "mtllib e.mtl\n"
                                    "v 0 0 0\nv 0 1 0\nv 0.5 1 0\nv 0.5 0 0\nv 1 1 0\nv 1 0 0\n"
                                    "o a\nusemtl a\nf 1 2 3 4\no b\nusemtl b\nf 4 3 5 6\n";
    const auto r = run_ffcube("solve " + (dir / "e.obj") + " --max-patch-edge 0.25 --resolution 32 -q --flat" +
                              " --camera 0.5,0.5,-2,0.5,0.5,0,40 --width 64 --height 48 --render " + (dir / "img.exr"));
    ASSERT_EQ(r.code, 0) << r.output;
    Imf::InputFile in((dir / "img.exr").c_str());
    const Imath::Box2i dw = in.header().dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    ASSERT_EQ(w, 64);
    ASSERT_EQ(h, 48);
    std::vector<float> px(static_cast<std::size_t>(w) * h * 4);
    Imf::FrameBuffer fb;
    const char* names[4] = {"R", "G", "B", "A"};
    for (int c = 0; c < 4; ++c) {
        ASSERT_NE(in.header().channels().findChannel(names[c]), nullptr);
        fb.insert(names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(px.data() + c), 16, 16 * static_cast<std::size_t>(w)));
    }
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    std::size_t covered = 0;
    for (float v : px) ASSERT_TRUE(std::isfinite(v));
    for (std::size_t i = 0; i < px.size(); i += 4) covered += px[i + 3] == 1.0f;
    // The square spans 1 / (2 × 2 tan 20°) = 0.687 of the height: about 0.687² × 64/48 of the pixels.
    EXPECT_NEAR(static_cast<double>(covered) / (64 * 48), 0.687 * 0.687 * 48 / 64, 0.03);
    // Seen from −z with +y up, +x runs to the left of the picture: object a (x < 0.5) on the right.
    const auto at = [&](int x, int y) { return &px[(static_cast<std::size_t>(y) * w + x) * 4]; };
    const double ka[3] = {1, 2, 3}, kb[3] = {0.5, 7, 0.25};
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(at(42, 24)[c], static_cast<float>(ka[c] / std::numbers::pi)) << c;
        EXPECT_EQ(at(21, 24)[c], static_cast<float>(kb[c] / std::numbers::pi)) << c;
    }
    EXPECT_EQ(at(0, 0)[3], 0.0f);  // background
}

TEST(SolveCli, MatrixFileGivesTheSameRadiosityAndAForeignOneIsRefused) {
    TempDir dir;
    std::ofstream(dir / "m.mtl") << "newmtl m\nKd 0.6 0.5 0.4\nnewmtl light\nKd 0.2 0.2 0.2\nKe 3 2 1\n";
    std::string obj = test::read_text(test::example("cube.obj"));
    // The ceiling (z1) emits; the rest reflect.
    obj = "mtllib m.mtl\nusemtl m\n" + obj;
    obj.replace(obj.find("o z1\n"), 5, "o z1\nusemtl light\n");
    std::ofstream(dir / "c.obj") << obj;
    const std::string common = (dir / "c.obj") + " --max-patch-edge 0.25 --resolution 64 -q --tolerance 1e-12";
    ASSERT_EQ(run_ffcube("formfactors " + common.substr(0, common.find(" --tolerance")) + " -o " + (dir / "F.ffm")).code, 0);
    auto r = run_ffcube("solve " + common + " --radiosity " + (dir / "direct.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("solve " + common + " --matrix " + (dir / "F.ffm") + " --radiosity " + (dir / "file.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto a = read_patch_csv(dir / "direct.csv"), b = read_patch_csv(dir / "file.csv");
    ASSERT_EQ(a.size(), 96u);
    ASSERT_EQ(b.size(), a.size());
    // Same rows, stored as float in the file (relative 6e-8 per entry): with ‖ρF‖ ≤ 0.6 the
    // solution moves by at most 6e-8 × 0.6/(1 − 0.6) ≈ 1e-7 relative; both runs are converged to
    // 1e-12; the CSV prints 9 digits. 1e-6 leaves a margin of 10.
    for (std::size_t i = 0; i < a.size(); ++i)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[i].B[c], a[i].B[c], 1e-6 * a[i].B[c]) << i;

    // The matrix of another scene: refused, exit 2, the message names the fingerprint, no output.
    ASSERT_EQ(run_ffcube("formfactors " + test::example("parallel_squares.obj") + " --max-patch-edge 0.5 --resolution 16 -q -o " +
                         (dir / "other.ffm"))
                  .code,
              0);
    r = run_ffcube("solve " + common + " --matrix " + (dir / "other.ffm") + " --radiosity " + (dir / "x.csv") + " --report " +
                   (dir / "x.json") + " --render " + (dir / "x.png"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("fingerprint"), std::string::npos) << r.output;
    for (const char* f : {"x.csv", "x.json", "x.png"}) EXPECT_FALSE(std::filesystem::exists(dir / f)) << f;
}

// The ray caster serves solve as it serves formfactors: rows made directly and rows read back from
// the .ffm that `formfactors --method raycast` wrote (same seed, so the same rays) give the same B.
TEST(SolveCli, RaycastRowsSolveLikeTheirMatrixFile) {
    TempDir dir;
    std::ofstream(dir / "m.mtl") << "newmtl m\nKd 0.6 0.5 0.4\nnewmtl light\nKd 0.2 0.2 0.2\nKe 3 2 1\n";
    std::string obj = "mtllib m.mtl\nusemtl m\n" + test::read_text(test::example("cube.obj"));
    obj.replace(obj.find("o z1\n"), 5, "o z1\nusemtl light\n");
    std::ofstream(dir / "c.obj") << obj;
    const std::string rows = (dir / "c.obj") + " --max-patch-edge 0.5 --method raycast --rays 512 -q";
    ASSERT_EQ(run_ffcube("formfactors " + rows + " -o " + (dir / "F.ffm")).code, 0);
    auto r = run_ffcube("solve " + rows + " --tolerance 1e-12 --radiosity " + (dir / "direct.csv") + " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(nlohmann::json::parse(test::read_text(dir / "r.json"))["rows"], "raycast");
    r = run_ffcube("solve " + (dir / "c.obj") + " --max-patch-edge 0.5 -q --tolerance 1e-12 --matrix " + (dir / "F.ffm") +
                   " --radiosity " + (dir / "file.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto a = read_patch_csv(dir / "direct.csv"), b = read_patch_csv(dir / "file.csv");
    ASSERT_EQ(a.size(), 24u);
    ASSERT_EQ(b.size(), a.size());
    // As above: float storage moves B by about 1e-7 relative; 9 printed digits; margin 10.
    for (std::size_t i = 0; i < a.size(); ++i)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[i].B[c], a[i].B[c], 1e-6 * a[i].B[c]) << i;
}

TEST(SolveCli, OutputsAreConsistentWithEachOther) {
    TempDir dir;
    const auto r = run_ffcube("solve --patches 150 --resolution 32 -q --objects " + (dir / "o.csv") + " --radiosity " +
                              (dir / "p.csv") + " --report " + (dir / "r.json") + " --mesh " + (dir / "m.ply") + " --render " +
                              (dir / "c.png") + " --width 40 --height 30");
    ASSERT_EQ(r.code, 0) << r.output;
    // Objects CSV = the patch CSV aggregated by area (both printed with 9 digits).
    const auto patches = read_patch_csv(dir / "p.csv");
    std::map<std::string, std::pair<double, std::array<double, 3>>> agg;
    for (const PatchRow& p : patches) {
        auto& [area, sum] = agg[p.object];
        area += p.area;
        for (int c = 0; c < 3; ++c) sum[c] += p.area * p.B[c];
    }
    std::istringstream in(test::read_text(dir / "o.csv"));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "object,area,B_r,B_g,B_b");
    std::size_t objects = 0;
    while (std::getline(in, line)) {
        std::stringstream ss(line);
        std::string name, field;
        std::getline(ss, name, ',');
        std::getline(ss, field, ',');
        const double area = std::stod(field);
        ASSERT_TRUE(agg.count(name)) << name;
        EXPECT_NEAR(area, agg[name].first, 1e-8 * area);
        for (int c = 0; c < 3; ++c) {
            std::getline(ss, field, ',');
            const double mean = agg[name].second[c] / agg[name].first;
            EXPECT_NEAR(std::stod(field), mean, 1e-7 * std::max(mean, 1e-3)) << name << c;
        }
        ++objects;
    }
    EXPECT_EQ(objects, agg.size());
    EXPECT_EQ(objects, 8u);  // the Cornell box's objects
    // The report.
    const auto rep = nlohmann::json::parse(test::read_text(dir / "r.json"));
    for (const char* key : {"iterations", "shots", "unshot_fraction", "stop_reason", "energy", "time", "history", "row_cache",
                            "hemicubes", "backend", "renderer", "resolution", "exposure", "render", "patches", "fingerprint"})
        EXPECT_TRUE(rep.contains(key)) << key;
    EXPECT_EQ(rep["stop_reason"], "converged");
    EXPECT_LE(rep["unshot_fraction"].get<double>(), 1e-4);
    EXPECT_EQ(rep["history"]["seconds"].size(), rep["history"]["unshot_fraction"].size());
    for (const char* key : {"rows_computed", "rows_reused", "rows_evicted", "patches_without_row"})
        EXPECT_TRUE(rep["row_cache"].contains(key)) << key;
    // Every patch either shot (its row computed once, the cache being large enough) or never needed a row.
    EXPECT_EQ(rep["row_cache"]["rows_computed"].get<std::size_t>() + rep["row_cache"]["patches_without_row"].get<std::size_t>(),
              patches.size());
    // One hemicube per computed row, and for the rows made of sub-hemicubes (near pairs that may
    // be occluded, occluders beside the sender) 4 on a quad, 3 on a triangle: 2 or 3 more each;
    // 16 (15 more) for those at 4 × 4 points (an occluder touching the sender).
    const std::size_t rows = rep["row_cache"]["rows_computed"], hemicubes = rep["hemicubes"],
                      sub = rep["sub_hemicube_rows"], fine = rep["corrections"]["rows_sub_hemicubes_4x4"];
    EXPECT_GE(hemicubes, rows + 2 * sub + 12 * fine);
    EXPECT_LE(hemicubes, rows + 3 * sub + 12 * fine);
    // Energy: emitted = absorbed + escaped + unshot, per channel.
    for (int c = 0; c < 3; ++c) {
        const double e = rep["energy"]["emitted"][c], a = rep["energy"]["absorbed"][c], s = rep["energy"]["escaped"][c],
                     u = rep["energy"]["unshot"][c];
        EXPECT_NEAR(e, a + s + u, 1e-9 * e);
    }
    // The PLY: the header's vertex count matches the body's size (27 bytes per vertex: xyz,
    // rgb, radiosity; faces: 1 + 4k bytes each).
    const std::string ply = test::read_text(dir / "m.ply");
    ASSERT_EQ(ply.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
    const std::size_t header_end = ply.find("end_header\n") + 11;
    const auto count = [&](const std::string& element) {
        const std::size_t at = ply.find("element " + element + " ");
        return std::stoul(ply.substr(at + 9 + element.size()));
    };
    const std::size_t vertices = count("vertex"), faces = count("face");
    EXPECT_EQ(faces, patches.size());
    std::size_t at = header_end + 27 * vertices, corners = 0;
    for (std::size_t f = 0; f < faces && at < ply.size(); ++f) {
        const auto n = static_cast<unsigned char>(ply[at]);
        ASSERT_TRUE(n == 3 || n == 4);
        corners += n;
        at += 1 + 4 * n;
    }
    EXPECT_EQ(at, ply.size());
    EXPECT_GT(corners, vertices);  // smooth: corners share vertices
    // The PNG exists and is one.
    EXPECT_EQ(test::read_text(dir / "c.png").substr(1, 3), "PNG");
}

TEST(SolveCli, ReflectanceOfOneIsRefusedWithNoOutput) {
    TempDir dir;
    const std::string scene = write_cube(dir, "1 0.5 0.5", "1 1 1");
    const auto r = run_ffcube("solve " + scene + " --max-patch-edge 0.5 --resolution 16 -q --objects " + (dir / "o.csv") +
                              " --report " + (dir / "r.json") + " --render " + (dir / "i.exr") + " --mesh " + (dir / "m.ply"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("steady state"), std::string::npos) << r.output;
    for (const char* f : {"o.csv", "r.json", "i.exr", "m.ply"}) EXPECT_FALSE(std::filesystem::exists(dir / f)) << f;
}

TEST(SolveCli, NoEmittersWarnsAndGivesZero) {
    TempDir dir;
    const std::string scene = write_cube(dir, "0.5 0.5 0.5", "0 0 0");
    const auto r = run_ffcube("solve " + scene + " --max-patch-edge 0.5 --resolution 16 --radiosity " + (dir / "p.csv") +
                              " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("warning"), std::string::npos) << r.output;
    for (const PatchRow& p : read_patch_csv(dir / "p.csv"))
        for (double b : p.B) EXPECT_EQ(b, 0.0);
    const auto rep = nlohmann::json::parse(test::read_text(dir / "r.json"));
    EXPECT_EQ(rep["stop_reason"], "nothing_to_do");
    EXPECT_EQ(rep["row_cache"]["rows_computed"], 0);
}

TEST(SolveCli, BadOptionsAreRefused) {
    TempDir dir;
    for (const std::string& args : {std::string("--render x.jpg"), std::string("--camera 1,2,3"), std::string("--tolerance -1"),
                                    std::string("--overshoot 2.5"), std::string("--solver newton"), std::string("--width 0"),
                                    std::string("--exposure -1"), std::string("--mesh m.obj")}) {
        const auto r = run_ffcube("solve " + test::example("cube.obj") + " --max-patch-edge 0.5 -q " + args);
        EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
    }
}


// Issue 16: a stiff furnace (unit box, 96 patches, ρ = 0.999) converges by default, the report
// says how (the GMRES finish) and bounds the error; a solve stopped before its tolerance exits 5
// with only the report (converged: false), unless --allow-unconverged writes everything.
TEST(SolveCli, StiffFurnaceConvergesAndUnconvergedExitsFive) {
    TempDir dir;
    const std::string scene = write_cube(dir, "0.999 0.999 0.999", "1 1 1");
    const std::string mesh = " --max-patch-edge 0.25 --resolution 64 -q";
    // γ as in SolveFurnace: the received sums of the same rows, so B* for them lies within
    // E/(1 − ρ(1 ± γ)) of 1000.
    ASSERT_EQ(run_ffcube("formfactors " + scene + mesh + " -o " + (dir / "F.ffm")).code, 0);
    const FfmFile f = read_ffm(dir / "F.ffm");
    std::vector<double> received(f.matrix.size(), 0.0);
    for (std::uint32_t i = 0; i < f.matrix.size(); ++i) {
        const RowView row = f.matrix.row(i);
        for (std::size_t k = 0; k < row.col.size(); ++k) received[row.col[k]] += f.areas[i] * row.val[k];
    }
    double gamma = 1e-7;
    for (std::uint32_t j = 0; j < f.matrix.size(); ++j) gamma = std::max(gamma, std::abs(received[j] / f.areas[j] - 1.0));

    const auto ok = run_ffcube("solve " + scene + mesh + " --objects " + (dir / "o.csv") + " --report " + (dir / "r.json"));
    ASSERT_EQ(ok.code, 0) << ok.output;
    const auto rep = nlohmann::json::parse(test::read_text(dir / "r.json"));
    EXPECT_EQ(rep["patches"], 96);
    EXPECT_EQ(rep["converged"], true);
    EXPECT_EQ(rep["stop_reason"], "converged");
    EXPECT_EQ(rep["stiffness"]["action"], "gmres");
    EXPECT_EQ(rep["stiffness"]["stiff"], true);
    EXPECT_EQ(rep["ambient_included"], false);
    const double bound = rep["error_bound"]["relative"];
    EXPECT_LE(bound, 1e-3);
    // Mean radiosity of the box: 1000 up to the rows' γ and the reported bound.
    std::istringstream in(test::read_text(dir / "o.csv"));
    std::string line;
    std::getline(in, line);
    double sum_ab = 0.0, sum_a = 0.0;
    while (std::getline(in, line)) {
        std::vector<std::string> v;
        std::stringstream ss(line);
        for (std::string item; std::getline(ss, item, ',');) v.push_back(item);
        ASSERT_EQ(v.size(), 5u) << line;
        sum_a += std::stod(v[1]);
        sum_ab += std::stod(v[1]) * std::stod(v[3]);
    }
    const double lo = 1.0 / (1.0 - 0.999 * (1.0 - gamma)), hi = 1.0 / (1.0 - 0.999 * (1.0 + gamma));
    EXPECT_GE(sum_ab / sum_a, lo * (1.0 - bound) - 1e-6) << "gamma " << gamma;
    EXPECT_LE(sum_ab / sum_a, hi * (1.0 + bound) + 1e-6) << "gamma " << gamma;

    // Stopped after 50 shots: exit 5, the report only.
    const std::string outputs = " --objects " + (dir / "u.csv") + " --report " + (dir / "u.json");
    const auto refused = run_ffcube("solve " + scene + mesh + " --max-iterations 50" + outputs);
    EXPECT_EQ(refused.code, 5) << refused.output;
    EXPECT_NE(refused.output.find("iteration limit"), std::string::npos) << refused.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "u.csv"));
    ASSERT_TRUE(std::filesystem::exists(dir / "u.json"));
    EXPECT_EQ(nlohmann::json::parse(test::read_text(dir / "u.json"))["converged"], false);

    // --allow-unconverged: everything written, exit 0, the report marked.
    const auto allowed = run_ffcube("solve " + scene + mesh + " --max-iterations 50 --allow-unconverged" + outputs);
    EXPECT_EQ(allowed.code, 0) << allowed.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "u.csv"));
    const auto urep = nlohmann::json::parse(test::read_text(dir / "u.json"));
    EXPECT_EQ(urep["converged"], false);
    EXPECT_EQ(urep["stop_reason"], "iteration_limit");
    EXPECT_GT(double(urep["error_bound"]["relative"]), 0.5);  // 50 shots of 96 at ρ = 0.999: far off
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// Issue 16 part 2 (docs/adaptive.md, "The default within 0.1%"): the built-in Cornell box at the
// default settings, every object's mean luminance within 0.1% of R, the ray caster's reference on
// the L = 15 mesh (two seeds, σ ≈ 0.024%; independent of the hemicube: area-averaged Monte Carlo
// rows). The tolerance is the issue's target itself; the default meets it with 0.086% (the right
// wall) where it was at 0.204% (the tall block) before the covered ceiling patches were measured
// at their exposed points and the emitting rows got the far field. The report says the far field
// ran on the 12 emitting rows only, and --far-field-emitters off turns that off.
TEST(SolveCli, CornellDefaultWithinATenthOfAPercentOfTheRayCastersReference) {
    TempDir dir;
    const auto r = run_ffcube("solve -q --objects " + (dir / "o.csv") + " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const std::map<std::string, double> ref{{"floor", 0.254843},      {"ceiling", 0.208008},     {"back_wall", 0.383158},
                                            {"right_wall", 0.199734}, {"left_wall", 0.116416},   {"short_block", 0.267503},
                                            {"tall_block", 0.339736}};
    std::istringstream in(test::read_text(dir / "o.csv"));
    std::string line;
    std::getline(in, line);
    std::size_t seen = 0;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream ss(line);
        for (std::string item; std::getline(ss, item, ',');) f.push_back(item);
        ASSERT_EQ(f.size(), 5u) << line;
        const auto it = ref.find(f[0]);
        if (it == ref.end()) continue;  // the light
        const double lum = 0.2126 * std::stod(f[2]) + 0.7152 * std::stod(f[3]) + 0.0722 * std::stod(f[4]);
        EXPECT_NEAR(lum / it->second - 1, 0.0, 1e-3) << f[0];
        ++seen;
    }
    EXPECT_EQ(seen, ref.size());
    const auto report = nlohmann::json::parse(test::read_text(dir / "r.json"));
    EXPECT_EQ(report["corrections"]["far_field"].get<std::string>().rfind("on for the 12 emitting rows only", 0), 0u)
        << report["corrections"]["far_field"];
    EXPECT_EQ(report["corrections"]["far_field_rows"], 12);
    EXPECT_EQ(report["sub_hemicube_rows_partly_enclosed"], 12);

    const auto off = run_ffcube("solve -q --far-field-emitters off --report " + (dir / "off.json"));
    ASSERT_EQ(off.code, 0) << off.output;
    const auto report_off = nlohmann::json::parse(test::read_text(dir / "off.json"));
    EXPECT_EQ(report_off["corrections"]["far_field"].get<std::string>().rfind("off", 0), 0u);
    EXPECT_EQ(report_off["corrections"]["far_field_rows"], 0);
}

}  // namespace
}  // namespace ffcube
