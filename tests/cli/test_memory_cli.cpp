// Memory at scale: a 20,000-patch run keeps F sparse and its peak resident memory under the bound
// documented in docs/robustness.md, far below the dense N×N matrix.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <algorithm>
#include <cmath>

#include "cli/cli_util.hpp"
#include "cli/rusage_util.hpp"
#include "ffcube/io/ffm.hpp"

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

struct StreamedRun {
    double peak = 0, nnz = 0, bands = 0;
};
StreamedRun streamed_run(const test::TempDir& dir, const std::string& resolution) {
    const std::string tag = "r" + resolution;
    const auto r = test::run_measured({"formfactors", test::example("cube.obj"), "--patches", "4000", "--resolution",
                                       resolution, "--stats-memory", "8", "-q", "-o", dir / (tag + ".ffm"), "--report",
                                       dir / (tag + ".json")},
                                      dir / (tag + ".txt"));
    EXPECT_EQ(r.code, 0) << test::read_text(dir / (tag + ".txt"));
    const auto report = nlohmann::json::parse(test::read_text(dir / (tag + ".json")));
    EXPECT_TRUE(report["streamed"].get<bool>());
    return {1024.0 * static_cast<double>(r.maxrss_kib), report["nnz"].get<double>(),
            report["reciprocity"]["bands"].get<double>()};
}

// Streamed to a .ffm, a run's peak memory does not grow with the number of entries: the same
// scene at 24² and 96² pixels per hemicube face (about 16 times the pixels, several times the
// entries) peaks within a few MiB.
TEST(MemoryCli, StreamedPeakDoesNotGrowWithTheEntries) {
    if (kSanitized) GTEST_SKIP() << "peak memory is meaningless under AddressSanitizer";
    test::TempDir dir;
    const StreamedRun lo = streamed_run(dir, "24"), hi = streamed_run(dir, "96");
    ASSERT_GT(hi.nnz, 2.0 * lo.nnz);
    EXPECT_GT(hi.bands, 1.0);  // the reciprocity check had to work in bands
    // What a streamed run holds that may differ between the two:
    //  - the reciprocity check's band of columns, at most --stats-memory 8 MiB (8 bytes per entry
    //    held), and while they are spilled a 64 KiB buffer per band (a few bands: < 1 MiB);
    //  - the writer's and the reader's block: at most 1 MiB of coded rows plus one row (9 bytes
    //    per entry, at most n = 4000 entries), in at most 4 buffers each (coded, raw, compressed,
    //    decoded): 8 × (1 MiB + 36 KB) < 9 MiB;
    //  - llvmpipe's atlas, 3N × N × 8 bytes: 221 KB at N = 96 per worker.
    // So 8 + 9 + 1 MiB, rounded up to 24 MiB for the allocator's arenas.
    const double growth = 24.0 * 1024 * 1024;
    EXPECT_LT(hi.peak - lo.peak, growth) << "peaks " << lo.peak / 1e6 << " and " << hi.peak / 1e6 << " MB for "
                                         << lo.nnz << " and " << hi.nnz << " entries";
    // The test means something only if holding the entries (12 bytes each in memory: see above)
    // would have broken that bound several times over.
    EXPECT_GT(12.0 * (hi.nnz - lo.nnz), 4.0 * growth);
    // And in absolute terms: the fixed 192 MiB and 1 KiB per patch of the in-memory bound, plus
    // the 18 MiB above, with no term per entry.
    EXPECT_LT(hi.peak, 192.0 * 1024 * 1024 + 1024.0 * 4000 + growth);
}

