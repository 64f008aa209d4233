// ffcube's own pre-checks of meshes read through Gmsh (scene/gmsh_loader.hpp), in process: what
// a Nastran deck may hold, and one name per physical group of a .msh file.
#include <gtest/gtest.h>

#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/gmsh_loader.hpp"

namespace ffcube {
namespace {

std::string refusal(const auto& check) {
    try {
        check();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

TEST(FePrechecks, NastranDeckWithCaseControlCommentsAndContinuations) {
    const std::string deck = "SOL 101\nCEND\nSUBCASE 1\nBEGIN BULK\n$ a comment\nGRID*   1               0.0             0.0\n"
                             "*       0.0\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nCTRIA3,1,7,1,2,3\nPSHELL,7,1,0.1\n"
                             "MAT1,1,2.1e11,,0.3\nENDDATA\nanything after ENDDATA\n";
    EXPECT_EQ(refusal([&] { check_nastran_cards(deck, "deck.bdf"); }), "");
}

TEST(FePrechecks, NastranCardsGmshWouldSkipAreRefusedWithTheirLine) {
    EXPECT_EQ(refusal([] { check_nastran_cards("GRID,1,,0.,0.,0.\nINCLUDE 'more.bdf'\n", "d.bdf"); }),
              "d.bdf: line 2: card 'INCLUDE' is not read (ffcube reads Nastran's GRID, CTRIA3, CTRIA6, CQUAD4, CQUAD8, CTETRA, "
              "CHEXA, CPENTA, CPYRAM through Gmsh, and passes over properties, materials and loads; coordinate systems and "
              "INCLUDE are not followed)");
    EXPECT_NE(refusal([] { check_nastran_cards("GRID,1,,0.,0.,0.\nCORD2R,9,0,0.,0.,0.\n", "d.bdf"); }).find("line 2: card 'CORD2R'"),
              std::string::npos);
    EXPECT_NE(refusal([] { check_nastran_cards("$ only comments\n", "d.bdf"); }).find("no GRID or element cards"), std::string::npos);
    EXPECT_NE(refusal([] { check_nastran_cards(std::string("GRID,1\n\0", 8), "d.bdf"); }).find("control byte"), std::string::npos);
}

TEST(FePrechecks, PhysicalGroupNamesMustDifferWithinADimension) {
    const std::string head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n";
    EXPECT_EQ(refusal([&] { check_msh_physical_names(head + "2 1 \"a\"\n2 2 \"b\"\n3 3 \"a\"\n$EndPhysicalNames\n", "m.msh"); }), "");
    EXPECT_EQ(refusal([&] { check_msh_physical_names(head + "2 1 \"a\"\n2 2 \"b\"\n2 3 \"a\"\n$EndPhysicalNames\n", "m.msh"); }),
              "m.msh: line 8: the physical group name \"a\" is used twice (also line 6); each group needs its own name");
    EXPECT_NE(refusal([&] { check_msh_physical_names(head + "2 1 \"a\"\n", "m.msh"); }).find("no $EndPhysicalNames"),
              std::string::npos);
}

}  // namespace
}  // namespace ffcube
