// One error policy across processes: an error raised inside a hemicube worker reaches the caller
// as the same class whether the workers are forked processes or threads, so main() maps it to
// the same exit code. The errors are raised by the test hook FFCUBE_TEST_WORKER_FAIL, which only
// the worker reads (docs/robustness.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/core/error_transport.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/gl/context.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

struct Caught {
    ErrorKind kind = ErrorKind::other;
    std::string what;
    bool thrown = false;
};

// Computes every row with the hook set to 'fail' (the workers read it when they start) and
// returns what compute_rows threw.
Caught fail_in_worker(const Scene& scene, const std::string& fail, const std::string& expected_workers) {
    ::setenv("FFCUBE_TEST_WORKER_FAIL", fail.c_str(), 1);
    Caught c;
    try {
        HemicubeOptions o;
        o.resolution = 16;
        o.threads = 2;
        HemicubeRowProvider provider(scene, o);
        ::unsetenv("FFCUBE_TEST_WORKER_FAIL");
        EXPECT_EQ(provider.workers(), expected_workers);
        (void)compute_all_rows(provider);
    } catch (const std::exception& e) {
        c = {error_kind(e), e.what(), true};
    }
    ::unsetenv("FFCUBE_TEST_WORKER_FAIL");
    return c;
}

TEST(HemicubeWorkers, ErrorsInsideWorkersKeepTheirClassWithProcessesAndThreads) {
    const Scene scene = test::make_scene(test::inward_box(1, 1, 1), 0.5);
    const std::vector<std::pair<std::string, ErrorKind>> cases = {
        {"input", ErrorKind::input}, {"gl", ErrorKind::gl}, {"io", ErrorKind::io}, {"internal", ErrorKind::internal}};
    std::vector<Caught> by_processes;
    for (const auto& [fail, kind] : cases) by_processes.push_back(fail_in_worker(scene, fail, "processes"));
    // A GL context made in this process makes forking unsafe from now on: threads.
    const auto ctx = create_headless_context(Backend::Auto);
    for (std::size_t k = 0; k < cases.size(); ++k) {
        const Caught t = fail_in_worker(scene, cases[k].first, "threads");
        const Caught& p = by_processes[k];
        ASSERT_TRUE(p.thrown && t.thrown) << cases[k].first;
        EXPECT_EQ(p.kind, cases[k].second) << cases[k].first << ": " << p.what;
        EXPECT_EQ(t.kind, cases[k].second) << cases[k].first << ": " << t.what;
        // The message crosses the socket unchanged (which row failed first depends on the
        // schedule: compare from the hook's name on).
        const auto tail = [](const std::string& s) { return s.substr(std::min(s.size(), s.find("(test hook"))); };
        EXPECT_NE(p.what.find("(test hook FFCUBE_TEST_WORKER_FAIL)"), std::string::npos) << p.what;
        EXPECT_EQ(tail(p.what), tail(t.what));
    }
    // Without the hook, the same provider computes rows.
    HemicubeOptions o;
    o.resolution = 16;
    HemicubeRowProvider provider(scene, o);
    EXPECT_EQ(compute_all_rows(provider).rows_filled(), scene.size());
}

TEST(ErrorTransport, EveryClassComesBackAsItself) {
    const auto round_trip = [](const std::exception& e) {
        try {
            throw_error(error_kind(e), e.what());
        } catch (const std::exception& back) {
            EXPECT_EQ(error_kind(back), error_kind(e));
            return std::string(back.what());
        }
        return std::string();
    };
    EXPECT_EQ(round_trip(InputError("in")), "in");
    EXPECT_EQ(round_trip(IoError("io")), "io");
    EXPECT_EQ(round_trip(GlError("gl")), "gl");
    EXPECT_EQ(round_trip(InternalError("bug")), "bug");
    EXPECT_EQ(round_trip(std::runtime_error("other")), "other");
    EXPECT_THROW(throw_error(ErrorKind::out_of_memory, ""), std::bad_alloc);
    EXPECT_THROW(throw_error(static_cast<ErrorKind>(99), "garbled"), InternalError);
}

}  // namespace
}  // namespace ffcube
