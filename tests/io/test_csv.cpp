#include <fmt/format.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "ffcube/formfactor/checks.hpp"
#include "ffcube/io/csv.hpp"
#include "io/io_test_util.hpp"

namespace ffcube::test {
namespace {

TEST(CsvField, QuotesOnlyWhatRfc4180Requires) {
    EXPECT_EQ(csv_field("floor"), "floor");
    EXPECT_EQ(csv_field("back wall"), "back wall");  // spaces are part of a field, no quotes needed
    EXPECT_EQ(csv_field(""), "");
    EXPECT_EQ(csv_field("light, ceiling"), "\"light, ceiling\"");
    EXPECT_EQ(csv_field("wall \"A\""), "\"wall \"\"A\"\"\"");
    EXPECT_EQ(csv_field("\""), "\"\"\"\"");
    EXPECT_EQ(csv_field("two\nlines"), "\"two\nlines\"");
    EXPECT_EQ(csv_field("cr\rhere"), "\"cr\rhere\"");
}

using Csv = ScratchDir;

// G for small_scene()/small_matrix() by hand (G[a][b] = Σ_{i∈a} A_i Σ_{j∈b} F_ij / Σ_{i∈a} A_i):
//   object 0 = patches 0 (A 1), 1 (A 0.5), area 1.5
//     patch 0: to obj0 F01 = 1/3f, obj1 F02 = 0.1f, obj2 F04 = 1e-7f
//     patch 1: to obj0 F10 = 0.2f, obj2 F13 = 0.7f
//     G00 = (1/3f + 0.5·0.2f)/1.5, G01 = 0.1f/1.5, G02 = (1e-7f + 0.5·0.7f)/1.5
//   object 1 = patch 2 (A 0.25): G10 = F20 + F21 = 0.123456789f + 2/7f, G12 = F23 + F24 = 1.5, G11 = 0
//   object 2 = patches 3 (A 2, empty row), 4 (A 0.125): G21 = 0.125·0.99999994f/2.125, G20 = G22 = 0
TEST_F(Csv, GroupsFileListsPositivePairsWithQuotedNames) {
    const Scene scene = small_scene();
    const auto G = object_form_factors(small_matrix(), scene);
    write_groups_csv(path("G.csv"), G, scene.objects);

    const double f = 1.0;  // makes the float → double promotions below explicit
    const double g00 = (f * (1.0f / 3.0f) + 0.5 * 0.2f) / 1.5, g01 = f * 0.1f / 1.5,
                 g02 = (f * 1e-7f + 0.5 * 0.7f) / 1.5;
    const double g10 = f * 0.123456789f + f * (2.0f / 7.0f), g12 = 1.5;
    const double g21 = 0.125 * 0.99999994f / 2.125;
    const std::string expected = fmt::format(
        "from,to,F\n"
        "floor,floor,{:.9g}\n"
        "floor,\"light, ceiling\",{:.9g}\n"
        "floor,\"wall \"\"A\"\"\",{:.9g}\n"
        "\"light, ceiling\",floor,{:.9g}\n"
        "\"light, ceiling\",\"wall \"\"A\"\"\",{:.9g}\n"
        "\"wall \"\"A\"\"\",\"light, ceiling\",{:.9g}\n",
        g00, g01, g02, g10, g12, g21);
    EXPECT_EQ(read_all(path("G.csv")), expected);
}

TEST_F(Csv, ObjectRadiosityFile) {
    const std::vector<std::string> names = {"light", "a,b"};
    const std::vector<double> area = {0.25, 3.0};
    const std::vector<Vec3> B = {{17.0, 12.0, 4.0}, {0.1, 1.0 / 3.0, 0.0}};
    write_object_radiosity_csv(path("O.csv"), names, area, B);
    EXPECT_EQ(read_all(path("O.csv")),
              "object,area,B_r,B_g,B_b\n"
              "light,0.25,17,12,4\n"
              "\"a,b\",3,0.1,0.333333333,0\n");
}

TEST_F(Csv, PatchRadiosityFile) {
    const std::vector<std::string> names = {"floor", "say \"hi\""};
    const std::vector<std::uint32_t> object = {1, 0, 1};
    const std::vector<double> area = {0.5, 1e-6, 2.0};
    const std::vector<Vec3> B = {{1.0, 2.0, 3.0}, {0.0, 0.0, 0.0}, {1e10, 2.5e-12, 123456789.0}};
    write_patch_radiosity_csv(path("P.csv"), object, area, B, names);
    EXPECT_EQ(read_all(path("P.csv")),
              "patch,object,area,B_r,B_g,B_b\n"
              "0,\"say \"\"hi\"\"\",0.5,1,2,3\n"
              "1,floor,1e-06,0,0,0\n"
              "2,\"say \"\"hi\"\"\",2,1e+10,2.5e-12,123456789\n");
}

}  // namespace
}  // namespace ffcube::test
