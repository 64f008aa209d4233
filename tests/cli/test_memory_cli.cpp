// Memory at scale: a 20,000-patch run keeps F sparse and its peak resident memory under the bound
// documented in docs/robustness.md, far below the dense N×N matrix.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

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

// The streamed run's statistics, computed from the stream and by passes over the written file
// (--stats-memory 1) or while the rows come (the default budget), are the in-memory run's to the
// last bit, and its .ffm holds the in-memory matrix.
TEST(MemoryCli, StreamedStatisticsEqualTheInMemoryOnes) {
    test::TempDir dir;
    const std::string scene = test::example("cube.obj");
    for (const auto& [out, extra] :
         {std::pair{"s.ffm", "--stats-memory 1"}, std::pair{"m.ffm", ""}, std::pair{"l.ffm", ""}}) {
        // m.ffm: the in-memory path (the test hook FFCUBE_TEST_IN_MEMORY).
        const std::string env = std::string(out) == "m.ffm" ? "FFCUBE_TEST_IN_MEMORY=1 " : "";
        const auto r = test::run_ffcube_env(env, fmt::format("formfactors {} --patches 1500 --resolution 48 -q {} -o {} --report {}.json",
                                                    scene, extra, dir / out, dir / out));
        ASSERT_EQ(r.code, 0) << r.output;
    }
    const auto s = nlohmann::json::parse(test::read_text(dir / "s.ffm.json"));
    const auto m = nlohmann::json::parse(test::read_text(dir / "m.ffm.json"));
    EXPECT_TRUE(s["streamed"].get<bool>());
    EXPECT_FALSE(m["streamed"].get<bool>());
    EXPECT_GT(s["reciprocity"]["bands"].get<int>(), 1);  // scratch files, read back one band at a time
    EXPECT_EQ(s["reciprocity"]["passes"].get<int>(), 2);
    for (const char* k : {"min", "max", "mean"}) EXPECT_EQ(s["row_sums"][k], m["row_sums"][k]) << k;
    for (const char* k : {"patch_max_abs", "object_max_rel"}) EXPECT_EQ(s["reciprocity"][k], m["reciprocity"][k]) << k;
    const auto l = nlohmann::json::parse(test::read_text(dir / "l.ffm.json"));
    EXPECT_EQ(l["reciprocity"]["passes"].get<int>(), 0);  // checked while the rows came
    EXPECT_GT(l["reciprocity"]["in_stream_peak_entries"].get<double>(), 0.0);
    EXPECT_GT(m["reciprocity"]["patch_max_abs"].get<double>(), 0.0);
    EXPECT_EQ(l["reciprocity"]["patch_max_abs"], m["reciprocity"]["patch_max_abs"]);
    const FfmFile a = read_ffm(dir / "s.ffm"), b = read_ffm(dir / "m.ffm");
    EXPECT_EQ(a.version, 2u);
    EXPECT_EQ(b.version, 2u);  // the in-memory path writes version 2 too (writing version 1 was retired)
    EXPECT_EQ(test::read_text(dir / "s.ffm"), test::read_text(dir / "m.ffm"));  // the same bytes
    EXPECT_EQ(a.matrix.row_ptr(), b.matrix.row_ptr());
    EXPECT_EQ(a.matrix.col(), b.matrix.col());
    EXPECT_EQ(a.matrix.val(), b.matrix.val());
}

// --enforce with a streamed .ffm (each mode, the transpose in several bands and closure's G in a
// scratch file, forced by --stats-memory 1) writes the very bytes of the in-memory run (forced by
// the test hook FFCUBE_TEST_IN_MEMORY), with the same report figures; a resumed
// checkpointed run too. The scratch directory is gone afterwards, also when closure is refused.
TEST(MemoryCli, StreamedEnforceEqualsTheInMemoryRunByteForByte) {
    test::TempDir dir;
    const std::string scene = test::example("cube.obj") + " --patches 700 --resolution 32 -q";
    const auto json = [&](const std::string& name) { return nlohmann::json::parse(test::read_text(dir / name)); };
    // "both" is closure (parse_enforce_mode); a resume is tried on the mode with most passes.
    for (const std::string mode : {"reciprocity", "closure"}) {
        SCOPED_TRACE(mode);
        const std::string e = " --enforce " + mode;
        const bool resume = mode == "closure";
        const std::string ck = resume ? " --checkpoint " + (dir / "ck") : "";
        const auto m = test::run_ffcube_env("FFCUBE_TEST_IN_MEMORY=1 ",
                                            fmt::format("formfactors {}{} -o {} --report {}", scene, e, dir / "m.ffm",
                                                        dir / "m.json"));
        const auto s = test::run_ffcube(fmt::format("formfactors {}{} --stats-memory 1 -o {} --report {}{}", scene, e,
                                                    dir / "s.ffm", dir / "s.json", ck));
        const auto r = resume ? test::run_ffcube(fmt::format("formfactors {}{} --stats-memory 1 -o {}{} --resume", scene,
                                                             e, dir / "r.ffm", ck))
                              : s;
        ASSERT_EQ(m.code, 0) << m.output;
        ASSERT_EQ(s.code, 0) << s.output;
        ASSERT_EQ(r.code, 0) << r.output;
        const auto a = json("m.json"), b = json("s.json");
        EXPECT_FALSE(a["streamed"].get<bool>());
        EXPECT_TRUE(b["streamed"].get<bool>());
        EXPECT_GT(b["enforce"]["bands"].get<int>(), 1);
        EXPECT_EQ(b["enforce"]["passes"].get<int>(), 2);
        if (mode != "reciprocity") {
            EXPECT_GT(b["enforce"]["iterations"].get<int>(), 0);
            // G (about 2 × nnz entries of 12 bytes) is more than 1 MiB: it went to a scratch file.
            EXPECT_GT(b["enforce"]["scratch_bytes"].get<double>(), 12.0 * b["nnz"].get<double>());
        }
        for (const char* k : {"mode", "iterations", "before", "after"}) EXPECT_EQ(a["enforce"][k], b["enforce"][k]) << k;
        for (const char* k : {"nnz", "row_sums", "reciprocity"}) {
            if (std::string(k) == "reciprocity") {
                for (const char* r2 : {"patch_max_abs", "object_max_rel"})
                    EXPECT_EQ(a[k][r2], b[k][r2]) << r2;
            } else {
                EXPECT_EQ(a[k], b[k]) << k;
            }
        }
        const std::string mb = test::read_text(dir / "m.ffm");
        EXPECT_GT(mb.size(), 0u);
        EXPECT_TRUE(mb == test::read_text(dir / "s.ffm")) << "streamed .ffm differs from the in-memory one";
        if (resume) {
            EXPECT_TRUE(mb == test::read_text(dir / "r.ffm")) << "resumed .ffm differs from the in-memory one";
        }
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
