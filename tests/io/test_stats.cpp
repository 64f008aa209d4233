// The statistics facility (core/stats.hpp): a set declared here, as a provider declares its own,
// merged by its rules, flattened and read back, and written to a Report by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "ffcube/core/stats.hpp"
#include "ffcube/io/report.hpp"

namespace ffcube::test {
namespace {

inline constexpr std::array<std::string_view, 3> kSides{"left", "middle", "right"};
using Sides = stats::PerPart<std::uint64_t, 3, kSides>;

#define FFCUBE_TEST_STATS(X)                                    \
    X(std::uint64_t, rows, sum, "test.rows")                    \
    X(double, seconds, sum, "time.test")                        \
    X(double, worst, max, "test.worst_change")                  \
    X(double, least, min, "test.least_sum")                     \
    X(std::uint64_t, fewest, min, "test.fewest")                \
    X(Sides, per_side, sum, "test.per_side")                    \
    X(double, hidden, sum, "")

struct TestStats {
    FFCUBE_STATS(TestStats, FFCUBE_TEST_STATS)
};

TEST(Stats, StartAtTheIdentityOfTheirRule) {
    const TestStats s;
    EXPECT_EQ(s.rows, 0u);
    EXPECT_EQ(s.seconds, 0.0);
    EXPECT_EQ(s.worst, 0.0);
    EXPECT_EQ(s.least, std::numeric_limits<double>::infinity());
    EXPECT_EQ(s.fewest, std::numeric_limits<std::uint64_t>::max());
    EXPECT_EQ(s.per_side, (Sides{{0, 0, 0}}));
    // So merging into a fresh set copies the other.
    TestStats a, b;
    b.rows = 7;
    b.least = -2.5;
    b.fewest = 3;
    b.worst = 0.25;
    b.per_side[2] = 9;
    stats::merge(a, b);
    EXPECT_EQ(stats::to_words(a), stats::to_words(b));
}

TEST(Stats, MergeAddsSumsAndKeepsTheLargestAndTheSmallest) {
    TestStats a, b;
    a.rows = 5;
    b.rows = 11;
    a.seconds = 0.5;  // 0.5 + 0.25 is exact in binary
    b.seconds = 0.25;
    a.worst = 0.125;
    b.worst = 0.0625;
    a.least = 0.9;
    b.least = 0.7;
    a.fewest = 4;
    b.fewest = 40;
    a.per_side = Sides{{1, 2, 3}};
    b.per_side = Sides{{10, 20, 30}};
    a.hidden = 1;
    b.hidden = 2;
    stats::merge(a, b);
    EXPECT_EQ(a.rows, 16u);
    EXPECT_EQ(a.seconds, 0.75);
    EXPECT_EQ(a.worst, 0.125);
    EXPECT_EQ(a.least, 0.7);
    EXPECT_EQ(a.fewest, 4u);
    EXPECT_EQ(a.per_side, (Sides{{11, 22, 33}}));
    EXPECT_EQ(a.hidden, 3.0);  // merged like the others: only the report leaves it out
}

// Sets counted on several threads and merged under a lock, in whatever order the threads end,
// give the totals counted by hand: sums of 1..n, and the extremes of the values seen.
TEST(Stats, MergedAcrossThreadsGiveTheTotals) {
    constexpr std::uint64_t n = 4000;
    constexpr unsigned threads = 4;
    TestStats total;
    std::mutex m;
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
            TestStats local;
            for (std::uint64_t i = 1 + t; i <= n; i += threads) {
                local.rows += i;
                local.worst = std::max(local.worst, static_cast<double>(i));
                local.fewest = std::min(local.fewest, i);
                ++local.per_side[i % 3];
            }
            const std::lock_guard lock(m);
            stats::merge(total, local);
        });
    for (std::thread& th : pool) th.join();
    EXPECT_EQ(total.rows, n * (n + 1) / 2);
    EXPECT_EQ(total.worst, static_cast<double>(n));
    EXPECT_EQ(total.fewest, 1u);
    // i % 3 == 0 for i = 3, 6, ..., 3999: 1333 of 1..4000; == 1 for 1, 4, ..., 4000: 1334; == 2: 1333.
    EXPECT_EQ(total.per_side, (Sides{{1333, 1334, 1333}}));
    EXPECT_EQ(total.least, std::numeric_limits<double>::infinity());  // never counted
}

