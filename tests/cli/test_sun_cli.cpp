// ffcube sun: a box on a plane against the closed form of its shadow (support/box_shadow.hpp),
// per patch and --by object, with --sun and --sun-direction; a generated city (no fraction
// outside [0, 1], no more sunlit projected area than the beam crossing the city's bounding box);
// the refusals (exit 2 naming the option, no output).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/cli_util.hpp"
#include "support/box_shadow.hpp"

namespace ffcube::test {
namespace {

// The exact fraction of each face for the sun s (n·s ≤ 1e-9: 0, as gl/sun.hpp).
std::map<std::string, double> exact(const std::array<double, 3>& s) {
    const auto lit = [&](double nx, double ny, double nz) { return nx * s[0] + ny * s[1] + nz * s[2] > 1e-9 ? 1.0 : 0.0; };
    return {{"ground", 1.0 - box_shadow_on_ground(s[0], s[1], s[2]) / 100.0},
            {"roof", lit(0, 0, 1)},
            {"south", lit(0, -1, 0)},
            {"east", lit(1, 0, 0)},
            {"north", lit(0, 1, 0)},
            {"west", lit(-1, 0, 0)}};
}

// Tolerance 1e-3 (the issue's): the worst-case bound of a pixel count, perimeter × pixel / projected
// area, is 5e-3 … 1.6e-2 at the default pixel budget for the grazing suns (tests/gl/test_sun.cpp
// derives it), but the grid turned by the golden angle keeps the measured errors near 1e-5.
TEST(SunCli, BoxOnPlaneByObjectMatchesTheAnalyticShadow) {
    TempDir dir;
    write_file(dir / "box.obj", kBoxOnPlane);
    for (const auto& [az, el] : {std::array<double, 2>{37, 5}, {200, 10}, {290, 30}, {0, 90}}) {
        const std::string out = dir / "o.csv";
        const RunResult r = run_ffcube("sun " + (dir / "box.obj") + " --no-subdivide -q --by object -o " + out + " --sun " +
                                       std::to_string(az) + "," + std::to_string(el));
        ASSERT_EQ(r.code, 0) << r.output;
        const std::string text = read_text(out);
        ASSERT_EQ(text.substr(0, text.find('\n')), "object,area,sunlit_fraction");
        const auto got = last_column_by_first(text);
        for (const auto& [name, want] : exact(sun_from_angles(az, el))) {
            ASSERT_TRUE(got.count(name)) << name;
            EXPECT_NEAR(got.at(name), want, 1e-3) << "sun " << az << "," << el << " " << name;
        }
    }
}

// Both methods: the shadow polygons (the default, exact) and the item buffer (--set sun-method=pixels).
TEST(SunCli, DirectionPerPatchAndReport) {
    TempDir dir;
    write_file(dir / "box.obj", kBoxOnPlane);
    for (const std::string method : {"clip", "pixels"}) {
    // Towards the sun (1, −2, 2)/3 (not unit on the command line).
    const RunResult r = run_ffcube("sun " + (dir / "box.obj") + " --no-subdivide -q --sun-direction 1,-2,2 -o " +
                                   (dir / "p.csv") + " --report " + (dir / "r.json") + " --set sun-method=" + method);
    ASSERT_EQ(r.code, 0) << r.output;
    std::istringstream in(read_text(dir / "p.csv"));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "patch,object,area,sunlit_fraction");
    const auto want = exact({1.0 / 3, -2.0 / 3, 2.0 / 3});
    int rows = 0;
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        std::string patch, object, area, fraction;
        std::getline(ls, patch, ',');
        std::getline(ls, object, ',');
        std::getline(ls, area, ',');
        std::getline(ls, fraction, ',');
        EXPECT_EQ(patch, std::to_string(rows));
        EXPECT_NEAR(std::stod(fraction), want.at(object), 1e-3) << object << " " << method;
        ++rows;
    }
    EXPECT_EQ(rows, 6);
    const auto j = nlohmann::json::parse(read_text(dir / "r.json"));
    EXPECT_EQ(j["method"].get<std::string>(), method);
    if (method == "pixels") {
        EXPECT_GT(j["pixel"]["size"].get<double>(), 0.0);
        EXPECT_GE(j["tiles"]["u"].get<int>(), 1);
    } else {
        EXPECT_FALSE(j.contains("pixel"));
    }
    EXPECT_TRUE(j["clamps"].contains("count"));
    EXPECT_TRUE(j["time"].contains("sun"));
    EXPECT_NEAR(j["sun_direction"][1].get<double>(), -2.0 / 3, 1e-15);
    }
}

