#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/io/report.hpp"
#include "io/io_test_util.hpp"

namespace ffcube::test {
namespace {

TEST(Report, DottedKeysMakeNestedObjectsInInsertionOrder) {
    Report r;
    r.set("patches", 5000);
    r.set("time.meshing", 0.5);
    r.set("backend", "egl");
    r.set("time.drawing", 1.25);
    r.set("rows.sum.min", 0.97);
    r.set("quiet", false);
    EXPECT_EQ(r.dump(),
              "{\n"
              "  \"patches\": 5000,\n"
              "  \"time\": {\n"
              "    \"meshing\": 0.5,\n"
              "    \"drawing\": 1.25\n"
              "  },\n"
              "  \"backend\": \"egl\",\n"
              "  \"rows\": {\n"
              "    \"sum\": {\n"
              "      \"min\": 0.97\n"
              "    }\n"
              "  },\n"
              "  \"quiet\": false\n"
              "}\n");
}

TEST(Report, NonFiniteNumbersBecomeNull) {
    Report r;
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    r.set("a", nan);
    r.set("b", -inf);
    r.set_array("c", std::vector<double>{1.0, inf, nan, 0.1});
    const auto j = nlohmann::json::parse(r.dump());
    EXPECT_TRUE(j["a"].is_null());
    EXPECT_TRUE(j["b"].is_null());
    ASSERT_EQ(j["c"].size(), 4u);
    EXPECT_EQ(j["c"][0].get<double>(), 1.0);
    EXPECT_TRUE(j["c"][1].is_null());
    EXPECT_TRUE(j["c"][2].is_null());
    EXPECT_EQ(j["c"][3].get<double>(), 0.1);  // shortest round-trip text: reads back exactly
}

TEST(Report, EveryValueTypeKeepsItsType) {
    Report r;
    r.set("int", -7);
    r.set("u32", std::uint32_t{4000000000u});
    r.set("size", std::size_t{12});
    r.set("i64min", std::numeric_limits<std::int64_t>::min());
    r.set("u64max", std::numeric_limits<std::uint64_t>::max());
    r.set("literal", "text");  // a string, not a bool (const char* → bool is a standard conversion)
    r.set("string", std::string("s"));
    r.set("flag", true);
    r.set("float", 0.1f);
    r.set_array("counts", std::vector<std::uint64_t>{1, 2, 3});
    r.set_array("signed", std::vector<std::int64_t>{-1, 2});
    r.set_array("names", std::vector<std::string>{"a", "b,c"});
    const auto j = nlohmann::json::parse(r.dump());
    EXPECT_EQ(j["int"].get<std::int64_t>(), -7);
    EXPECT_EQ(j["u32"].get<std::uint64_t>(), 4000000000u);
    EXPECT_EQ(j["size"].get<std::uint64_t>(), 12u);
    EXPECT_EQ(j["i64min"].get<std::int64_t>(), std::numeric_limits<std::int64_t>::min());
    EXPECT_EQ(j["u64max"].get<std::uint64_t>(), std::numeric_limits<std::uint64_t>::max());
    EXPECT_EQ(j["literal"], "text");
    EXPECT_EQ(j["string"], "s");
    EXPECT_EQ(j["flag"], true);
    EXPECT_EQ(j["float"].get<double>(), static_cast<double>(0.1f));
    EXPECT_EQ(j["counts"], nlohmann::json::parse("[1,2,3]"));
    EXPECT_EQ(j["signed"], nlohmann::json::parse("[-1,2]"));
    EXPECT_EQ(j["names"], nlohmann::json::parse("[\"a\",\"b,c\"]"));
}

TEST(Report, SettingAgainReplacesInPlace) {
    Report r;
    r.set("a", 1);
    r.set("b", 2);
    r.set("a", "one");
    EXPECT_EQ(r.dump(), "{\n  \"a\": \"one\",\n  \"b\": 2\n}\n");
    EXPECT_TRUE(r.contains("a"));
    EXPECT_FALSE(r.contains("a.b"));
    EXPECT_FALSE(r.contains("c"));
}

TEST(Report, MalformedKeysAreProgrammingErrors) {
    Report r;
    r.set("x", 1.0);
    EXPECT_THROW(r.set("x.y", 2.0), InternalError);  // x holds a number, not an object
    EXPECT_THROW(r.set("", 2.0), InternalError);
    EXPECT_THROW(r.set("a..b", 2.0), InternalError);
    EXPECT_THROW(r.set("a.", 2.0), InternalError);
    EXPECT_EQ(r.dump(), "{\n  \"x\": 1.0\n}\n");  // nothing half-made by the refused keys
}

TEST(Report, InvalidUtf8IsReplacedNotThrown) {
    Report r;
    r.set("name", std::string("caf\xe9"));  // Latin-1 é
    const std::string text = r.dump();
    EXPECT_TRUE(nlohmann::json::accept(text));
    EXPECT_NE(text.find("caf\xef\xbf\xbd"), std::string::npos) << text;  // U+FFFD
}

using ReportFile = ScratchDir;

TEST_F(ReportFile, WriteGivesTheDump) {
    Report r;
    r.set("time.writing", 0.01);
    r.write(path("R.json"));
    EXPECT_EQ(read_all(path("R.json")), r.dump());
    EXPECT_EQ(entries().size(), 1u);
}

}  // namespace
}  // namespace ffcube::test
