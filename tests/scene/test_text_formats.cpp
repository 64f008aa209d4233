// The line tokenizer shared by the ASCII STL and View3D readers (src/scene/text_lines.hpp), and
// the View3D control keys: honoured (encl, emit, out), ignored with a warning and a record
// (eps, maxU, maxO, minO, row, col, list, unknown keys), refused when out of range.
#include <gtest/gtest.h>

#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/stl_loader.hpp"
#include "ffcube/scene/vs3_loader.hpp"
#include "scene/text_lines.hpp"

namespace ffcube {
namespace {

const char* kSquare = "V 1 0 0 0\nV 2 1 0 0\nV 3 1 1 0\nS 1 1 2 3 0 0 0 0.9 tri\n";

std::string thrown(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "(nothing thrown)";
}

TEST(LineReader, CommentsBomBlanksAndControlBytes) {
    const std::string source = "f.txt";
    detail::LineReader r("\xEF\xBB\xBF  a b ! c\r\n\tx/y\n", source, "!/", "binary?");
    std::string_view line, t;
    ASSERT_TRUE(r.next(line));
    EXPECT_EQ(r.line_number(), 1u);
    ASSERT_TRUE(r.token(line, t));
    EXPECT_EQ(t, "a");
    ASSERT_TRUE(r.token(line, t));
    EXPECT_EQ(t, "b");
    EXPECT_FALSE(r.token(line, t));  // "! c\r" is a comment
    ASSERT_TRUE(r.next(line));
    ASSERT_TRUE(r.token(line, t));
    EXPECT_EQ(t, "x");  // '/' starts a comment too
    EXPECT_FALSE(r.token(line, t));
    ASSERT_TRUE(r.next(line));  // the empty text after the last '\n'
    EXPECT_FALSE(r.next(line));

    detail::LineReader bad("ok\nbad\x01\n", source, "", "not text (control bytes)");
    ASSERT_TRUE(bad.next(line));
    EXPECT_EQ(thrown([&] { bad.next(line); }), "f.txt:2: not text (control bytes)");

    detail::LineReader numbers("1.5 x\n", source, "", "-");
    ASSERT_TRUE(numbers.next(line));
    EXPECT_EQ(numbers.number(line, "a coordinate"), 1.5);
    EXPECT_NE(thrown([&] { numbers.no_more(line, "one number only"); }).find("f.txt:1: one number only, found 'x'"),
              std::string::npos);
}

TEST(LineReader, TheStlAndView3dReadersShareIt) {
    // The same tokenizer rules in both: a token over 4096 bytes is refused naming the line.
    const std::string long_token(5000, 'a');
    EXPECT_NE(thrown([&] { parse_vs3("T t\n" + long_token + "\n", "l.vs3"); }).find("l.vs3:2: a token of 5000 bytes"),
              std::string::npos);
    EXPECT_NE(thrown([&] { parse_stl("solid s\n" + long_token + "\n", "l.stl", "l"); }).find("l.stl:2: a token of 5000 bytes"),
              std::string::npos);
}

TEST(View3dControls, HonouredKeysAreRecorded) {
    const ObjModel m = parse_vs3(std::string("T first\nT the title\nC encl=1 emit=1 out=1\n") + kSquare, "c.vs3");
    EXPECT_TRUE(m.view3d.present);
    EXPECT_EQ(m.view3d.encl, 1);
    EXPECT_EQ(m.view3d.emit, 1);
    EXPECT_EQ(m.view3d.out, 1);
    EXPECT_EQ(m.view3d.title, "the title");  // the last T line wins
    EXPECT_TRUE(m.view3d.ignored.empty());
    EXPECT_TRUE(m.warnings.empty() || m.warnings[0].find("control") == std::string::npos);
}

TEST(View3dControls, IgnoredKeysWarnAndAreListed) {
    // row=0, col=0, list=0 are View3D's defaults (every row, every column): nothing is ignored.
    const ObjModel m = parse_vs3(std::string("F 3\nC eps=1e-6 maxU=10 maxO=8 minO=0 row=0 col=0 list=0\nC row=2 foo=3\n") + kSquare,
                                 "c.vs3");
    // eps is honoured as the accuracy target (--tolerance); the other accuracy keys are not.
    ASSERT_EQ(m.view3d.ignored.size(), 5u);
    EXPECT_EQ(m.view3d.eps, 1e-6);
    EXPECT_EQ(m.view3d.ignored[0].rfind("maxU=10: ", 0), 0u) << m.view3d.ignored[0];
    EXPECT_EQ(m.view3d.ignored[3].rfind("row=2: ffcube computes every row", 0), 0u) << m.view3d.ignored[3];
    EXPECT_EQ(m.view3d.ignored[4], "'foo'=3: unknown control key");
    // row, col and maxD are recorded with their line: `ffcube view3d` refuses row and col and
    // applies maxD; the other commands warn that they ignore them (apply_view3d_controls).
    EXPECT_EQ(m.view3d.row, 2);
    EXPECT_EQ(m.view3d.row_line, 3u);
    for (const auto& w : m.warnings) EXPECT_EQ(w.find("row=2"), std::string::npos) << w;
    bool warned = false;
    for (const auto& w : m.warnings) warned |= w.find("c.vs3:2: control maxU=10 is ignored") != std::string::npos;
    EXPECT_TRUE(warned);
    const ObjModel d = parse_vs3(std::string("C out=2 maxD=96.0 row=0 col=0\n") + kSquare, "d.vs3");
    EXPECT_EQ(d.view3d.out, 2);
    EXPECT_EQ(d.view3d.max_distance, 96.0);
    EXPECT_EQ(d.view3d.max_distance_line, 1u);
    EXPECT_EQ(d.view3d.row, 0);
    ASSERT_EQ(d.view3d.ignored.size(), 1u);  // for the commands other than view3d
    EXPECT_EQ(d.view3d.ignored[0].rfind("maxD=96: ", 0), 0u) << d.view3d.ignored[0];
    // An STL file has no View3D controls.
    const ObjModel stl = parse_stl("solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                                   "endloop\nendfacet\nendsolid s\n",
                                   "s.stl", "s");
    EXPECT_FALSE(stl.view3d.present);
}

TEST(View3dControls, OutOfRangeValuesAreRefusedNamingTheLine) {
    EXPECT_EQ(thrown([&] { parse_vs3(std::string("T t\nC encl=2\n") + kSquare, "c.vs3"); }), "c.vs3:2: control encl=2 must be 0 or 1");
    EXPECT_EQ(thrown([&] { parse_vs3(std::string("C out=0.5\n") + kSquare, "c.vs3"); }),
              "c.vs3:1: control out=0.5 must be 0, 1 or 2 (0 text, 1 binary, 2 sparse text)");
    EXPECT_EQ(thrown([&] { parse_vs3(std::string("T t\nC col=4\n") + kSquare, "c.vs3"); }),
              "c.vs3:2: control col=4 needs row (View3D: \"Must set row before setting column\")");
    EXPECT_EQ(thrown([&] { parse_vs3(std::string("C maxD=-1\n") + kSquare, "c.vs3"); }).rfind("c.vs3:1: control maxD=-1 must be > 0", 0),
              0u);
}

}  // namespace
}  // namespace ffcube