// A View3D obstruction-only surface (O) shades but has no line of its own: the ground [−2,2]² under
// a unit awning at z = 1, drawn facing down (its back faces the sun: back faces block). Its
// shadow is the unit square moved by −(s_x, s_y)/s_z, wholly on the ground for this sun: the
// ground's fraction is 1 − 1/16 exactly (tolerance as above).
TEST(SunCli, ObstructionOnlySurfacesShadeButAreNotListed) {
    TempDir dir;
    write_file(dir / "awning.vs3", R"(T ground under an obstruction-only awning
C encl=0 emit=0
F 3
V 1 -2 -2 0
V 2 2 -2 0
V 3 2 2 0
V 4 -2 2 0
V 5 0 0 1
V 6 0 1 1
V 7 1 1 1
V 8 1 0 1
S 1 1 2 3 4 0 0 0.9 ground
O 2 5 6 7 8 0 0 0.9 awning
End of data
)");
    const RunResult r =
        run_ffcube("sun " + (dir / "awning.vs3") + " --no-subdivide -q --sun 200,45 --by object -o " + (dir / "o.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto got = last_column_by_first(read_text(dir / "o.csv"));
    ASSERT_EQ(got.size(), 1u) << read_text(dir / "o.csv");
    EXPECT_NEAR(got.at("ground"), 1.0 - 1.0 / 16.0, 1e-3);
}

// The beam through the city's axis-aligned bounding box (extents a, b, c) has the cross-section
// |s_x| b c + |s_y| a c + |s_z| a b: no set of facets inside the box can intercept more of it.
TEST(SunCli, CityFractionsStayInRangeAndCreateNoEnergy) {
    TempDir dir;
    const std::string city = dir / "city.stl";
    ASSERT_EQ(gen_city(city, 2000, 1), 0);
    // The bounding box from the binary STL itself (80-byte header, count, 50 bytes a facet).
    std::ifstream stl(city, std::ios::binary);
    char header[80];
    std::uint32_t n = 0;
    stl.read(header, 80);
    stl.read(reinterpret_cast<char*>(&n), 4);
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (std::uint32_t t = 0; t < n; ++t) {
        float f[12];
        char attr[2];
        stl.read(reinterpret_cast<char*>(f), sizeof f);
        stl.read(attr, 2);
        for (int v = 1; v < 4; ++v)
            for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], double(f[3 * v + k])), hi[k] = std::max(hi[k], double(f[3 * v + k]));
    }
    ASSERT_TRUE(stl) << "short STL";
    const double a = hi[0] - lo[0], b = hi[1] - lo[1], c = hi[2] - lo[2];
    for (const auto& [az, el] : {std::array<double, 2>{135, 35}, {260, 8}}) {
        const auto s = sun_from_angles(az, el);
        const RunResult r = run_ffcube("sun " + city + " --no-subdivide -q -o " + (dir / "s.csv") + " --report " +
                                       (dir / "r.json") + " --sun " + std::to_string(az) + "," + std::to_string(el));
        ASSERT_EQ(r.code, 0) << r.output;
        std::istringstream in(read_text(dir / "s.csv"));
        std::string line;
        std::getline(in, line);
        std::size_t rows = 0, lit = 0;
        double area_lit = 0;
        while (std::getline(in, line)) {
            const double area = std::stod(line.substr(line.find(',', line.find(',') + 1) + 1));
            const double f = std::stod(line.substr(line.rfind(',') + 1));
            EXPECT_GE(f, 0.0) << line;
            EXPECT_LE(f, 1.0) << line;
            lit += f > 0 ? 1 : 0;
            area_lit += area * f;
            ++rows;
        }
        EXPECT_EQ(rows, 2000u);
        EXPECT_GT(lit, 100u);
        const auto j = nlohmann::json::parse(read_text(dir / "r.json"));
        const double sunlit = j["sunlit_projected_area"].get<double>();
        const double beam = std::abs(s[0]) * b * c + std::abs(s[1]) * a * c + std::abs(s[2]) * a * b;
        // Every beam line that meets z = 0 inside the footprint meets the ground (which covers it, gen_city.py)
        // or something above it first: at least the footprint's cross-section s_z a b is intercepted.
        const double footprint = s[2] * a * b;
        // The pixel h: 0 for the default shadow polygons (exact, no "pixel" in the report).
        const double h = j.contains("pixel") ? j["pixel"]["size"].get<double>() : 0.0;
        std::printf("city, sun %g,%g: sunlit projected area %.6g, footprint's beam %.6g, beam through the bounding box "
                    "%.6g, sunlit area %.6g, %d clamped (largest overshoot %.2e), pixel %.3g\n",
                    az, el, sunlit, footprint, beam, area_lit, j["clamps"]["count"].get<int>(),
                    j["clamps"]["max_overshoot"].get<double>(), h);
        EXPECT_GT(sunlit, 0.0);
        EXPECT_LE(sunlit, beam);
        // The pixel counts' error over the footprint's outline (perimeter 2(a + b), pixel h): 2(a + b) h.
        EXPECT_GE(sunlit, footprint - 2 * (a + b) * h);
    }
}