// --enforce closure streamed out of core keeps that property: at 2000 patches, 12² against 64²
// pixels per face (about twice the entries), with --stats-memory 1, the peaks are within a few MiB.
TEST(MemoryCli, StreamedEnforcePeakDoesNotGrowWithTheEntries) {
    if (kSanitized) GTEST_SKIP() << "peak memory is meaningless under AddressSanitizer";
    test::TempDir dir;
    StreamedRun run[2];
    const char* res[2] = {"12", "64"};
    for (int k = 0; k < 2; ++k) {
        const std::string tag = std::string("e") + res[k];
        const auto r = test::run_measured({"formfactors", test::example("cube.obj"), "--patches", "2000", "--resolution",
                                           res[k], "--stats-memory", "1", "--enforce", "closure", "-q", "-o",
                                           dir / (tag + ".ffm"), "--report", dir / (tag + ".json")},
                                          dir / (tag + ".txt"));
        ASSERT_EQ(r.code, 0) << test::read_text(dir / (tag + ".txt"));
        const auto report = nlohmann::json::parse(test::read_text(dir / (tag + ".json")));
        EXPECT_TRUE(report["streamed"].get<bool>());
        EXPECT_GT(report["enforce"]["scratch_bytes"].get<double>(), 0.0);  // G went to a scratch file
        run[k] = {1024.0 * static_cast<double>(r.maxrss_kib), report["nnz"].get<double>(),
                  report["enforce"]["bands"].get<double>()};
    }
    const StreamedRun &lo = run[0], &hi = run[1];
    ASSERT_GT(hi.nnz, 1.5 * lo.nnz);
    EXPECT_GT(hi.bands, 1.0);
    // What may differ between the two (pipeline/enforcement.hpp, io/transpose_scratch.hpp):
    //  - a band of the transpose, at most --stats-memory 1 MiB (8 bytes per entry), while it is
    //    loaded, and G held in memory up to 1 MiB before it moves to its scratch file: 2 MiB;
    //  - while the bands are spilled, a 64 KiB buffer per band, at most 64 bands open: 4 MiB;
    //    reading G back, a 1 MiB buffer;
    //  - the reader's block (the rows as computed) and the writer's (the enforced rows), at most
    //    9 MiB as above; llvmpipe's atlas at N = 64, 98 KB.
    // So 16.1 MiB, rounded up to 24 MiB for the allocator's arenas.
    const double growth = 24.0 * 1024 * 1024;
    EXPECT_LT(hi.peak - lo.peak, growth) << "peaks " << lo.peak / 1e6 << " and " << hi.peak / 1e6 << " MB for "
                                         << lo.nnz << " and " << hi.nnz << " entries";
    // The test means something only if the in-memory enforcement would have broken the bound: it
    // holds G and the enforced matrix in double at once (12 bytes per entry each, and G has at
    // least F's entries).
    EXPECT_GT(24.0 * (hi.nnz - lo.nnz), growth);
    EXPECT_LT(hi.peak, 192.0 * 1024 * 1024 + 1024.0 * 2000 + growth);
}

// ReciprocityStats::patch_max_abs of a matrix read back, by hand: every entry F_ij with its F_ji
// looked up (0 when absent), |A_i F_ij − A_j F_ji| / ((A_i + A_j) / 2), the largest; no transpose,
// no bands. (Each pair with only F_ji > 0 is looked at from row j.)
double patch_max_abs(const FfmFile& f) {
    double worst = 0.0;
    for (std::uint32_t i = 0; i < f.n; ++i) {
        const RowView r = f.matrix.row(i);
        for (std::size_t k = 0; k < r.col.size(); ++k) {
            const std::uint32_t j = r.col[k];
            const double ai = f.areas[i], aj = f.areas[j];
            worst = std::max(worst, std::abs(ai * r.val[k] - aj * f.matrix.at(j, i)) / (0.5 * (ai + aj)));
        }
    }
    return worst;
}

