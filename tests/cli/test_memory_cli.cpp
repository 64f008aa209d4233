// Memory at scale: a 20,000-patch run keeps F sparse and its peak resident memory under the bound
// documented in docs/robustness.md, far below the dense N×N matrix.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli/cli_util.hpp"
#include "cli/rusage_util.hpp"

namespace ffcube {
namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

TEST(MemoryCli, TwentyThousandPatchesStayUnderTheDocumentedBound) {
    // AddressSanitizer's shadow memory and quarantine (256 MB of freed blocks kept mapped) are not
    // ffcube's memory; the bound is for normal builds.
    if (kSanitized) GTEST_SKIP() << "peak memory is meaningless under AddressSanitizer";
    test::TempDir dir;
    const auto r = test::run_measured({"formfactors", test::example("cube.obj"), "--patches", "20000", "--resolution",
                                       "32", "-q", "-o", dir / "F.ffm", "--report", dir / "r.json"},
                                      dir / "log.txt");
    ASSERT_EQ(r.code, 0) << test::read_text(dir / "log.txt");
    const auto report = nlohmann::json::parse(test::read_text(dir / "r.json"));
    const double n = report["patches"].get<double>(), nnz = report["nnz"].get<double>();
    ASSERT_GT(n, 19000.0);
    // The bound of docs/robustness.md:
    //  - 12 bytes per nonzero: the CSR arrays (u32 column + f32 value = 8 bytes) grow by doubling,
    //    and at the last reallocation of the two arrays the old and new copies of one together
    //    with the other's old copy hold at most 1.5 × 8 bytes per final nonzero;
    //  - 1 KiB per patch: the patch and its vertices (about 120 B), the row pointer, the areas and
    //    objects the writer copies, and per-row scratch (generous);
    //  - 192 MiB fixed: libraries, the GL context and llvmpipe (a 6-patch run peaks at about 85 MB).
    const double bound = 12.0 * nnz + 1024.0 * n + 192.0 * 1024 * 1024;
    const double peak = 1024.0 * static_cast<double>(r.maxrss_kib);
    EXPECT_LT(peak, bound) << "peak " << peak / 1e6 << " MB, nnz " << nnz << ", bound " << bound / 1e6 << " MB";
    // The test means something only if a dense matrix (n² floats) would break the bound.
    EXPECT_GT(4.0 * n * n, bound);
    // And F is sparse at all: at 32² a hemicube has 3072 pixels, so a row holds at most 3072
    // entries, far fewer than n.
    EXPECT_LE(nnz, 3072.0 * n);
}

}  // namespace
}  // namespace ffcube
