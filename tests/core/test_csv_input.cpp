// core/csv_input.hpp: the one reader of the small CSV inputs (S.csv, B.csv, SUN.csv, A.csv,
// --materials). Expected values are written by hand here; numbers are compared with the compiler's
// own reading of the same literal (both round correctly, so they must be equal, not near).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "ffcube/core/csv_input.hpp"
#include "ffcube/core/error.hpp"
#include "support/temp_files.hpp"

namespace ffcube {
namespace {

const std::vector<CsvHeader> kOne = {{"object", "value"}};

const auto message_of = test::input_error_of;

TEST(CsvInput, ReadsBomCrlfCommentsBlanksAndQuotes) {
    // Line 1: BOM + header (CRLF); 2: comment; 3: blank; 4: a quoted name with a comma and a
    // doubled quote; 5: blanks around fields; 6: an indented comment; 7: last line without LF.
    const std::string text =
        "\xEF\xBB\xBFobject,value\r\n# note\r\n\r\n\"wall, \"\"south\"\"\",0.25\r\n  roof ,\t-3e2 \n   # x\nfloor,";
    const CsvTable t = parse_csv(text, "a.csv", kOne);
    ASSERT_EQ(t.rows.size(), 3u);
    EXPECT_EQ(t.header_index, 0u);
    EXPECT_EQ(t.rows[0].line, 4u);
    EXPECT_EQ(t.rows[0].where, "a.csv:4");
    EXPECT_EQ(t.rows[0].fields, (std::vector<std::string>{"wall, \"south\"", "0.25"}));
    EXPECT_EQ(t.rows[0].number(1), 0.25);
    EXPECT_EQ(t.rows[1].line, 5u);
    EXPECT_EQ(t.rows[1].fields, (std::vector<std::string>{"roof", "-3e2"}));
    EXPECT_EQ(t.rows[1].required(1), -300.0);
    EXPECT_EQ(t.rows[2].line, 7u);
    EXPECT_EQ(t.rows[2].fields, (std::vector<std::string>{"floor", ""}));
    EXPECT_FALSE(t.rows[2].number(1).has_value());
    EXPECT_EQ(message_of([&] { t.rows[2].required(1); }), "a.csv:7: value is missing");
    // A header alone: no rows, no error.
    EXPECT_TRUE(parse_csv("object,value\n", "a.csv", kOne).rows.empty());
}

TEST(CsvInput, PicksOneOfSeveralHeaders) {
    const std::vector<CsvHeader> two = {{"time", "a", "b"}, {"time", "x", "y", "z"}};
    const CsvTable t = parse_csv("time,x,y,z\nt0,1,2,3\n", "s.csv", two);
    EXPECT_EQ(t.header_index, 1u);
    ASSERT_EQ(t.rows.size(), 1u);
    EXPECT_EQ(t.rows[0].required(3), 3.0);
    EXPECT_EQ(parse_csv("time,a,b\n", "s.csv", two).header_index, 0u);
    EXPECT_EQ(message_of([&] { parse_csv("time,a\n", "s.csv", two); }),
              "s.csv:1: the first line must be the header 'time,a,b' or 'time,x,y,z'");
    EXPECT_EQ(message_of([&] { parse_csv("# only a comment\n\n", "s.csv", two); }),
              "s.csv: empty; expected the header 'time,a,b' or 'time,x,y,z'");
}

TEST(CsvInput, AnOptionalHeaderIsTheFirstLineNamedByItsFirstColumn) {
    const CsvTable with = parse_csv("# c\nobject,anything\nlamp,1\n", "m.csv", kOne, true);
    ASSERT_EQ(with.rows.size(), 1u);
    EXPECT_EQ(with.rows[0].line, 3u);
    const CsvTable without = parse_csv("lamp,1\nfloor,2\n", "m.csv", kOne, true);
    ASSERT_EQ(without.rows.size(), 2u);
    EXPECT_EQ(without.rows[1].fields[0], "floor");
    EXPECT_EQ(without.rows[1].number(1), 2.0);
    EXPECT_TRUE(parse_csv("", "m.csv", kOne, true).rows.empty());
    // Only the first line can be the header: a later "object" line is a row.
    EXPECT_EQ(parse_csv("lamp,1\nobject,2\n", "m.csv", kOne, true).rows.size(), 2u);
}

TEST(CsvInput, RefusesBadFilesNamingFileLineAndRule) {
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"", "a.csv: empty; expected the header 'object,value'"},
        {"name,value\nx,1\n", "a.csv:1: the first line must be the header 'object,value'"},
        {"object,value,extra\n", "a.csv:1: the first line must be the header 'object,value'"},
        {"object,value\nx\n", "a.csv:2: 1 fields; each line is object,value (2 fields)"},
        {"object,value\n\nx,1,2\n", "a.csv:3: 3 fields; each line is object,value (2 fields)"},
        {"object,value\n\"x,1\n", "a.csv:2: a double quote is not closed"},
    };
    for (const auto& [text, want] : cases)
        EXPECT_EQ(message_of([&] { parse_csv(text, "a.csv", kOne); }), want) << text;
    const std::string nul = std::string("object,value\nx,1\ny,2") + '\0' + "\n";
    EXPECT_EQ(message_of([&] { parse_csv(nul, "a.csv", kOne); }), "a.csv:3: not a CSV file (a NUL byte)");
}