TEST(SunCli, BadInputExitsTwoNamingTheOptionAndWritesNothing) {
    TempDir dir;
    write_file(dir / "box.obj", kBoxOnPlane);
    const std::string base = "sun " + (dir / "box.obj") + " --no-subdivide -o " + (dir / "o.csv") + " --report " + (dir / "r.json");
    const std::pair<std::string, std::string> cases[] = {
        {" --sun-direction 0,0,0", "--sun-direction"},
        {" --sun-direction 1,nan,1", "--sun-direction"},
        {" --sun-direction 1,inf,1", "--sun-direction"},
        {" --sun-direction 1,2", "--sun-direction"},
        {" --sun-direction 1,x,2", "--sun-direction"},
        {" --sun 10,95", "--sun"},
        {" --sun 10,-90.5", "--sun"},
        {" --sun 10", "--sun"},
        {" --sun nan,30", "--sun"},
        {"", "--sun"},
        {" --sun 10,30 --sun-direction 0,0,1", "--sun"},
        {" --sun 10,30 --by floor", "--by"},
        {" --sun 10,30 --set tolerance=0", "--tolerance"},
        {" --sun 10,30 --set max-pixels=0", "--max-pixels"},
        {" --sun 10,30 --set sun-method=raster", "--sun-method"},
    };
    for (const auto& [args, option] : cases) {
        const RunResult r = run_ffcube(base + args);
        EXPECT_EQ(r.code, 2) << args << ": " << r.output;
        EXPECT_NE(r.output.find(option), std::string::npos) << args << ": " << r.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "o.csv")) << args;
        EXPECT_FALSE(std::filesystem::exists(dir / "r.json")) << args;
    }
}

TEST(SunCli, SameInputSameBytes) {
    TempDir dir;
    write_file(dir / "box.obj", kBoxOnPlane);
    std::string first;
    for (int k = 0; k < 2; ++k) {
        const RunResult r = run_ffcube("sun " + (dir / "box.obj") + " -q --sun 123,45 --set max-pixels=4000000 -o " +
                                       (dir / "o.csv"));
        ASSERT_EQ(r.code, 0) << r.output;
        if (k == 0)
            first = read_text(dir / "o.csv");
        else
            EXPECT_EQ(read_text(dir / "o.csv"), first);
    }
}

}  // namespace
}  // namespace ffcube::test