// The statistics of a run, computed from the stream and by passes over the written file in bands
// (--stats-memory 1) or while the rows come (the default budget), are those of the matrix read
// back from the .ffm, computed here directly from its entries.
TEST(MemoryCli, StatisticsAreThoseOfTheWrittenMatrix) {
    test::TempDir dir;
    const std::string scene = test::example("cube.obj");
    for (const auto& [out, extra] : {std::pair{"s.ffm", "--stats-memory 1"}, std::pair{"l.ffm", ""}}) {
        const auto r = test::run_ffcube(fmt::format("formfactors {} --patches 1500 --resolution 48 -q {} -o {} --report {}.json",
                                                    scene, extra, dir / out, dir / out));
        ASSERT_EQ(r.code, 0) << r.output;
    }
    const auto s = nlohmann::json::parse(test::read_text(dir / "s.ffm.json"));
    const auto l = nlohmann::json::parse(test::read_text(dir / "l.ffm.json"));
    EXPECT_GT(s["reciprocity"]["bands"].get<int>(), 1);  // scratch files, read back one band at a time
    EXPECT_EQ(s["reciprocity"]["passes"].get<int>(), 2);
    EXPECT_EQ(l["reciprocity"]["passes"].get<int>(), 0);  // checked while the rows came
    EXPECT_GT(l["reciprocity"]["in_stream_peak_entries"].get<double>(), 0.0);
    EXPECT_EQ(test::read_text(dir / "s.ffm"), test::read_text(dir / "l.ffm"));  // the budget changes no byte
    const FfmFile f = read_ffm(dir / "s.ffm");
    EXPECT_EQ(f.version, 2u);
    // Row sums in double over the float entries, as RowView::sum adds them: the same bits.
    double lo = 1e300, hi = -1e300, total = 0.0;
    for (std::uint32_t i = 0; i < f.n; ++i) {
        const double sum = f.matrix.row(i).sum();
        lo = std::min(lo, sum), hi = std::max(hi, sum), total += sum;
    }
    const double worst = patch_max_abs(f);
    EXPECT_GT(worst, 0.0);  // hemicube rows are not reciprocal to the last bit: the check is not vacuous
    for (const auto* j : {&s, &l}) {
        EXPECT_EQ((*j)["nnz"].get<double>(), static_cast<double>(f.matrix.nnz()));
        EXPECT_EQ((*j)["row_sums"]["min"].get<double>(), lo);
        EXPECT_EQ((*j)["row_sums"]["max"].get<double>(), hi);
        EXPECT_EQ((*j)["row_sums"]["mean"].get<double>(), total / f.n);
        EXPECT_EQ((*j)["reciprocity"]["patch_max_abs"].get<double>(), worst);
    }
}