TEST(CsvInput, NumbersAreWholeFiniteFields) {
    const auto num = [](const std::string& f) { return parse_csv_number(f, "value", "a.csv:2"); };
    EXPECT_FALSE(num("").has_value());
    EXPECT_EQ(num("0.1"), 0.1);
    EXPECT_EQ(num("-2.5"), -2.5);
    EXPECT_EQ(num("+3"), 3.0);
    EXPECT_EQ(num(".5"), 0.5);
    EXPECT_EQ(num("5."), 5.0);
    EXPECT_EQ(num("1E-3"), 1e-3);
    EXPECT_EQ(num("6.02214076e23"), 6.02214076e23);
    EXPECT_EQ(num("1.7976931348623157e308"), 1.7976931348623157e308);  // the largest double
    EXPECT_EQ(num("2e-310"), 2e-310);                                   // subnormal
    EXPECT_EQ(num("1e-400"), 0.0);                                      // below every subnormal: 0
    for (const char* bad : {"nan", "NaN", "inf", "-inf", "infinity", "1e400", "-1e309", "0x10", "1.5.2", "300x", "++1",
                            "+-1", "+", "-", "1 2", " 1", "e5", "1e", "--1"})
        EXPECT_EQ(message_of([&] { num(bad); }), fmt::format("a.csv:2: value '{}' is not a finite number", bad)) << bad;
    // A hint after the rule; control bytes shown as '?', long fields cut at 40 characters.
    EXPECT_EQ(message_of([&] { parse_csv_number("x\t", "kd_r", "m.csv:1", "Kd within [0,1)"); }),
              "m.csv:1: kd_r 'x?' is not a finite number (Kd within [0,1))");
    EXPECT_EQ(message_of([&] { num(std::string(50, 'a')); }),
              fmt::format("a.csv:2: value '{}...' is not a finite number", std::string(40, 'a')));
}

TEST(CsvInput, ObjectIndexFindsNamesAndListsTheSceneInItsRefusal) {
    std::vector<std::string> many;
    for (int k = 0; k < 14; ++k) many.push_back(fmt::format("o{}", k));
    const ObjectIndex index(many);
    EXPECT_EQ(index.at("o0", "x.csv:2"), 0u);
    EXPECT_EQ(index.at("o13", "x.csv:2"), 13u);
    EXPECT_EQ(message_of([&] { index.at("q", "x.csv:2"); }),
              "x.csv:2: the scene has no object 'q' (its objects: o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, o11, ...)");
    const std::vector<std::string> two = {"wall, south", "roof"};
    EXPECT_EQ(ObjectIndex(two).at("roof", "a.csv:3"), 1u);
    EXPECT_EQ(message_of([&] { ObjectIndex(two).at("Roof", "a.csv:3"); }),
              "a.csv:3: the scene has no object 'Roof' (its objects: wall, south, roof)");
}

// Mangled files: each is read (every row has the header's field count) or refused with an
// InputError naming the file first; never a crash. 2,000 small texts: well under a second.
TEST(CsvInput, MangledFilesAreReadOrRefused) {
    const std::string good = "object,value\n\"a, b\",1\nc,2.5\n# x\nd,-3\n";
    const std::string alphabet = std::string("0123456789.,-+e\"\n\r #xinfa\xEF\xBB\xBF") + '\0';
    std::mt19937 rng(7);
    std::size_t read = 0, refused = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        std::string text = good;
        for (int e = 0, edits = 1 + static_cast<int>(rng() % 3); e < edits; ++e) {
            const std::size_t at = rng() % (text.size() + 1);
            if (rng() % 2 && at < text.size())
                text[at] = alphabet[rng() % alphabet.size()];
            else
                text.insert(at, 1, alphabet[rng() % alphabet.size()]);
        }
        try {
            for (const CsvRow& row : parse_csv(text, "m.csv", kOne).rows) {
                EXPECT_EQ(row.fields.size(), 2u) << text;
                try {
                    if (const auto v = row.number(1)) {
                        EXPECT_TRUE(std::isfinite(*v)) << text;
                    }
                } catch (const InputError& e) {
                    EXPECT_EQ(std::string(e.what()).rfind(row.where + ": ", 0), 0u) << e.what();
                }
            }
            ++read;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()).rfind("m.csv", 0), 0u) << e.what();
            ++refused;
        }
    }
    EXPECT_GT(read, 100u);
    EXPECT_GT(refused, 100u);
}

}  // namespace
}  // namespace ffcube