TEST(Stats, FlatFormIsOneWordAValueInDeclarationOrderAndReadsBackExactly) {
    // 5 scalars, a PerPart of 3, and the unreported one: 9 words.
    static_assert(stats::words<TestStats>() == 9);
    constexpr auto rules = stats::word_rules<TestStats>();
    EXPECT_EQ(rules[0], stats::Merge::sum);
    EXPECT_EQ(rules[2], stats::Merge::max);
    EXPECT_EQ(rules[3], stats::Merge::min);
    EXPECT_EQ(rules[5], stats::Merge::sum);  // the parts
    EXPECT_EQ(rules[7], stats::Merge::sum);
    TestStats s;
    s.rows = std::numeric_limits<std::uint64_t>::max();  // not representable as a double
    s.seconds = 0.1;
    s.worst = -0.0;
    s.least = std::numeric_limits<double>::infinity();
    s.fewest = (std::uint64_t{1} << 53) + 1;
    s.per_side = Sides{{1, 0, std::uint64_t{1} << 60}};
    s.hidden = std::nextafter(1.0, 2.0);
    const auto w = stats::to_words(s);
    EXPECT_EQ(w[0], s.rows);
    EXPECT_EQ(w[1], std::bit_cast<std::uint64_t>(0.1));
    EXPECT_EQ(w[7], std::uint64_t{1} << 60);
    const TestStats back = stats::from_words<TestStats>(w);
    EXPECT_EQ(back.rows, s.rows);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(back.seconds), std::bit_cast<std::uint64_t>(s.seconds));
    EXPECT_TRUE(std::signbit(back.worst));  // -0.0 kept, not turned into +0.0
    EXPECT_EQ(back.least, s.least);
    EXPECT_EQ(back.fewest, s.fewest);
    EXPECT_EQ(back.per_side, s.per_side);
    EXPECT_EQ(back.hidden, s.hidden);
}

TEST(Stats, ReportWritesEveryKeyedMemberByName) {
    TestStats s;
    s.rows = 42;
    s.seconds = 1.5;
    s.worst = 0.25;
    s.least = 0.875;
    s.fewest = 2;
    s.per_side = Sides{{4, 5, 6}};
    s.hidden = 99;
    Report r;
    stats::report(r, s);
    const nlohmann::json j = nlohmann::json::parse(r.dump());
    EXPECT_EQ(j["test"]["rows"], 42);
    EXPECT_EQ(j["time"]["test"], 1.5);
    EXPECT_EQ(j["test"]["worst_change"], 0.25);
    EXPECT_EQ(j["test"]["least_sum"], 0.875);
    EXPECT_EQ(j["test"]["fewest"], 2);
    EXPECT_EQ(j["test"]["per_side"]["left"], 4);
    EXPECT_EQ(j["test"]["per_side"]["middle"], 5);
    EXPECT_EQ(j["test"]["per_side"]["right"], 6);
    // 5 scalars with keys and one PerPart: 2 top-level objects, test (5 members) and time (1).
    EXPECT_EQ(j.size(), 2u);
    EXPECT_EQ(j["test"].size(), 5u);
    EXPECT_FALSE(r.contains("hidden"));
    // A minimum that saw nothing is +inf, which the report writes as null.
    Report fresh;
    stats::report(fresh, TestStats{});
    EXPECT_TRUE(nlohmann::json::parse(fresh.dump())["test"]["least_sum"].is_null());
    // The integers stay integers in JSON (a u64 above 2^53 would lose digits as a double).
    EXPECT_TRUE(j["test"]["rows"].is_number_unsigned());
}

}  // namespace
}  // namespace ffcube::test