// --enforce (each mode, the transpose in several bands and closure's G in a scratch file, forced by
// --stats-memory 1) makes rows with the property asked for, checked on the matrix read back: A_i F_ij
// = A_j F_ji up to the float rounding of each direction, and for closure rows summing to 1 up to
// the same rounding. The default budget (one band, G in memory) and a resumed checkpointed run
// write the same bytes. The scratch directory is gone afterwards, also when closure is refused.
TEST(MemoryCli, EnforcedRowsHaveTheirPropertyInAnyBudget) {
    test::TempDir dir;
    const std::string scene = test::example("cube.obj") + " --patches 700 --resolution 32 -q";
    const auto json = [&](const std::string& name) { return nlohmann::json::parse(test::read_text(dir / name)); };
    // "both" is closure (parse_enforce_mode); a resume is tried on the mode with most passes.
    for (const std::string mode : {"reciprocity", "closure"}) {
        SCOPED_TRACE(mode);
        const std::string e = " --enforce " + mode;
        const bool resume = mode == "closure";
        const std::string ck = resume ? " --checkpoint " + (dir / "ck") : "";
        const auto m = test::run_ffcube(fmt::format("formfactors {}{} -o {} --report {}", scene, e, dir / "m.ffm", dir / "m.json"));
        const auto s = test::run_ffcube(fmt::format("formfactors {}{} --stats-memory 1 -o {} --report {}{}", scene, e,
                                                    dir / "s.ffm", dir / "s.json", ck));
        ASSERT_EQ(m.code, 0) << m.output;
        ASSERT_EQ(s.code, 0) << s.output;
        if (resume) {
            // The checkpoint's log cut to half its records' bytes (a torn record at the end), resumed.
            const std::string log = test::read_text(std::filesystem::path(dir / "ck") / "rows.log");
            test::write_file((std::filesystem::path(dir / "ck") / "rows.log").string(), log.substr(0, log.size() / 2));
            const auto r = test::run_ffcube(
                fmt::format("formfactors {}{} --stats-memory 1 -o {}{} --resume", scene, e, dir / "r.ffm", ck));
            ASSERT_EQ(r.code, 0) << r.output;
        }
        const auto a = json("m.json"), b = json("s.json");
        EXPECT_EQ(a["enforce"]["bands"].get<int>(), 1);
        EXPECT_GT(b["enforce"]["bands"].get<int>(), 1);
        EXPECT_EQ(b["enforce"]["passes"].get<int>(), 2);
        if (mode != "reciprocity") {
            EXPECT_GT(b["enforce"]["iterations"].get<int>(), 0);
            // G (about 2 × nnz entries of 12 bytes) is more than 1 MiB: it went to a scratch file.
            EXPECT_GT(b["enforce"]["scratch_bytes"].get<double>(), 12.0 * b["nnz"].get<double>());
        }
        const std::string mb = test::read_text(dir / "m.ffm");
        EXPECT_TRUE(mb == test::read_text(dir / "s.ffm")) << "the .ffm depends on --stats-memory";
        if (resume) EXPECT_TRUE(mb == test::read_text(dir / "r.ffm")) << "the resumed .ffm differs";
        const FfmFile f = read_ffm(dir / "m.ffm");
        // Reciprocity: G_ij = G_ji is one double, each direction G/A rounded to float (relative
        // error at most 2^-24), so A_i F_ij and A_j F_ji differ by at most 2^-24 of their sum, and
        // the check's measure (divided by the mean area) by at most 2^-23 × max(A F) / mean area.
        double bound = 0.0, area_min = 1e300;
        for (std::uint32_t i = 0; i < f.n; ++i) {
            area_min = std::min(area_min, f.areas[i]);
            const RowView r = f.matrix.row(i);
            for (std::size_t k = 0; k < r.col.size(); ++k) bound = std::max(bound, f.areas[i] * r.val[k]);
        }
        EXPECT_LE(patch_max_abs(f), std::ldexp(bound, -23) / area_min);
        EXPECT_LE(b["reciprocity"]["patch_max_abs"].get<double>(), std::ldexp(bound, -23) / area_min);
        if (mode == "closure") {
            // Closure to 1e-12 in double, then each entry rounded to float (relative 2^-24): a row
            // sum is 1 within 1e-12 + 2^-24 × (its sum, 1) + the double sum's own rounding (far below).
            for (std::uint32_t i = 0; i < f.n; ++i)
                EXPECT_NEAR(f.matrix.row(i).sum(), 1.0, 1e-12 + std::ldexp(1.0, -24)) << "row " << i;
        }
        // Before, the rows were not reciprocal to that bound (the corrected rows of this closed
        // cube already summed to 1 within about 1e-8): the check above is not vacuous.
        EXPECT_GT(b["enforce"]["before"]["reciprocity_max"].get<double>(), 10 * std::ldexp(bound, -23) / area_min);
    }
    // Two squares at 90° are open: closure is refused after the rows were streamed to scratch.
    const auto open = test::run_ffcube(fmt::format("formfactors {} --max-patch-edge 0.5 --resolution 32 -q "
                                                   "--enforce closure --stats-memory 1 -o {}",
                                                   test::example("perpendicular_squares.obj"), dir / "G.ffm"));
    EXPECT_EQ(open.code, 2) << open.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "G.ffm"));
    for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
        EXPECT_NE(entry.path().filename().string().front(), '.') << "left behind: " << entry.path();
}

}  // namespace
}  // namespace ffcube
